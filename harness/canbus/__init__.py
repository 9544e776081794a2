"""The harness's side of CAN: the profile's ``can`` section and the drivers opened with it.

- :mod:`.config`: :class:`~harness.canbus.config.CanConfig`, the ``can:`` section (interface,
  channel, bitrate, protocol version, every message's rate).
- :mod:`.link`: that section handed to :mod:`drivers.link` as plain arguments: a checked,
  open link for the harness or the rig.

Named ``canbus``, not ``can``: ``harness.can`` would read like python-can's ``can``. The
package imports nothing at import, so the profile takes :mod:`.config` without the drivers.
"""
