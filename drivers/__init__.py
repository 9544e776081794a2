"""CAN protocol and drivers: the only part of the harness that knows CAN.

- ``rig.dbc``: the protocol, one source of truth (messages, scales, ranges, E2E Data-IDs, version).
- :mod:`drivers.e2e`: CRC-8/2F and rolling counter (AUTOSAR E2E profile-2 style).
- :mod:`drivers.codec`: the DBC compiled into fast SI encoders/decoders (:func:`~drivers.codec.load_protocol`).
- :mod:`drivers.decoder`: the never-raising, counting :class:`~drivers.decoder.Decoder`.
- :mod:`drivers.config`: :class:`~drivers.config.CanConfig`, the profile's ``can`` section.
- :mod:`drivers.busload`: worst-case bus load and the refusal above the allowed share.
- :mod:`drivers.bus`: :func:`~drivers.bus.open_bus` for any python-can interface; error-frame and send-failure accounting.
- :mod:`drivers.reader` / :mod:`drivers.writer`: poll-in-the-tick readers and preallocated-frame writers, harness and rig side.
"""

from drivers.seqpacket import register as _register_seqpacket

_register_seqpacket()  # can.Bus(interface="seqpacket") works before the entry point is installed
