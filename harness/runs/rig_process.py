"""The virtual rig's own process, as ``harness dry-run`` starts it.

``python -m harness.runs.rig_process`` reads one JSON document on its standard input: the
profile the dry run resolved (:meth:`harness.profile.Profile.resolved_data`), the CAN
interface and channel, ``lockstep`` and ``parent_pid``. It parses no command-line
options, so the rig always serves the very profile the loop runs. On a ``seqpacket`` channel
it admits only ``parent_pid`` at the other end (:mod:`drivers.transports.seqpacket.peers`): the dry run
made the channel's name and hands it over here, and a hub or relay that another process put on
it is refused. It serves until
SIGINT, or until the dry run's process is gone; a problem goes to standard error, which
the dry run reports.
"""

from __future__ import annotations

import json
import sys

from harness import exit_codes
from harness.loop.operator import OperatorSignals


def main() -> int:
    """Serve the rig of the job on standard input; return an exit status.

    The dry run may stop this process while it still imports (its SIGINT): the handlers that
    only set a flag come first, and the serve's own (:func:`stop_on_signals`) take the request
    over, so a stop is never swallowed by a library's callback and the rig never serves on.
    """
    with OperatorSignals():
        try:
            return _serve()
        except KeyboardInterrupt:
            return exit_codes.STOPPED


def _serve() -> int:
    from harness.errors import EXPECTED_ERRORS
    from harness.profile import Profile
    from harness.realtime.interrupts import stop_on_signals
    from harness.runs.rig_service import serve_rig

    job = json.loads(sys.stdin.read())
    profile = Profile.from_resolved(job["profile"])
    can_config = profile.can_settings(job["interface"], job["channel"])
    try:
        with stop_on_signals():
            return serve_rig(profile, can_config, lockstep=job["lockstep"], parent_pid=job["parent_pid"],
                             peer_pids=(job["parent_pid"],))
    except EXPECTED_ERRORS as err:
        print(f"error: {err}", file=sys.stderr)
        return exit_codes.INPUT_ERROR


if __name__ == "__main__":
    sys.exit(main())
