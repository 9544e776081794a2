"""The rig's CAN protocol, whatever bus carries it: what the frames mean and how they are checked.

- ``rig.dbc``: the protocol, one source of truth (messages, scales, ranges, value tables, E2E Data-IDs,
  version); ``PROTOCOL.md`` is its reading aid.
- ``rig_fd.dbc``: its CAN FD variant (``can.fd``): the same messages as FD frames, plus SENSOR_SET.
- :mod:`.protocol_values`: the protocol version and the DBC's value tables as IntEnums (drive state, ...).
- :mod:`.e2e`: CRC-8/2F and rolling counter (AUTOSAR E2E profile-2 style).
- :mod:`.codec`: the DBC compiled into fast SI encoders/decoders (:func:`~drivers.protocol.codec.load_protocol`).
- :mod:`.decoder`: the never-raising, counting :class:`~drivers.protocol.decoder.Decoder`.
- :mod:`.frame_kernel`: the decoder's checks and decoding, compiled (one frame, or a poll's datagrams).
- :mod:`.frame_flags`: a frame's kind in one small integer; :mod:`.datagram`: one frame in one datagram.
- :mod:`.busload`: worst-case bus load and the refusal above the allowed share.

Nothing here opens a bus or imports :mod:`drivers.transports`; importing the package imports nothing.
"""
