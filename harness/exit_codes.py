"""Exit statuses of the ``harness`` commands (documented in ``harness --help`` and the README)."""

#: The command did what was asked (a run completed, a simulation finished).
OK = 0
#: An unexpected internal error (a bug): the message says where; please report it.
INTERNAL_ERROR = 1
#: Bad input or a refused configuration, before anything moved: profile, record, bus, pre-arm check.
INPUT_ERROR = 2
#: The run tripped safely: force zeroed and drive disabled; the run folder says why.
TRIPPED = 3
#: The run was stopped early, safely (force ramped to zero, drive disabled): by the operator (Ctrl-C) or by a
#: check whose action is a safe stop (its name is the run's reason, e.g. ``table_record_mismatch``).
STOPPED = 4
