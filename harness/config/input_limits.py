"""Ranges of the numbers a user may give, on the command line and in profiles, with the reason for each.

Every bound here caps something real: an allocation that grows with the number (samples of a
simulation, rows of a run, slots of a detector's window), or what the rig and the CAN bus can do.
The command line checks its options against them when it parses them
(``harness/commands/options.py``) and the profile schema declares the same bounds on the
matching keys, so ``--rate``, a profile's ``control.rate_hz`` and ``--set`` all refuse the same
values with the same reason.

This module imports nothing heavy: the command line uses it before it loads numpy.
"""

from __future__ import annotations

from dataclasses import dataclass

#: The loop's rate when a profile gives none (Hz): ``control.rate_hz``, the one rate the controller
#: samples at, the loop ticks at and the actuator command goes at (harness/control/config.py).
DEFAULT_RATE_HZ = 500.0

#: Fastest loop or controller sample rate (Hz): the schema's bound (``control.rate_hz <= 5000``,
#: harness/control/config.py). A Python tick computes in one to a few hundred us and the host stalls for
#: 0.2-1 ms and more (benchmarks/README.md: "Timing facts the loop is built on", "Loop compute budget"),
#: so a faster loop cannot keep its deadlines; a simulation faster than any loop would predict a
#: test nobody can run. Below this bound the virtual rig's physics
#: sub-step (0.5 ms) and the CAN bus load check refuse, with their own figures, rates the rig or
#: the bus cannot serve.
MAX_RATE_HZ = 5000.0

#: Largest target peak table acceleration (g): the records' plausibility bound
#: (:data:`harness.motions.checks.MAX_ABS_ACCEL_G`, 10 g, which no record reaches); a table's own
#: limit (``table.acceleration_limit_g``) then refuses what that table cannot do.
MAX_PGA_G = 10.0

#: Range of the time compression factor F. Froude similitude makes F the square root of the length
#: scale, so F = 10 is a 1:100 model, smaller than any shaking-table building; F < 1 stretches the
#: record, and F = 0.1 makes it ten times longer (the run's length, and what it allocates, grow as 1/F).
MIN_TIME_SCALE = 0.1
MAX_TIME_SCALE = 10.0

#: Longest run or simulation (s): ten times the longest record of the catalog (Hachinohe, 60 s).
#: Memory grows with it: a simulation at :data:`MAX_RATE_HZ` for 600 s holds 3 million samples
#: of the state (about 0.5 GB for the eight-story building); a run folder's signals.csv at 500 Hz
#: gets about 75 MB.
MAX_DURATION_S = 600.0

#: Fewest samples a run or a simulation covers, of the record and of the loop alike: a record of
#: fewer is refused (:data:`harness.motions.checks.MIN_SAMPLES` is this number), and so is a run
#: shorter than this many loop periods (a 0.5 s simulation at 1 Hz reported zero for every peak).
#: ``--duration`` therefore has a lower bound besides the range above: this many samples of the
#: record (0.05 s for the synthetic record at time scale 2) and this many periods (0.02 s at 500 Hz).
MIN_RUN_SAMPLES = 10

#: Loop periods that must fit in the stall budget (``safety.run.max_stall_s``): the shortest
#: stall, one missed deadline, is a gap of two periods between two ticks, and the loop is meant
#: to ride such a stall through. With a period longer than half the budget every late tick trips
#: ``loop_stall`` (a dry run at 50 Hz, a 20 ms period against the 20 ms budget, tripped on its
#: sixth tick). docs/SAFETY.md, "Stall budget".
STALL_BUDGET_PERIODS = 2.0

#: Loop periods that must fit in the drive's watchdog (``rig.drive.watchdog_timeout_s``): a
#: command reaches the drive within one more period (the rig is serviced once a period), so the
#: drive sees a command at most two periods old; a longer period disables the drive between
#: commands and the run cannot arm (``--rate 10``: "drive fault=True"). docs/SAFETY.md, "Stall budget".
WATCHDOG_PERIODS = 2.0

#: Longest transport delay (s): the rig's sensor and actuator delays share this bound
#: (``rig.*.delay_s <= 1``); a delay line holds one slot per sub-step, and a delay of a second is
#: already longer than the fundamental period of the isolated building, beyond any useful feedback.
MAX_DELAY_S = 1.0

#: Range of the controller model's stiffness factor (robustness studies use 0.7 and 1.3): beyond
#: a factor of ten either way the design model is not the same building any more.
MIN_STIFFNESS_SCALE = 0.1
MAX_STIFFNESS_SCALE = 10.0

#: Largest noise seed: 32 bits, which NumPy's seeding and every tool reading the metadata take;
#: more bits would not give runs that differ in any way that matters here.
MAX_SEED = 2**32 - 1

#: Largest process id: Linux caps ``/proc/sys/kernel/pid_max`` at 2^22 (``PID_MAX_LIMIT``).
MAX_PID = 2**22

#: Largest count a safety detector's sliding window may allow (``safety.comms.max_*``): the
#: window preallocates one slot per allowed event (8 bytes each), and a 1 Mbit/s bus carries at
#: most about 8,000 frames a second, so a limit above 10,000 per window would never fire and
#: only cost memory (a limit of 10^9 asked for 8 GB).
MAX_WINDOW_COUNT = 10_000

#: Largest event ring of the supervisor (``safety.run.event_capacity``): a run raises a few events
#: per fault; 65,536 preallocated slots hold every event of a long run with a fault every tick
#: for two minutes at 500 Hz.
MAX_EVENT_CAPACITY = 65_536


@dataclass(frozen=True)
class NumberRange:
    """An allowed range of a number, with its unit, for messages like "a number of Hz in (0, 5000]".

    Parameters
    ----------
    low, high : float
        The bounds.
    unit : str
        Unit of the number ("" for a plain factor).
    low_open : bool
        True if ``low`` itself is refused.
    integer : bool
        True for whole numbers.
    """

    low: float
    high: float
    unit: str = ""
    low_open: bool = True
    integer: bool = False

    def describe(self) -> str:
        """Words for the range, e.g. ``"a number of Hz in (0, 5000]"``."""
        kind = "a whole number" if self.integer else "a number"
        unit = f" of {self.unit}" if self.unit else ""
        opening = "(" if self.low_open else "["
        return f"{kind}{unit} in {opening}{self.low:g}, {self.high:g}]"

    def check(self, text: str) -> float | int:
        """Parse ``text`` and check it is in the range.

        Returns
        -------
        float or int
            The number (an int when :attr:`integer`).

        Raises
        ------
        ValueError
            Saying what was found and what is expected.
        """
        unit = f" {self.unit}" if self.unit else ""
        stripped = text.strip()
        if not stripped:
            raise ValueError(f"found an empty value, expected {self.describe()}")
        try:
            value: float | int = int(stripped) if self.integer else float(stripped)
        except ValueError:
            raise ValueError(f"found {text!r}, expected {self.describe()}") from None
        below = value <= self.low if self.low_open else value < self.low
        # NaN fails every comparison, so test "inside" rather than "outside".
        if not (not below and value <= self.high):
            raise ValueError(f"found {value:g}{unit}, expected {self.describe()}")
        return value
