"""CAN protocol and drivers: the only part of the harness that knows CAN.

The drivers import nothing from :mod:`harness` (``tests/unit/test_architecture.py`` checks it);
they take plain arguments, as ``can.Bus`` does, and the harness adapts its profile to them.

- ``rig.dbc``: the protocol, one source of truth (messages, scales, ranges, value tables, E2E Data-IDs, version).
- ``rig_fd.dbc``: its CAN FD variant (``can.fd``): the same messages as FD frames, plus SENSOR_SET.
- :mod:`drivers.protocol_values`: the protocol version and the DBC's value tables as IntEnums (drive state, ...).
- :mod:`drivers.errors`: :class:`~drivers.errors.DriverError` and its ProtocolError, BusError, BusLoadError.
- :mod:`drivers.e2e`: CRC-8/2F and rolling counter (AUTOSAR E2E profile-2 style).
- :mod:`drivers.codec`: the DBC compiled into fast SI encoders/decoders (:func:`~drivers.codec.load_protocol`).
- :mod:`drivers.decoder`: the never-raising, counting :class:`~drivers.decoder.Decoder`.
- :mod:`drivers.measurements`: :class:`~drivers.measurements.Measurements`, the decoded control sample.
- :mod:`drivers.busload`: worst-case bus load and the refusal above the allowed share.
- :mod:`drivers.bus`: :func:`~drivers.bus.open_bus` for any python-can interface; error-frame and send-failure accounting.
- :mod:`drivers.reader` / :mod:`drivers.writer`: the harness's poll-in-the-tick reader; preallocated-frame writers, both sides.
- :mod:`drivers.rig_reader`: the rig's reader, one frame at a time (every command frame is an event).
- :mod:`drivers.link`: one call to a checked, open link with its reader and writer.
- :mod:`drivers.seqpacket`: the ``seqpacket`` python-can interface (Unix SOCK_SEQPACKET hub): channel, wire format, bus.

Importing this package stays cheap (the harness imports :mod:`drivers.errors` everywhere):
python-can is not imported here. python-can finds the ``seqpacket`` interface through the
installed entry point; :func:`drivers.bus.open_bus` registers it before opening one where the
entry point is not installed (:mod:`drivers.seqpacket` says how).
"""
