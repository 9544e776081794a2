"""``harness run``'s question before arming and its peak table; the options and banner around a served rig.

The question is answered on standard input (pytest's captured stdout is not a terminal, so
rich prints plain text). The peak table is checked on a real session: a lockstep dry run's,
handed to ``harness run`` in place of a session on a real rig, which a test cannot have.
"""

from __future__ import annotations

import io
import shlex

import pytest

from harness import exit_codes
from harness.cli import build_parser, main
from harness.commands.rig import banner
from harness.profile import load_profile
from harness.recording import load_run
from harness.recording.peaks import run_peaks
from harness.report.quantities import CONSOLE_WORDING, response_quantities
from harness.runs.dry_run import DryRunOptions, dry_run
from harness.runs.options import StudyOptions

RUN = ["run", "--record", "synthetic", "--duration", "1", "--interface", "seqpacket", "--channel", "nowhere"]


def test_the_arm_prompt_shows_y_n_and_names_the_record_pga_time_scale_and_duration(monkeypatch, capsys):
    monkeypatch.setattr("sys.stdin", io.StringIO("n\n"))
    assert main([*RUN, "--pga", "0.2", "--time-scale", "2"]) == exit_codes.INPUT_ERROR
    out = capsys.readouterr().out
    prompt = next(line for line in out.splitlines() if line.startswith("Arm the actuator"))
    assert "mm)? [y/N] " in prompt, "[y/N] reaches the terminal (not taken for markup), on the prompt's one line"
    for part in ("on seqpacket:nowhere", "record synthetic:0", "PGA 0.200 g", "time scale 2", "1.0 s"):
        assert part in prompt, (part, prompt)
    assert out.rstrip().endswith("not armed")


def test_the_arm_prompt_says_the_drive_will_be_reset(monkeypatch, capsys):
    monkeypatch.setattr("sys.stdin", io.StringIO("\n"))
    assert main([*RUN, "--reset-drive"]) == exit_codes.INPUT_ERROR
    assert "Reset the drive's latched fault and arm the actuator" in capsys.readouterr().out


def test_reset_drive_needs_an_external_rig(capsys):
    assert main(["dry-run", "--reset-drive"]) == exit_codes.INPUT_ERROR
    assert "add --external-rig" in capsys.readouterr().err  # an error, on standard error (also under --quiet)


@pytest.mark.parametrize("lockstep", [False, True])
def test_the_rig_banner_prints_the_command_that_reaches_it(lockstep):
    text = banner("seqpacket", "harness", lockstep)
    command = next(line.strip() for line in text.splitlines() if line.strip().startswith("harness dry-run"))
    args = build_parser().parse_args(shlex.split(command)[1:])
    assert args.external_rig and args.interface == "seqpacket" and args.channel == "harness"
    assert args.lockstep is lockstep, "a lockstep rig's banner asks for --lockstep"
    assert "--reset-drive" in text


def test_run_prints_the_peak_table_of_what_it_measured(tmp_path, monkeypatch, capsys):
    profile = load_profile(None)
    done = dry_run(profile, DryRunOptions(study=StudyOptions(record="synthetic", duration_s=1.0), interface="virtual",
                                          log_dir=str(tmp_path), lockstep=True, show_console=False, compare=False))
    assert done.session.outcome == "completed"
    monkeypatch.setattr("harness.runs.run.run_session", lambda *args, **kwargs: done.session)
    capsys.readouterr()
    assert main([*RUN, "--yes", "--log-dir", str(tmp_path)]) == exit_codes.OK
    out = capsys.readouterr().out
    assert "peak responses of the run" in out and "run, record synthetic:0: PGA" in out
    peaks = run_peaks(load_run(done.session.run_path))
    for quantity in response_quantities(peaks.n_stories, CONSOLE_WORDING):
        value = quantity.display_value(peaks)
        assert value is not None
        row = next(line for line in out.splitlines() if quantity.label in line)
        assert f"{value:.{quantity.digits}f}" in row, (quantity.label, row)


def test_the_rig_terminal_prints_each_journal_line_on_one_stamped_line():
    from rich.console import Console

    from harness.commands.rig import print_journal_line

    out = io.StringIO()
    console = Console(file=out, width=40)
    line = "drive FAULT, fault HEARTBEAT_WATCHDOG; the next run needs --reset-drive [sic]"
    print_journal_line(console, 0.0, line)
    printed = out.getvalue().splitlines()
    assert len(printed) == 1 and printed[0].endswith(line), "one line, markup-looking text kept as it is"
    assert printed[0][2] == ":" and printed[0][5] == ":", "stamped HH:MM:SS"
