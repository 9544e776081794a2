"""Exit statuses of the ``harness`` commands (documented in ``harness --help`` and the README)."""

#: The command did what was asked (a run completed, a simulation finished).
OK = 0
#: An unexpected internal error (a bug): the message says where; please report it.
INTERNAL_ERROR = 1
#: Bad input or a refused configuration, before anything moved: profile, record, bus, pre-arm check.
INPUT_ERROR = 2
#: The run tripped safely: force zeroed and drive disabled; the run folder says why.
TRIPPED = 3
#: The operator stopped the run early (Ctrl-C): safe stop completed, run folder marked so.
STOPPED = 4
