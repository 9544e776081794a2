"""Worst-case CAN bus load from the DBC, the configured rates and the bitrate.

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
The load is ``sum(rate_i * bits_i) / bitrate``. Worst-case stuffing makes this an
upper bound; error frames and retransmissions come on top, which is one reason to
keep the configured share (default 50 %) well below 1.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from drivers.codec import Protocol
from drivers.errors import BusLoadError, ProtocolError

STUFFABLE_HEADER_BITS_STD = 34
STUFFABLE_HEADER_BITS_EXT = 54
UNSTUFFED_TRAILER_BITS = 13


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
class BusLoad:
    """Result of a bus-load computation.

    Attributes
    ----------
    bitrate_bps : int
        The bitrate (bit/s).
    bits_per_s : dict of str to float
        Worst-case bits per second each message needs.
    """

    bitrate_bps: int
    bits_per_s: Mapping[str, float]

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
        parts = [f"{name} {bits / self.bitrate_bps:.1%}" for name, bits in rows]
        return f"{self.share:.1%} of {self.bitrate_bps} bit/s (" + ", ".join(parts) + ")"


def bus_load(protocol: Protocol, rates_hz: Mapping[str, float], bitrate_bps: int) -> BusLoad:
    """Worst-case load of the protocol's messages at the given rates.

    Parameters
    ----------
    protocol : Protocol
        The compiled DBC.
    rates_hz : mapping of str to float
        Rate of every message of the DBC (Hz); 0 for a message that is never sent.
    bitrate_bps : int
        Bitrate (bit/s).

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
    bits = {name: float(rates_hz[name]) * frame_bits(codec.length) for name, codec in protocol.messages.items()}
    return BusLoad(int(bitrate_bps), bits)


def check_bus_load(
    protocol: Protocol, rates_hz: Mapping[str, float], bitrate_bps: int, max_share: float = 0.5
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
    load = bus_load(protocol, rates_hz, bitrate_bps)
    if load.share > max_share:
        raise BusLoadError(
            f"bus load {load.share:.1%} exceeds the allowed {max_share:.1%}: "
            f"{load.describe()}; lower the rates or raise can.bitrate_bps"
        )
    return load
