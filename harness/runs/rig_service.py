"""``harness rig PROFILE``: serve the virtual rig on a CAN bus in the foreground.

The CLI parses the arguments and calls :func:`run_rig_command`; this module does
the rest: load the profile and record, open the bus (checked by
:func:`harness.canbus.link.open_rig`), serve the rig in a thread until Ctrl-C or the stop
event, then stop cleanly: drive disabled and announced, bus shut down.

The rig serves run after run. Each change it sees (the drive's state and fault, the
harness's run, the table, a drive reset) is queued by the rig's thread in its journal
(:mod:`harness.rig.journal`); this thread, which only waits for the stop, hands the lines
to ``on_journal`` every :data:`JOURNAL_PERIOD_S`, so printing never delays the physics.
"""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable
from pathlib import Path

from harness import exit_codes
from harness.canbus.config import CanConfig
from harness.canbus.link import open_rig
from harness.errors import EXPECTED_ERRORS, BusError
from harness.model.warmup import warm_up
from harness.profile import Profile, load_profile
from harness.realtime.host import freeze_garbage
from harness.rig.parts import RigParts
from harness.rig.virtual_rig import VirtualRig
from harness.runs.options import StudyOptions, prepare_motion, resolve_profile

#: How often the serving thread checks for the stop and prints the rig's journal (s).
JOURNAL_PERIOD_S = 0.1


def run_rig_command(
    profile_path: str | Path | None,
    *,
    interface: str | None = None,
    channel: str | None = None,
    lockstep: bool = False,
    options: StudyOptions | None = None,
    seed: int | None = None,
    variant: str | None = None,
    overrides: list[str] | tuple[str, ...] = (),
    stop_event: threading.Event | None = None,
    clock: Callable[[], float] = time.monotonic,
    on_ready: Callable[[VirtualRig], None] | None = None,
    parent_pid: int | None = None,
    on_journal: Callable[[float, str], None] | None = None,
) -> int:
    """Serve the virtual rig until Ctrl-C or ``stop_event``; return an exit status.

    Parameters
    ----------
    profile_path : str or Path or None
        Profile YAML (None: the default profile).
    interface, channel : str, optional
        Override the profile's ``can.interface`` / ``can.channel`` (``--interface``, ``--channel``).
    lockstep : bool
        ``--lockstep``: start in lockstep and stay there (otherwise the harness may
        switch it on with RIG_CONTROL lockstep=1).
    options : StudyOptions, optional
        Record overrides (``--record``, ``--records-dir``, ``--pga``, ``--time-scale``,
        ``--duration``); ``rate_hz`` (``--rate``) sets the step period (default: the
        profile's ``control.rate_hz``, the harness's tick rate).
    seed : int, optional
        ``--seed``: noise seed (default ``rig.seed``).
    variant : str, optional
        ``--variant`` of the profile.
    overrides : sequence of str
        ``--set KEY.PATH=VALUE`` profile overrides.
    stop_event : threading.Event, optional
        Set it to stop (tests, an embedding process); Ctrl-C stops too.
    clock : callable
        Wall clock (s).
    on_ready : callable, optional
        Called with the running rig once it serves (for a console's status line).
    parent_pid : int, optional
        Stop (drive disabled and announced) once this process is gone: a dry run that
        started the rig and died must not leave it serving.
    on_journal : callable, optional
        ``on_journal(wall_time_s, line)``: each state change of the rig (drive, harness run,
        table, drive reset), called from this thread, never from the rig's.

    Returns
    -------
    int
        :data:`harness.exit_codes.OK` after a stop by ``stop_event``,
        :data:`~harness.exit_codes.STOPPED` after Ctrl-C. Configuration errors
        (profile, record, bus) raise one of :data:`~harness.errors.EXPECTED_ERRORS`
        before anything is sent; the CLI maps them to ``INPUT_ERROR``.

    Raises
    ------
    BusError
        The rig stopped serving on its own (the bus failed), after the clean stop.
    """
    options = options or StudyOptions()
    profile = resolve_profile(load_profile(profile_path, variant, overrides), options)
    return serve_rig(profile, profile.can_settings(interface, channel), lockstep=lockstep, seed=seed,
                     stop_event=stop_event, clock=clock, on_ready=on_ready, parent_pid=parent_pid, on_journal=on_journal)


def serve_rig(
    profile: Profile,
    can_config: CanConfig,
    *,
    lockstep: bool = False,
    seed: int | None = None,
    stop_event: threading.Event | None = None,
    clock: Callable[[], float] = time.monotonic,
    on_ready: Callable[[VirtualRig], None] | None = None,
    parent_pid: int | None = None,
    on_journal: Callable[[float, str], None] | None = None,
    peer_pids: tuple[int, ...] = (),
) -> int:
    """Serve the virtual rig of a resolved ``profile`` on ``can_config`` until stopped.

    The rig steps at the profile's ``control.rate_hz`` (the harness's tick rate) and plays
    its ``record`` section. Parameters and return value as :func:`run_rig_command`;
    ``peer_pids``: on a ``seqpacket`` channel, the only processes the rig admits at the other
    end (the dry run that started it), so a relay or a stranger on the channel is refused.
    """
    warm_up()  # compile the plant's kernel before serving the bus in real time
    motion = prepare_motion(profile)
    period = 1.0 / profile.control.rate_hz
    stop = stop_event or threading.Event()
    with open_rig(can_config, peer_pids) as link:
        rig = VirtualRig(
            RigParts.from_profile(profile), motion, link, step_period_s=period, lockstep=lockstep or None, seed=seed,
            clock=clock,
            can_config=can_config,
        )
        status = exit_codes.OK
        freeze_garbage()  # no full collection over the start-up's objects while serving (harness.realtime.host)
        rig.start_thread(fifo_priority=profile.loop.realtime.fifo_priority)  # in real time only (harness.rig.runner)
        try:
            if on_ready is not None:
                on_ready(rig)
            while not stop.wait(JOURNAL_PERIOD_S) and rig.serving and _alive(parent_pid):
                _print_journal(rig, on_journal)
        except KeyboardInterrupt:
            status = exit_codes.STOPPED
        finally:
            rig.stop()
            _print_journal(rig, on_journal)
    if isinstance(rig.error, (*EXPECTED_ERRORS, OSError)):
        raise BusError(f"the virtual rig stopped serving: {rig.error}") from rig.error
    if rig.error is not None:
        raise rig.error
    return status


def _print_journal(rig: VirtualRig, on_journal: Callable[[float, str], None] | None) -> None:
    """Hand the rig's journalled lines to ``on_journal`` (this thread: the rig's own never prints)."""
    for wall_time_s, line in rig.journal.drain():
        if on_journal is not None:
            on_journal(wall_time_s, line)


def _alive(pid: int | None) -> bool:
    """True while process ``pid`` exists (always True for None)."""
    if pid is None or os.getppid() == pid:
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True
