"""The ``seqpacket`` python-can interface: a CAN bus between the processes of one host, over Unix sockets.

- :mod:`.channel`: a channel name (``harness``, ``@harness``, a socket path) and the address its hub listens on.
- :mod:`.peers`: who may join a channel (the peer's kernel credentials).
- :mod:`.bus`: :class:`~drivers.transports.seqpacket.bus.SeqPacketBus`, the python-can bus: hub, peers, relay;
  it offers the datagram path (:class:`~drivers.transports.datagram_path.DatagramPath`).

Its wire is :mod:`drivers.protocol.datagram`: one datagram per frame (header, then the data).

How python-can finds it
-----------------------
``import can`` reads the ``can.interface`` entry points once, into
``can.interfaces.BACKENDS`` (name -> module and class) and the frozen
``VALID_INTERFACES``; ``can.Bus(interface=...)`` refuses a name outside the second and
imports the class the first names. This project declares the entry point
(``pyproject.toml``: ``seqpacket = "drivers.transports.seqpacket:SeqPacketBus"``), so an installed
checkout needs nothing more; the entry point names this package, as python-can's own
backends name theirs (``can.interfaces.socketcan``), so the bus class is importable from here.

Where the entry point is not installed (a checkout on ``PYTHONPATH`` only), :func:`register`
adds the interface to those two tables: :func:`drivers.transports.bus.open_bus` calls it before it opens
a ``seqpacket`` bus, the one call besides the entry point. Importing the package registers
nothing.
"""

import can

from drivers.transports.seqpacket.bus import SeqPacketBus

#: python-can interface name.
INTERFACE = "seqpacket"


def register() -> None:
    """Make ``can.Bus(interface="seqpacket")`` work without the installed entry point.

    Adds the interface to ``can.interfaces.BACKENDS``. python-can checks names against
    ``VALID_INTERFACES``, a frozenset built at import and imported by value into
    ``can.util`` and ``can``, so those three module attributes are rebound to a set
    with the name added. A no-op when the entry point already registered it.
    """
    can.interfaces.BACKENDS.setdefault(INTERFACE, (__name__, SeqPacketBus.__name__))
    valid = can.interfaces.VALID_INTERFACES
    if INTERFACE in valid:
        return
    widened = frozenset(valid | {INTERFACE})
    for module in (can.interfaces, can.util, can):
        if getattr(module, "VALID_INTERFACES", None) is valid:
            module.VALID_INTERFACES = widened  # type: ignore[attr-defined]


__all__ = ["INTERFACE", "SeqPacketBus", "register"]
