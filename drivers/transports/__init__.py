"""What carries the frames: python-can buses, the ``seqpacket`` interface, and the datagram path.

- :mod:`.bus`: :func:`~drivers.transports.bus.open_bus` for any python-can interface; error-frame and
  send-failure accounting (:class:`~drivers.transports.bus.BusHealth`).
- :mod:`.datagram_path`: :class:`~drivers.transports.datagram_path.DatagramPath`, the capability a bus
  offers when it takes and hands over frames as datagrams (:mod:`drivers.protocol.datagram`) besides
  python-can's ``send`` and ``recv``; the reader and writer ask for it with
  :func:`~drivers.transports.datagram_path.datagram_path`.
- :mod:`.seqpacket`: the ``seqpacket`` python-can interface (Unix SOCK_SEQPACKET hub): channel, peers, bus;
  it offers the datagram path.

The transports know frames (:mod:`drivers.protocol`'s frame encodings), not the roles that send and
read them. Importing the package imports nothing (python-can finds ``seqpacket`` through its entry point,
``drivers.transports.seqpacket:SeqPacketBus``).
"""
