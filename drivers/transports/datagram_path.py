"""The datagram path: a capability a python-can bus may offer besides :class:`can.BusABC`.

The generic reader and writer (:class:`drivers.reader.FrameReader`, :class:`drivers.writer.FrameWriter`)
talk to any :class:`can.BusABC` through ``recv`` and ``send``, one :class:`can.Message` per frame. A
backend that can also take and hand over frames as raw datagrams, in the layout of
:mod:`drivers.protocol.datagram` (header, then the data), says so by implementing
:class:`DatagramPath`; the reader then decodes a poll's frames without building a Message (with one
peer, straight off the backend's socket in one compiled call), and the writer sends each frame's
preallocated datagram. The frames, their order and their bytes are the same on either path.

The capability is structural (a :class:`typing.Protocol`, checkable at run time): a backend needs
no base class of this project, only the members, and python-can knows nothing of it, as it knows
nothing of a backend's other extras. :func:`datagram_path` asks once, when the reader or writer is
made; what may change while the bus is open (:attr:`DatagramPath.raw_receive_ok`,
:attr:`DatagramPath.direct_fd`) is read on every poll. The ``seqpacket`` interface offers it
(:class:`drivers.transports.seqpacket.bus.SeqPacketBus`); python-can's own backends do not.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import can


@runtime_checkable
class DatagramPath(Protocol):
    """A bus that takes and hands over frames as datagrams of :mod:`drivers.protocol.datagram`.

    Attributes
    ----------
    channel : str
        The channel the bus is open on: the ``channel`` of the frames received on this path.
    """

    channel: str

    @property
    def raw_receive_ok(self) -> bool:
        """True when :meth:`recv_datagram` hands over every frame ``recv`` would (no filters, no local echo).

        Read before every poll: the reader takes the datagram path only while it holds.
        """
        ...

    @property
    def direct_fd(self) -> int:
        """The descriptor of the one socket whose datagrams may be read straight off it, else -1.

        When it is not -1 the reader drains it itself (:meth:`drivers.protocol.decoder.Decoder.receive_datagrams`)
        and then calls :meth:`note_direct_receive`; otherwise it takes the datagrams through
        :meth:`recv_datagram`.
        """
        ...

    def note_direct_receive(self, malformed: int) -> None:
        """Account a drain of :attr:`direct_fd` made by the reader.

        Parameters
        ----------
        malformed : int
            Datagrams of that drain that were not a frame (wrong size), skipped.
        """
        ...

    def recv_datagram(self, into: memoryview | bytearray | None = None) -> int:
        """Take the next waiting frame's datagram into ``into``, without blocking.

        Parameters
        ----------
        into : writable bytes-like, optional
            At least :data:`drivers.protocol.datagram.MAX_DATAGRAM_BYTES` + 1 bytes; default the bus's own buffer.

        Returns
        -------
        int
            The datagram's size in bytes; 0 when no frame waits.

        Raises
        ------
        can.CanOperationError
            The bus is shut down.
        """
        ...

    def send_datagram(self, frame: bytes | bytearray | memoryview) -> None:
        """Send one frame already in the datagram layout, without blocking.

        Parameters
        ----------
        frame : bytes-like
            :data:`drivers.protocol.datagram.HEADER` then the data.

        Raises
        ------
        can.CanOperationError
            The bus did not take the frame (a full transmit buffer: ``error_code`` ``ENOBUFS``), or it is shut down.
        """
        ...


def datagram_path(bus: can.BusABC) -> DatagramPath | None:
    """The bus itself when it offers the datagram path, else None.

    Parameters
    ----------
    bus : can.BusABC
        An open bus.

    Returns
    -------
    DatagramPath or None
        ``bus``, typed as the capability, when it implements every member of :class:`DatagramPath`;
        None for a bus that offers only python-can's ``recv`` and ``send``.
    """
    return bus if isinstance(bus, DatagramPath) else None
