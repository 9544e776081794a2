"""CAN protocol and drivers: the only part of the harness that knows CAN.

The drivers import nothing from :mod:`harness` (``tests/unit/test_architecture.py`` checks it);
they take plain arguments, as ``can.Bus`` does, and the harness adapts its profile to them.

Three parts, each importing only those above it (the architecture test checks that too):

- :mod:`drivers.protocol`: the CAN protocol, whatever carries it: the DBC files (``rig.dbc``, its CAN FD
  variant ``rig_fd.dbc``), the codec, E2E protection, the decoder and its compiled kernels, the frame
  encodings (flags, one frame in one datagram), the protocol's value tables and the bus load.
- :mod:`drivers.transports`: what carries the frames: :func:`~drivers.transports.bus.open_bus` for any
  python-can interface with its health accounting, the ``seqpacket`` interface, and the datagram path
  (:class:`~drivers.transports.datagram_path.DatagramPath`), the capability a bus offers when it can
  take and hand over frames without a :class:`can.Message`.
- The roles, here, on any :class:`can.BusABC`:

  - :mod:`drivers.reader` / :mod:`drivers.writer`: the harness's poll-in-the-tick reader; preallocated-frame
    writers, both sides (the datagram path where the bus offers it).
  - :mod:`drivers.rig_reader`: the rig's reader, one frame at a time (every command frame is an event).
  - :mod:`drivers.measurements`: :class:`~drivers.measurements.Measurements`, the decoded control sample
    the harness's reader fills.
  - :mod:`drivers.link`: one call from plain settings to a checked, open link with its reader and writer.

- :mod:`drivers.errors`: :class:`~drivers.errors.DriverError` and its ProtocolError, BusError, BusLoadError
  (every part raises them).

Importing this package stays cheap (the harness imports :mod:`drivers.errors` everywhere):
python-can is not imported here, nor by :mod:`drivers.protocol` or :mod:`drivers.transports` themselves.
python-can finds the ``seqpacket`` interface through the installed entry point;
:func:`drivers.transports.bus.open_bus` registers it before opening one where the entry point is not
installed (:mod:`drivers.transports.seqpacket` says how).
"""
