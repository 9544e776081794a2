"""The drivers' error tree: what the CAN layer raises on purpose.

Every error derives from :class:`DriverError` and from the builtin that fits it
(python-control's habit), so a caller may catch either: ``except BusError`` or
``except OSError`` alike. Messages say what was expected and what was found, as
cantools' do ("Wrong data size: 6 instead of 8 bytes").

The drivers import nothing from :mod:`harness`, so these classes cannot derive from
:class:`harness.errors.HarnessError`. The harness includes them in its own error tree
instead: :mod:`harness.errors` re-exports them and names both roots in
:data:`harness.errors.EXPECTED_ERRORS`, the tuple its command line catches.
"""

from __future__ import annotations


class DriverError(Exception):
    """Base of every error the drivers raise on purpose (protocol, bus, bus load)."""


class ProtocolError(DriverError, ValueError):
    """A CAN frame, value or DBC does not match what the protocol expects.

    For example a DBC without its ``ProtocolVersion``, a signal name the message
    lacks, or a value outside the signal's range (say ``force`` of 40000 N where the
    DBC allows -30000..30000 N).
    """


class BusError(DriverError, OSError):
    """A CAN bus cannot be opened, used, or has failed; the message says how to fix it."""


class BusLoadError(DriverError, ValueError):
    """The configured messages and rates (Hz) need more of the bitrate (bit/s) than the allowed share."""
