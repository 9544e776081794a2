"""``harness replay``: a run's ticks again from its own log, bit for bit, or with changed settings (open loop)."""

from __future__ import annotations

import argparse

from rich.console import Console
from rich.markup import escape

from harness import exit_codes
from harness.commands.options import add_overrides, output_dir, wrap

EXAMPLES = """\
examples:
  harness replay logs/<RUN>          (exact: every frame compared bit for bit with the one the run sent)
  harness replay logs/<RUN> --set safety.stroke.hard_limit_m=0.097
      (what-if, open loop: would the tighter stroke bound have tripped, when and on what)
  harness replay logs/<RUN> --set control.compensation=model --out logs/whatif/
  harness report logs/<RUN> logs/whatif/          (recorded and replayed overlaid)

exit status: 0 replayed identical, or a what-if replayed; 1 an exact replay that differs from the
run (the first differing tick is printed: a non-determinism in the tick, or other code than the
run had); 2 a run folder that cannot be replayed (logged before replay existed, an incomplete
record, a kind replay does not cover) or a change a what-if cannot apply
"""


def add_parser(sub) -> None:
    parser = sub.add_parser(
        "replay",
        help="re-run a run's ticks from its own log: bit for bit, or what-if with changed settings",
        description=wrap(
            "Run the ticks of a dry run or run again from its run folder, through the same tick code as the run "
            "(decoder, estimator, controller, compensation, supervisor, writer): each tick gets the frames it "
            "consumed, in the order the run's reader handled them, and the time, step, lateness and stall the "
            "loop gave it. Without changes it compares every frame the replay would send with the one the run "
            "sent (force, enable, counter and CRC, bit for bit) and prints 'replayed N ticks: N identical' and "
            "the recorded outcome, or the first differing tick with both frames (exit 1). With --set or --overlay "
            "it replays the same sensor frames through the changed settings (a controller, a bound, a detector's "
            "threshold, compensation) and reports where the commands first differ, the largest difference and "
            "whether, when and on what the changed supervisor would have tripped. That is open loop: the rig "
            "does not answer the changed commands. Nothing moves and nothing is written."
        ),
        epilog=EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("run_dir", metavar="RUN_DIR", help="a run folder of `harness dry-run` or `harness run`")
    add_overrides(parser, "safety.stroke.hard_limit_m=0.097")
    parser.add_argument("--out", type=output_dir, metavar="DIR",
                        help="also write the replayed ticks as a run folder in DIR (signals and events), so that "
                        "`harness report RUN_DIR DIR` overlays recorded and replayed")
    parser.add_argument("--quiet", action="store_true", help="print the first line and the outcome only")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, console: Console) -> int:
    from harness.replay.run import replay

    output = replay(args.run_dir, tuple(args.overrides), args.overlay, args.variant, args.out)
    lines = output.lines if not args.quiet else [output.lines[0], *(line for line in output.lines if "outcome" in line)]
    if args.quiet and args.out:
        lines.append(output.lines[-1])
    for line in lines:
        console.print(escape(line), highlight=False, soft_wrap=True)
    if not args.quiet:
        console.print(f"replay took {output.seconds:.2f} s for {output.run_span_s:.2f} s of the run's loop time",
                      highlight=False)
    if output.identical is False:
        return exit_codes.INTERNAL_ERROR
    return exit_codes.OK
