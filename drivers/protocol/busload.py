"""Worst-case CAN bus load from the DBC, the configured rates and the bitrate(s), classic CAN or CAN FD.

Frame length on the wire, classic CAN, worst-case bit stuffing (Davis, Burns,
Bril & Lukkien, "Controller Area Network (CAN) schedulability analysis: refuted,
revisited and revised", Real-Time Systems 35, 2007, Eq. 3)::

    bits(s) = g + 8 s + 13 + floor((g + 8 s - 1) / 4)

- ``s``: data bytes (DLC, 0..8);
- ``g``: bits exposed to stuffing outside the data field: 34 for an 11-bit ID
  (SOF 1, ID 11, RTR 1, IDE 1, r0 1, DLC 4, CRC 15), 54 for a 29-bit ID;
- 13: CRC delimiter 1, ACK slot and delimiter 2, end of frame 7, interframe space 3
  (never stuffed);
- ``floor((g + 8 s - 1) / 4)``: at most one stuff bit per 4 bits after the first 5.

An 8-byte standard frame is 135 bits: 135 us at 1 Mbit/s ("about 130 us").

CAN FD frames (:func:`fd_frame_bits`, the FD base frame format of ISO 11898-1:2015, 11-bit ID)
have two phases. With bit-rate switching the data phase runs at the data bit rate from the
sample point of BRS to the sample point of the CRC delimiter; everything else runs at the
nominal rate. Worst case, per phase::

    nominal bits = A + floor((A - 1) / 4) + 13
    data bits    = 5 + 8 s + (floor((A + 5 + 8 s - 1) / 4) - floor((A - 1) / 4))
                   + (4 + c) + ceil((4 + c) / 4)

- ``A``: arbitration-phase bits, 17 (SOF 1, ID 11, RRS 1, IDE 1, FDF 1, res 1, BRS 1);
- 13: CRC delimiter 1 (counted at the nominal rate, the conservative side), ACK slot and
  delimiter 2, end of frame 7, interframe space 3, never stuffed;
- 5: ESI 1, DLC 4; ``s`` data bytes (0..8, 12, 16, 20, 24, 32, 48, 64);
- dynamic stuff bits from SOF to the end of the data field, at most one per 4 bits after the
  first 5, as in classic CAN: ``floor((A + 5 + 8 s - 1) / 4)`` in all, of which at most
  ``floor((A - 1) / 4)`` (4) fall in the arbitration phase; counting as many there as can be
  puts them at the slower rate, which keeps the total an upper bound;
- the CRC field: the stuff count (3 bits Gray-coded count modulo 8 and a parity bit, 4) and
  the CRC sequence ``c`` (17 bits for up to 16 data bytes, 21 above), with fixed stuff bits
  (not dynamic ones): one before the field and one after every 4 bits of it,
  ``ceil((4 + c) / 4)`` (6 for CRC-17, 7 for CRC-21).

The frame's time is ``nominal bits / nominal rate + data bits / data rate`` (both at the nominal
rate without bit-rate switching). A 32-byte FD frame is 34 nominal and 358 data bits: 105.6 us
at 1 and 5 Mbit/s, where four classic 8-byte frames take 540 us.

The load is ``sum(rate_i * time_i)``, the busy share of each second, reported as bits at the
nominal rate (``time_i * bitrate``) so a classic load reads ``sum(rate_i * bits_i) / bitrate``.
Worst-case stuffing makes this an upper bound; error frames and retransmissions come on top,
which is one reason to keep the configured share (default 50 %) well below 1.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from drivers.errors import BusLoadError, ProtocolError
from drivers.protocol.codec import FD_LENGTHS, MessageCodec, Protocol

STUFFABLE_HEADER_BITS_STD = 34
STUFFABLE_HEADER_BITS_EXT = 54
UNSTUFFED_TRAILER_BITS = 13
#: FD base frame, arbitration phase: SOF 1, ID 11, RRS 1, IDE 1, FDF 1, res 1, BRS 1.
FD_ARBITRATION_BITS = 17
#: FD data phase before the data field: ESI 1, DLC 4.
FD_CONTROL_BITS = 5
#: The CRC field's stuff count: 3 bits Gray-coded, 1 parity bit.
FD_STUFF_COUNT_BITS = 4
#: Data bytes up to which an FD frame carries CRC-17 (CRC-21 above).
FD_CRC17_MAX_BYTES = 16


def frame_bits(dlc: int, extended_id: bool = False) -> int:
    """Worst-case length of one classic CAN data frame on the wire, interframe space included (bits).

    Parameters
    ----------
    dlc : int
        Data bytes, 0..8.
    extended_id : bool
        29-bit identifier instead of 11-bit.
    """
    if not 0 <= dlc <= 8:
        raise ValueError(f"DLC {dlc} is outside 0..8 for classic CAN")
    g = STUFFABLE_HEADER_BITS_EXT if extended_id else STUFFABLE_HEADER_BITS_STD
    return g + 8 * dlc + UNSTUFFED_TRAILER_BITS + (g + 8 * dlc - 1) // 4


@dataclass(frozen=True)
class FdFrameBits:
    """Worst-case length of one CAN FD frame, per phase (bits).

    Attributes
    ----------
    nominal : int
        Bits at the nominal bit rate (arbitration phase, CRC delimiter, ACK, EOF, interframe space).
    data : int
        Bits of the data phase (ESI, DLC, data, stuff bits, CRC field), at the data bit rate when
        the frame switches bit rate and at the nominal rate otherwise.
    """

    nominal: int
    data: int

    def time_s(self, nominal_bps: float, data_bps: float) -> float:
        """Time on the wire (s) at ``nominal_bps`` and ``data_bps`` (bit/s)."""
        return self.nominal / nominal_bps + self.data / data_bps


def fd_frame_bits(length: int) -> FdFrameBits:
    """Worst-case bits of one CAN FD base-format data frame (11-bit ID), interframe space included.

    Parameters
    ----------
    length : int
        Data bytes: 0..8, 12, 16, 20, 24, 32, 48 or 64.

    Returns
    -------
    FdFrameBits
        The module docstring's formula (ISO 11898-1:2015 FD base frame format).
    """
    if length not in FD_LENGTHS:
        raise ValueError(f"{length} data bytes is not a CAN FD frame length; expected one of {sorted(FD_LENGTHS)}")
    arbitration = FD_ARBITRATION_BITS
    arbitration_stuff = (arbitration - 1) // 4
    dynamic_stuff = (arbitration + FD_CONTROL_BITS + 8 * length - 1) // 4
    crc_field = FD_STUFF_COUNT_BITS + (17 if length <= FD_CRC17_MAX_BYTES else 21)
    fixed_stuff = -(-crc_field // 4)
    nominal = arbitration + arbitration_stuff + UNSTUFFED_TRAILER_BITS
    data = FD_CONTROL_BITS + 8 * length + (dynamic_stuff - arbitration_stuff) + crc_field + fixed_stuff
    return FdFrameBits(nominal, data)


def frame_time_s(codec: MessageCodec, bitrate_bps: float, data_bitrate_bps: float | None = None) -> float:
    """Worst-case time one frame of ``codec``'s message occupies the bus (s).

    Parameters
    ----------
    codec : MessageCodec
        The message (classic or FD, with or without bit-rate switching, as its DBC says).
    bitrate_bps : float
        Nominal bit rate (bit/s).
    data_bitrate_bps : float, optional
        Data-phase bit rate of FD frames that switch (bit/s); default the nominal rate.
    """
    if not codec.is_fd:
        return frame_bits(codec.length) / bitrate_bps
    data_bps = data_bitrate_bps if codec.bitrate_switch and data_bitrate_bps else bitrate_bps
    return fd_frame_bits(codec.length).time_s(bitrate_bps, data_bps)


@dataclass(frozen=True)
class BusLoad:
    """Result of a bus-load computation.

    Attributes
    ----------
    bitrate_bps : int
        The (nominal) bitrate (bit/s).
    bits_per_s : dict of str to float
        Worst-case bus time each message needs per second, in bit times at the nominal rate.
    data_bitrate_bps : int
        The data-phase bitrate of CAN FD frames (bit/s); 0 for a classic protocol.
    """

    bitrate_bps: int
    bits_per_s: Mapping[str, float]
    data_bitrate_bps: int = 0

    @property
    def total_bits_per_s(self) -> float:
        """All messages together (bit/s)."""
        return float(sum(self.bits_per_s.values()))

    @property
    def share(self) -> float:
        """Fraction of the bitrate used, 0..(more than 1 when overloaded)."""
        return self.total_bits_per_s / self.bitrate_bps

    def describe(self) -> str:
        """One line per message, biggest first, then the total (for the CLI and error messages)."""
        rows = sorted(self.bits_per_s.items(), key=lambda item: -item[1])
        parts = [f"{name} {bits / self.bitrate_bps:.1%}" for name, bits in rows if bits > 0.0]
        rate = f"{self.bitrate_bps} bit/s"
        if self.data_bitrate_bps:
            rate = f"CAN FD at {self.bitrate_bps} bit/s nominal, {self.data_bitrate_bps} bit/s data"
        return f"{self.share:.1%} of {rate} (" + ", ".join(parts) + ")"


def bus_load(
    protocol: Protocol, rates_hz: Mapping[str, float], bitrate_bps: int, data_bitrate_bps: int | None = None,
) -> BusLoad:
    """Worst-case load of the protocol's messages at the given rates.

    Parameters
    ----------
    protocol : Protocol
        The compiled DBC (classic or CAN FD).
    rates_hz : mapping of str to float
        Rate of every message of the DBC (Hz); 0 for a message that is never sent.
    bitrate_bps : int
        (Nominal) bitrate (bit/s).
    data_bitrate_bps : int, optional
        Data-phase bitrate of the FD frames that switch (bit/s); default the nominal rate.

    Raises
    ------
    ProtocolError
        If a message of the DBC has no rate, or a rate names a message the DBC lacks.
    """
    missing = [name for name in protocol.messages if name not in rates_hz]
    if missing:
        raise ProtocolError(f"no rate configured for message {missing[0]} of {protocol.path.name}")
    unknown = [name for name in rates_hz if name not in protocol.messages]
    if unknown:
        raise ProtocolError(f"a rate is configured for {unknown[0]}, which {protocol.path.name} does not define")
    bits = {
        name: float(rates_hz[name]) * frame_time_s(codec, bitrate_bps, data_bitrate_bps) * bitrate_bps
        for name, codec in protocol.messages.items()
    }
    data_bps = int(data_bitrate_bps or bitrate_bps) if protocol.fd else 0
    return BusLoad(int(bitrate_bps), bits, data_bps)


def check_bus_load(
    protocol: Protocol, rates_hz: Mapping[str, float], bitrate_bps: int, max_share: float = 0.5,
    data_bitrate_bps: int | None = None,
) -> BusLoad:
    """Compute the load of the given rates and refuse it when above ``max_share`` of the bitrate.

    Call it before opening the bus, so nothing is sent with a refused configuration.

    Parameters
    ----------
    protocol : Protocol
        The compiled DBC.
    rates_hz : mapping of str to float
        Rate of every message of the DBC (Hz), as for :func:`bus_load`.
    bitrate_bps : int
        Bitrate (bit/s).
    max_share : float
        Largest allowed share of the bitrate (0..1).
    data_bitrate_bps : int, optional
        Data-phase bitrate of CAN FD frames (bit/s), as for :func:`bus_load`.

    Returns
    -------
    BusLoad
        The accepted load (for display and logging).

    Raises
    ------
    BusLoadError
        With the computed share, the allowed share and the per-message breakdown.
    ProtocolError
        From :func:`bus_load`.
    """
    load = bus_load(protocol, rates_hz, bitrate_bps, data_bitrate_bps)
    if load.share > max_share:
        raise BusLoadError(
            f"bus load {load.share:.1%} exceeds the allowed {max_share:.1%}: "
            f"{load.describe()}; lower the rates or raise can.bitrate_bps"
        )
    return load
