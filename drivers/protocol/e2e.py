"""End-to-end protection: AUTOSAR E2E profile-2 style CRC-8/2F and the 4-bit rolling counter.

Frame layout shared by every message of ``drivers/protocol/rig.dbc``:

- byte 0: CRC-8/2F (polynomial 0x2F, the SAE J1850 polynomial variant AUTOSAR calls
  ``Crc8H2F``; init 0xFF, final xor 0xFF, not reflected; check value 0xDF over ``b"123456789"``);
- bits 8-11 (low nibble of byte 1): the rolling counter 0..15.

The same layout protects the CAN FD messages of ``drivers/protocol/rig_fd.dbc``, the 32-byte
SENSOR_SET included: nothing here depends on the length (the CRC covers the whole payload).

The CRC covers bytes 1..DLC-1 followed by one Data-ID byte, picked from the
message's 16-entry Data-ID list by the counter (profile 2). A frame routed to the
wrong message, or one whose counter nibble was corrupted, therefore fails the CRC
even if its bytes happen to be self-consistent.

The receiver keeps the counter of each message (:mod:`drivers.protocol.frame_kernel` checks every
received frame): the first frame after a reset is accepted (nothing to compare with), then
the counter must advance by exactly one (mod 16). A repeated counter is rejected and the
state is kept; a skipped counter (frames lost or injected) is rejected and the state
resynchronises to it, so the next consecutive frame is accepted again.
"""

from __future__ import annotations

from collections.abc import Sequence

CRC8_2F_POLY = 0x2F
CRC8_2F_INIT = 0xFF
CRC8_2F_XOROUT = 0xFF
COUNTER_MODULO = 16


def _make_table(poly: int) -> tuple[int, ...]:
    table = []
    for byte in range(256):
        crc = byte
        for _ in range(8):
            crc = ((crc << 1) ^ poly) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
        table.append(crc)
    return tuple(table)


_TABLE: tuple[int, ...] = _make_table(CRC8_2F_POLY)


def crc_table() -> tuple[int, ...]:
    """The CRC-8/2F lookup table (256 entries), for the compiled receive side (:mod:`drivers.protocol.frame_kernel`)."""
    return _TABLE


def crc8_2f(data: bytes | bytearray | memoryview, start: int = 0, stop: int | None = None) -> int:
    """CRC-8/2F (AUTOSAR ``Crc8H2F``) of ``data[start:stop]``, without copying.

    Parameters
    ----------
    data : bytes-like
        The bytes.
    start, stop : int
        The range to cover (``stop=None`` means the end).

    Returns
    -------
    int
        The CRC, 0..255.
    """
    table = _TABLE
    crc = CRC8_2F_INIT
    end = len(data) if stop is None else stop
    for index in range(start, end):
        crc = table[crc ^ data[index]]
    return crc ^ CRC8_2F_XOROUT


def profile2_crc(data: bytes | bytearray | memoryview, length: int, data_ids: Sequence[int]) -> int:
    """The profile-2 CRC of a frame: bytes 1..length-1, then the counter's Data-ID.

    Parameters
    ----------
    data : bytes-like
        The frame payload (at least ``length`` bytes; byte 0 is ignored).
    length : int
        Number of payload bytes the CRC protects (the DLC), at least 2.
    data_ids : sequence of int
        The message's 16 Data-IDs.
    """
    table = _TABLE
    crc = CRC8_2F_INIT
    for index in range(1, length):
        crc = table[crc ^ data[index]]
    crc = table[crc ^ data_ids[data[1] & 0x0F]]
    return crc ^ CRC8_2F_XOROUT


def protect(data: bytearray | memoryview, counter: int, data_ids: Sequence[int]) -> None:
    """Write ``counter`` into bits 8-11 and the CRC into byte 0 of ``data``, in place.

    Parameters
    ----------
    data : bytearray
        The payload with every signal already packed (byte 0 and the counter nibble are overwritten).
    counter : int
        Rolling counter 0..15.
    data_ids : sequence of int
        The message's 16 Data-IDs.
    """
    data[1] = (data[1] & 0xF0) | (counter & 0x0F)
    data[0] = profile2_crc(data, len(data), data_ids)


def parse_data_ids(text: str, message: str) -> tuple[int, ...]:
    """Parse a DBC ``E2EDataIDs`` attribute: 16 integers 0..255 separated by spaces or commas.

    Raises
    ------
    ValueError
        If there are not exactly 16 values in 0..255 (the caller wraps it in ProtocolError).
    """
    parts = text.replace(",", " ").split()
    try:
        values = tuple(int(part, 0) for part in parts)
    except ValueError as err:
        raise ValueError(f"{message}: E2EDataIDs {text!r} is not a list of integers") from err
    if len(values) != COUNTER_MODULO:
        raise ValueError(f"{message}: E2EDataIDs has {len(values)} values instead of {COUNTER_MODULO}")
    bad = [v for v in values if not 0 <= v <= 255]
    if bad:
        raise ValueError(f"{message}: E2EDataIDs value {bad[0]} is outside 0..255")
    return values

