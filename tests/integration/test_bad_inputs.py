"""Bad input files through the real command line: one clear error, exit status 2, never a traceback.

The profiles come from tests/unit/test_profile.py (each kind of bad profile); the records
are malformed accelerograms written here. Each goes through ``harness simulate`` (and the
profiles also through ``harness dry-run``) in-process: an exception escaping ``main``
would fail the test, so status 2 proves the error was handled and reported.

:data:`BAD_ARGUMENTS` is the bad-input sweep of both safety reviews as one table: every
option, value, path, key or file that was refused badly (a traceback, a silent acceptance,
an unclear message) and is now refused well. Each row runs through ``main`` in-process
and must exit 2, print no traceback, name the offending option or key with what was
expected, and leave no run folder (nor sweep results) behind.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

from harness import exit_codes
from harness.cli import main
from harness.profile import load_profile
from tests.conftest import PROFILES
from tests.unit.test_profile import BAD_PROFILES

GOOD_HEADER = "t_s,accel_g\n"
BAD_RECORDS = {
    "empty.csv": (b"", "empty"),
    "binary.csv": (bytes(range(256)) * 8, ""),
    "header_only.csv": (GOOD_HEADER.encode(), ""),
    "no_unit.csv": (b"t,acc\n" + b"".join(f"{i * 0.01:.2f},0.01\n".encode() for i in range(50)), "unit"),
    "text_value.csv": (
        (GOOD_HEADER + "".join(f"{i * 0.01:.2f},{'abc' if i == 7 else '0.01'}\n" for i in range(50))).encode(), ".csv:9:"
    ),
    "nan_value.csv": ((GOOD_HEADER + "".join(f"{i * 0.01:.2f},{'nan' if i == 9 else '0.01'}\n" for i in range(50))).encode(), ""),
    "non_uniform.csv": (
        (GOOD_HEADER + "".join(f"{i * 0.01 + (0.004 if i == 20 else 0):.3f},0.01\n" for i in range(50))).encode(), ""
    ),
    "too_short.csv": ((GOOD_HEADER + "0,0.01\n0.01,0.02\n").encode(), ""),
    "huge_values.csv": ((GOOD_HEADER + "".join(f"{i * 0.01:.2f},1e6\n" for i in range(50))).encode(), ""),
    "one_column.csv": ((GOOD_HEADER + "".join("0.01\n" for _ in range(50))).encode(), ""),
    "bad_at2.AT2": (b"PEER\nline2\nline3\nNPTS= 100, DT= .01 SEC\n0.1 0.2 oops\n", ""),
    "at2_missing_npts.AT2": (b"PEER\nline2\nline3\nno header here\n" + b"0.1 0.2 0.3\n" * 40, ""),
}


@pytest.mark.parametrize("case", sorted(BAD_PROFILES))
@pytest.mark.parametrize("command", ["simulate", "dry-run"])
def test_bad_profile_gives_a_clear_error_and_exit_2(tmp_path, capsys, case, command):
    content, pattern = BAD_PROFILES[case]
    path = tmp_path / f"{case}.yaml"
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    log_dir = ["--log-dir", str(tmp_path)] if command == "dry-run" else []
    status = main([command, str(path), "--duration", "1", "--quiet", *log_dir])
    err = capsys.readouterr().err
    assert status == exit_codes.INPUT_ERROR
    assert err.startswith("error:") and path.name in err
    assert "Traceback" not in err


@pytest.mark.parametrize("case", sorted(BAD_RECORDS))
def test_bad_record_gives_a_clear_error_and_exit_2(tmp_path, capsys, case):
    content, pattern = BAD_RECORDS[case]
    path = tmp_path / case
    path.write_bytes(content)
    status = main(["simulate", "--record", str(path), "--duration", "1", "--quiet"])
    err = capsys.readouterr().err
    assert status == exit_codes.INPUT_ERROR
    assert err.startswith("error:") and case in err
    assert pattern.lower() in err.lower()
    assert "Traceback" not in err


def test_bad_input_file_gives_a_clear_error_and_exit_2(tmp_path, capsys):
    """At least 20 malformed inputs are covered by the two tests above (the issue's count)."""
    assert len(BAD_PROFILES) + len(BAD_RECORDS) >= 20
    status = main(["simulate", "--record", str(tmp_path / "missing.AT2"), "--quiet"])
    err = capsys.readouterr().err
    assert status == exit_codes.INPUT_ERROR and "missing.AT2" in err


# --- every bad option, value, path or key: exit 2, a message naming it and what was expected -------------

#: The billion laughs: nine anchors, each nine aliases of the one before (9^9 strings once expanded), in 300 bytes.
ALIAS_BOMB = "l0: &l0 [" + ", ".join(["lol"] * 9) + "]\n" + "".join(
    f"l{i}: &l{i} [" + ", ".join([f"*l{i - 1}"] * 9) + "]\n" for i in range(1, 9)
)

RATE_RANGE = "expected a number of Hz in (0, 5000]"
DURATION_RANGE = "expected a number of s in (0, 600]"
#: (arguments, what the message must say); ``{tmp}`` is a folder prepared by the ``inputs`` fixture.
BAD_ARGUMENTS = {
    # harness simulate --drive-from (issue 34): what the twin is driven from, refused with what was expected
    "drive_from_a_folder_that_is_no_run": (
        ["simulate", "--rig-effects", "--drive-from", "{tmp}/folder"],
        ["--drive-from", "found no metadata.json", "`harness dry-run` or `harness run`"],
    ),
    "drive_from_without_rig_effects": (
        ["simulate", "--drive-from", "{tmp}/folder"], ["--drive-from", "expected --rig-effects with it"],
    ),
    "drive_from_with_a_record": (
        ["simulate", "--rig-effects", "--drive-from", "{tmp}/folder", "--pga", "0.2"],
        ["found --pga with --drive-from", "replaces the record"],
    ),
    # crashed with a traceback (exit 1)
    "simulate_negative_rate": (["simulate", "--rate", "-500"], ["--rate", "found -500 Hz", RATE_RANGE]),
    "e2e_window_of_a_billion": (
        ["dry-run", "--set", "safety.comms.max_e2e_rejects=1000000000"],
        ["safety.comms.max_e2e_rejects", "found 1e+09", "<= 10000"],
    ),
    "report_binary_signals": (["report", "{tmp}/binary_signals"], ["signals.csv", "not UTF-8 text", "byte 0x"]),
    # silently accepted
    "simulate_zero_rate": (["simulate", "--rate", "0"], ["--rate", "found 0 Hz", RATE_RANGE]),
    "simulate_rate_20_kHz": (["simulate", "--rate", "20000"], ["--rate", "found 20000 Hz", RATE_RANGE]),
    "report_half_truncated_signals": (
        ["report", "{tmp}/truncated_signals"], ["signals.csv", "holds 20 rows (lines 2 to 21)", "wrote 40", "rows 21 to 40"],
    ),
    # unclear messages
    "dry_run_negative_rate": (["dry-run", "--rate", "-500"], ["--rate", "found -500 Hz", RATE_RANGE]),
    "infinite_duration": (["simulate", "--duration", "inf"], ["--duration", "found inf s", DURATION_RANGE]),
    "record_without_unit": (["simulate", "--record", "{tmp}/no_unit.csv"], ["no_unit.csv", "record.accel_unit", "header"]),
    "acceleration_1e308": (["simulate", "--record", "{tmp}/huge.csv"], ["huge.csv:7", "1e+308 g", "exceeds 10 g"]),
    "binary_dbc": (["dry-run", "--set", "can.dbc_path={tmp}/binary.dbc"], ["binary.dbc", "not a text file", "expected a DBC"]),
    # a dozen more of the same kind
    "nan_rate": (["simulate", "--rate", "nan"], ["--rate", "found nan Hz", RATE_RANGE]),
    "rig_zero_rate": (["rig", "--rate", "0"], ["--rate", "found 0 Hz", RATE_RANGE]),
    "run_negative_rate": (["run", "--rate", "-1"], ["--rate", "found -1 Hz", RATE_RANGE]),
    "text_rate": (["simulate", "--rate", "fast"], ["--rate", "found 'fast'", RATE_RANGE]),
    "empty_duration": (["simulate", "--duration", ""], ["--duration", "found an empty value", DURATION_RANGE]),
    "zero_duration": (["records", "synthetic", "--duration", "0"], ["--duration", "found 0 s", DURATION_RANGE]),
    "negative_pga": (["simulate", "--pga", "-0.3"], ["--pga", "found -0.3 g", "expected a number of g in (0, 10]"]),
    "nan_pga": (["records", "synthetic", "--pga", "nan"], ["--pga", "found nan g", "(0, 10]"]),
    "zero_time_scale": (["simulate", "--time-scale", "0"], ["--time-scale", "found 0", "expected a number in [0.1, 10]"]),
    "huge_time_scale": (["dry-run", "--time-scale", "1e9"], ["--time-scale", "found 1e+09", "[0.1, 10]"]),
    "negative_delay": (["simulate", "--delay", "-0.001"], ["--delay", "found -0.001 s", "expected a number of s in [0, 1]"]),
    "zero_stiffness_scale": (["simulate", "--design-stiffness-scale", "0"], ["--design-stiffness-scale", "found 0", "[0.1, 10]"]),
    "negative_seed": (["rig", "--seed", "-1"], ["--seed", "found -1", "expected a whole number in [0, 4.29497e+09]"]),
    "fractional_seed": (["rig", "--seed", "1.5"], ["--seed", "found '1.5'", "whole number"]),
    "set_without_equals": (["dry-run", "--set", "safety.stroke.hard_limit_m"], ["--set", "expected KEY.PATH=VALUE"]),
    "set_empty": (["dry-run", "--set", ""], ["--set", "expected KEY.PATH=VALUE"]),
    "set_unknown_key": (["dry-run", "--set", "safety.strokes.hard_limit_m=0.05"], ["safety.strokes", "unknown key 'strokes'"]),
    "set_bad_yaml": (["dry-run", "--set", "safety.stroke.hard_limit_m=[0.05"], ["--set", "not valid YAML"]),
    "set_twice": (
        ["dry-run", "--set", "safety.stroke.hard_limit_m=0.05", "--set", "safety.stroke.hard_limit_m=0.02"],
        ["--set", "sets safety.stroke.hard_limit_m again", "expected each key once"],
    ),
    "set_duplicate_inside_value": (
        ["dry-run", "--set", "safety.stroke={hard_limit_m: 0.05, hard_limit_m: 0.02}"], ["--set", "duplicate key 'hard_limit_m'"],
    ),
    "set_rate_above_bound": (["dry-run", "--set", "control.rate_hz=20000"], ["control.rate_hz", "found 20000", "<= 5000 Hz"]),
    "unknown_variant": (["simulate", "--variant", "no_such_variant"], ["unknown variant 'no_such_variant'"]),
    "missing_profile": (["simulate", "{tmp}/missing.yaml"], ["missing.yaml", "not found", "expected an existing YAML file"]),
    "profile_is_a_directory": (["dry-run", "{tmp}/folder"], ["folder", "is a directory", "expected an existing YAML file"]),
    "record_is_a_directory": (["simulate", "--record", "{tmp}/folder"], ["folder", "is a directory, expected a record file"]),
    "missing_record": (["records", "{tmp}/missing.csv"], ["missing.csv", "does not exist"]),
    "too_long_record": (
        ["dry-run", "--record", "{tmp}/long.csv", "--time-scale", "1", "--set", "record.duration_s=null"],
        ["runs 700 s", "at most 600 s", "--duration"],
    ),
    "json_is_a_directory": (["simulate", "--json", "{tmp}/folder"], ["--json", "is a directory, expected a file name"]),
    "json_in_missing_folder": (["simulate", "--json", "{tmp}/nowhere/out.json"], ["--json", "nowhere", "does not exist"]),
    "out_is_a_file": (["simulate", "--out", "{tmp}/file.txt"], ["--out", "is a file, expected a directory"]),
    "log_dir_is_a_file": (["dry-run", "--log-dir", "{tmp}/file.txt"], ["--log-dir", "is a file, expected a directory"]),
    "plot_is_a_directory": (["records", "synthetic", "--plot", "{tmp}/folder"], ["--plot", "is a directory"]),
    "report_missing_folder": (["report", "{tmp}/missing_run"], ["missing_run", "no such folder, expected a run folder"]),
    "report_of_a_file": (["report", "{tmp}/file.txt"], ["file.txt", "is a file, expected a run folder"]),
    "report_binary_events": (["report", "{tmp}/binary_events"], ["events.jsonl", "not UTF-8 text"]),
    "dbc_is_a_directory": (["dry-run", "--set", "can.dbc_path={tmp}/folder"], ["folder", "is a directory, expected a DBC"]),
    "missing_dbc": (["dry-run", "--set", "can.dbc_path={tmp}/missing.dbc"], ["missing.dbc", "not found"]),
    "empty_record_name": (["simulate", "--record", ""], ["--record", "found an empty value"]),
    "empty_controller": (["dry-run", "--controller", " "], ["--controller", "found an empty value"]),
    "synthetic_seed_too_large": (
        ["simulate", "--record", "synthetic:99999999999999999999"], ["expected a seed in [0, 4294967295]"]
    ),
    "zero_parent_pid": (["rig", "--parent-pid", "0"], ["--parent-pid", "found 0", "expected a whole number in [1, 4.1943e+06]"]),
    "weaker_safety_without_the_flag": (
        ["dry-run", "--set", "safety.comms.error_frame_action=indicate"],
        ["safety.comms.error_frame_action safe_stop -> indicate", "--allow-weaker-safety"],
    ),
    "max_force_beyond_the_dbc_with_the_flag": (
        ["dry-run", "--set", "safety.force.max_force_N=40000", "--allow-weaker-safety",
         # a load-cell limit and a supply force above it, so that the protocol's bound is the one that speaks
         "--set", "safety.force.load_cell_limit_N=60000", "--set", "safety.force.supply_force_N=60000"],
        ["safety.force.max_force_N", "found 40000 N", "expected at most 30000 N", "ACTUATOR_CMD"],
    ),
    # --- second review (issue 19): a traceback (exit 1) ---
    **{
        f"log_dir_{label}_{command.replace('-', '_')}": (
            [command, "--log-dir", path, *(["--yes"] if command == "run" else [])], ["--log-dir", *expected],
        )
        for command in ("dry-run", "run")
        for label, path, expected in (
            ("proc_self_x", "/proc/self/x", ["/proc/self/x: cannot create a folder there", "expected a writable directory"]),
            ("proc_1", "/proc/1", ["/proc/1: cannot create a folder there", "expected a writable directory"]),
            ("sys_kernel", "/sys/kernel", ["/sys/kernel: cannot create a folder there", "expected a writable directory"]),
            ("below_a_file", "{tmp}/file.txt/logs", ["file.txt/logs is below", "which is a file, expected a directory"]),
        )
    },
    "deep_yaml_profile": (["simulate", "{tmp}/deep.yaml"], ["deep.yaml", "invalid YAML", "nested deeper than 32 levels",
                                                           "MAX_DEPTH"]),
    "deep_yaml_profile_dry_run": (["dry-run", "{tmp}/deep.yaml"], ["deep.yaml", "MAX_DEPTH"]),
    "deep_yaml_set": (["dry-run", "--set", "name=" + "[" * 500 + "]" * 500], ["--set", "not valid YAML", "MAX_DEPTH"]),
    "deep_yaml_study": (["sweep", "{tmp}/deep_study.yaml"], ["deep_study.yaml", "invalid YAML", "MAX_DEPTH"]),
    # --- second review: refused only after 66 s and 3.2 GB ---
    "alias_bomb_in_a_string_field": (["simulate", "{tmp}/bomb.yaml"], ["bomb.yaml", "more than 100000 values", "MAX_VALUES"]),
    "alias_bomb_dry_run": (["dry-run", "{tmp}/bomb.yaml"], ["bomb.yaml", "MAX_VALUES"]),
    "alias_bomb_set": (["simulate", "--set", "description=" + ALIAS_BOMB], ["--set", "not valid YAML", "MAX_VALUES"]),
    "alias_bomb_study": (["sweep", "{tmp}/bomb_study.yaml"], ["bomb_study.yaml", "MAX_VALUES"]),
    "recursive_alias": (["simulate", "{tmp}/recursive.yaml"], ["recursive.yaml", "recursive anchor"]),
    "set_value_of_a_megabyte": (["dry-run", "--set", "name=" + "x" * 1_000_001], ["--set", "MAX_YAML_CHARS", "'name=xxx"]),
    # --- second review: 120 s of silence and 2.3 GB ---
    "sweep_plan_of_ten_million_cases": (
        ["sweep", "{tmp}/huge_study.yaml", "--plan"],
        ["huge_study.yaml", "axes", "10000000 cases", "10 records x 1000 PGA levels", "expected at most 100000 (MAX_CASES)"],
    ),
    "reset_drive_without_external_rig_quiet": (["dry-run", "--reset-drive", "--quiet"],
                                               ["--reset-drive resets the drive", "add --external-rig"]),
    "study_record_is_not_a_record": (["sweep", "{tmp}/secret_study.yaml"],
                                     ["secret_study.yaml", "axes.records[0]", "is not a record file"]),
    "sweep_of_ten_million_cases": (["sweep", "{tmp}/huge_study.yaml"], ["huge_study.yaml", "axes", "(MAX_CASES)"]),
    # --- second review: unclear messages, and a run folder written ---
    "lockstep_rate_0_001": (
        ["dry-run", "--lockstep", "--rate", "0.001"],
        ["--rate", "found 0.001 Hz", "expected at least 100 Hz", "safety.run.max_stall_s", "rig.drive.watchdog_timeout_s"],
    ),
    "realtime_rate_10": (["dry-run", "--rate", "10"], ["--rate", "found 10 Hz", "expected at least 100 Hz",
                                                       "rig.drive.watchdog_timeout_s (50 ms"]),
    "run_rate_10": (["run", "--rate", "10", "--yes"], ["--rate", "found 10 Hz", "expected at least 100 Hz"]),
    "rate_profile_key_below_the_bound": (
        ["dry-run", "--set", "control.rate_hz=50"],
        ["control.rate_hz", "found 50 Hz", "expected at least 100 Hz"],
    ),
    "rate_copy_key_of_old": (
        ["dry-run", "--set", "loop.rate_hz=1000"],
        ["loop.rate_hz is no longer a key", "one rate, control.rate_hz", "remove this key"],
    ),
    "command_rate_copy_key_of_old": (
        ["dry-run", "--set", "can.command_rate_hz=1000"],
        ["can.command_rate_hz is no longer a key", "control.rate_hz"],
    ),
    "dry_run_rate_of_no_whole_substeps": (["dry-run", "--rate", "300"], ["--rate", "found 300 Hz", "rig.physics_substep_s",
                                                                         "333.333 Hz or 285.714 Hz"]),
    "duration_1e_9": (["dry-run", "--duration", "1e-9"], ["--duration", "found 1e-09 s", "expected at least 0.02 s"]),
    "simulate_duration_1e_9": (["simulate", "--duration", "1e-9"], ["--duration", "found 1e-09 s", "expected at least 0.02 s"]),
    "run_duration_1e_9": (["run", "--duration", "1e-9", "--yes"], ["--duration", "found 1e-09 s"]),
    # --- issue 23: --overlay ---
    "missing_overlay": (["simulate", "--overlay", "{tmp}/missing_overlay.yaml"],
                        ["missing_overlay.yaml", "not found", "expected an existing YAML file"]),
    "overlay_unknown_key": (["dry-run", "--overlay", "{tmp}/typo_overlay.yaml"],
                            ["typo_overlay.yaml", "bearing.mu_maxx", "unknown key 'mu_maxx'"]),
    "overlay_with_extends": (["simulate", "--overlay", "{tmp}/extends_overlay.yaml"],
                             ["extends_overlay.yaml", "an overlay holds values only", "expected no 'extends'"]),
    "overlay_weakens_safety": (["dry-run", "--overlay", "{tmp}/weak_overlay.yaml"],
                               ["safety.comms.error_frame_action safe_stop -> indicate", "--allow-weaker-safety"]),
    "duration_below_ten_record_samples": (
        ["simulate", "--duration", "0.03"], ["--duration", "0.03 s", "expected at least 0.05 s", "10 samples of the record"],
    ),
    # --- third review (issue 30): data and messages ---
    "identify_actuator_band_between_two_bins": (  # excited the actuator, then an IndexError
        ["identify", "actuator", "--resolution-hz", "10", "--band-hz", "1,5", "--duration", "2", "--out", "{tmp}/frf"],
        ["--resolution-hz", "a frequency every 7.81 Hz", "--band-hz 1,5 holds 0 of them", "expected at least 10"],
    ),
    "identify_actuator_into_earlier_results": (
        ["identify", "actuator", "--duration", "4", "--resolution-hz", "1", "--out", "{tmp}/earlier_results"],
        ["earlier_results", "already holds the results of an earlier identification", "excitation.json", "--force"],
    ),
    "identify_structure_band_between_two_bins": (  # an IndexError
        ["identify", "structure", "{tmp}/quiet_run", "--band-hz", "1,1.01", "--out", "{tmp}/ident"],
        ["--band-hz 1,1.01 holds 0 frequencies", "expected at least 10"],
    ),
    "identify_structure_nan_row": (  # a ValueError
        ["identify", "structure", "{tmp}/nan_row_run", "--out", "{tmp}/ident"],
        ["nan_row_run", "is nan on 1 row(s)", "line 7 of signals.csv", "expected a number on every row"],
    ),
    "identify_structure_same_run_twice": (  # passed the quality gate it failed alone
        ["identify", "structure", "{tmp}/quiet_run", "{tmp}/quiet_run_copy", "--out", "{tmp}/ident"],
        ["quiet_run and", "quiet_run_copy", "the same signals.csv", "expected each run once"],
    ),
    "identify_bearing_incomplete_run": (  # used without a word
        ["identify", "bearing", "{tmp}/incomplete_run", "--out", "{tmp}/ident"],
        ["incomplete_run", "its outcome is 'incomplete'", "expected a run that ended"],
    ),
    "identify_structure_into_earlier_results": (
        ["identify", "structure", "{tmp}/quiet_run", "--out", "{tmp}/earlier_results"],
        ["already holds the results of an earlier identification", "identified.yaml", "--force"],
    ),
    "json_over_a_runs_metadata": (  # then `harness report RUN` exited 2
        ["simulate", "--json", "{tmp}/quiet_run/metadata.json"], ["--json", "is in the run folder", "never overwritten"],
    ),
    "json_over_an_existing_file": (["simulate", "--json", "{tmp}/file.txt"], ["--json", "file.txt exists", "--force"]),
    "overlay_of_dev_zero": (["simulate", "--overlay", "/dev/zero"],
                            ["/dev/zero", "is a character device, not a file", "expected an existing YAML file"]),
    "study_named_dot_dot": (["sweep", "{tmp}/dots_study.yaml"], ["dots_study.yaml", "name: found '..'", "dots only"]),
    "mu_max_above_one": (["simulate", "--set", "bearing.mu_max=2"], ["bearing.mu_max", "found 2", "<= 1"]),
    "sweep_sample_of_mu_max_above_one": (  # read "<= 1 1": a ratio's unit "1" after its bound
        ["sweep", "{tmp}/mu_study.yaml"], ["mu_study.yaml", "monte_carlo", "bearing.mu_max", "expected a value >= 0 and <= 1 ("],
    ),
}

#: Paths of the table that exist on Linux only.
KERNEL_PATHS = ("/proc/", "/sys/", "/dev/")


def _run_folder(parent: Path, name: str, rows: int = 40) -> Path:
    from harness.recording import RunFolder, canonical_columns

    columns = canonical_columns(3)
    run = RunFolder.create(parent, "p", "dry-run", {}, columns)
    run.start()
    for i in range(rows):
        run.record_row([i * 0.002] + [0.0] * (len(columns) - 1))
    run.finish("completed")
    return run.path.rename(parent / name)


@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> Path:
    tmp = tmp_path_factory.mktemp("bad_inputs")
    (tmp / "folder").mkdir()
    (tmp / "typo_overlay.yaml").write_text("bearing:\n  mu_maxx: 0.1\n")
    (tmp / "extends_overlay.yaml").write_text("extends: nceer_4dof.yaml\nbearing:\n  mu_max: 0.1\n")
    (tmp / "weak_overlay.yaml").write_text("safety:\n  comms:\n    error_frame_action: indicate\n")
    (tmp / "file.txt").write_text("not a folder\n")
    (tmp / "binary.dbc").write_bytes(b"\x7fELF\x02\x01\x01\x00\x1b[31m" + bytes(range(256)) * 4)
    (tmp / "no_unit.csv").write_text("t,acc\n" + "".join(f"{i * 0.01:.2f},0.01\n" for i in range(50)))
    (tmp / "huge.csv").write_text(GOOD_HEADER + "".join(f"{i * 0.01:.2f},{'1e308' if i == 5 else '0.01'}\n" for i in range(50)))
    (tmp / "long.csv").write_text(GOOD_HEADER + "".join(f"{i * 0.1:.1f},{0.01 if i % 2 else -0.01}\n" for i in range(7001)))
    _run_folder(tmp, "binary_signals")
    (tmp / "binary_signals" / "signals.csv").write_bytes(bytes(range(128, 256)) * 20)
    _run_folder(tmp, "binary_events")
    (tmp / "binary_events" / "events.jsonl").write_bytes(b"\xff\xfe" + bytes(range(128, 256)) * 4)
    signals = _run_folder(tmp, "truncated_signals") / "signals.csv"
    lines = signals.read_text().splitlines(keepends=True)
    signals.write_text("".join(lines[:21]) + lines[21][:10])  # header, 20 rows and a torn one: half the file
    profile = PROFILES / "nceer_4dof.yaml"
    (tmp / "deep.yaml").write_text(f"extends: {profile}\nname: " + "[" * 500 + "]" * 500 + "\n")
    (tmp / "bomb.yaml").write_text(f"extends: {profile}\n" + ALIAS_BOMB + "name: *l8\n")  # a string field
    (tmp / "recursive.yaml").write_text(f"extends: {profile}\ndescription: &d [1, *d]\n")
    study = f"profile: {profile}\noptions: {{duration_s: 1}}\n"
    (tmp / "deep_study.yaml").write_text(study + "name: " + "[" * 500 + "]" * 500 + "\n")
    (tmp / "bomb_study.yaml").write_text(study + ALIAS_BOMB + "name: *l8\n")
    (tmp / "secret").write_text("root:$6$hash-that-must-not-be-echoed:19000:0:99999:7:::\n")
    (tmp / "secret_study.yaml").write_text(study + f"name: secret\naxes:\n  records: [{tmp / 'secret'}]\n")
    records = ", ".join(f'"synthetic:{seed}"' for seed in range(1, 11))
    (tmp / "huge_study.yaml").write_text(
        study + f"name: huge\naxes:\n  records: [{records}]\n  pga_levels: {{start_g: 0.1, stop_g: 0.4, count: 1000}}\n"
        "monte_carlo:\n  samples: 1000\n  seed: 1\n  set: {bearing.mu_max: {kind: uniform, low: 0.05, high: 0.12}}\n"
    )
    _identification_inputs(tmp)
    return tmp


def _identification_inputs(tmp: Path) -> None:
    """Run folders an identification refuses, and a folder of earlier results (issue 30)."""
    import json
    import shutil

    import numpy as np

    from harness.recording import write_simulation_case

    profile_data = load_profile().resolved_data()
    columns = ("t_s", "base_acceleration_m_s2", *(f"floor_acceleration_{j}_m_s2" for j in (1, 2, 3)))
    rng = np.random.default_rng(1)
    arrays = {"t_s": np.arange(5000) / 500.0, **{name: 0.01 * rng.standard_normal(5000) for name in columns[1:]}}
    quiet = write_simulation_case(tmp, "quiet_run", columns, arrays, {"profile_name": "nceer_4dof"}, profile_data=profile_data)
    shutil.copytree(quiet, tmp / "quiet_run_copy")
    arrays["base_acceleration_m_s2"][5] = np.nan
    write_simulation_case(tmp, "nan_row_run", columns, arrays, {"profile_name": "nceer_4dof"}, profile_data=profile_data)
    incomplete = shutil.copytree(quiet, tmp / "incomplete_run")
    metadata = json.loads((incomplete / "metadata.json").read_text())
    (incomplete / "metadata.json").write_text(json.dumps({**metadata, "outcome": "incomplete"}))
    (tmp / "earlier_results").mkdir()
    for name in ("identified.yaml", "identification.json", "excitation.json"):
        (tmp / "earlier_results" / name).write_text("{}\n")
    (tmp / "dots_study.yaml").write_text(f"profile: {PROFILES / 'nceer_4dof.yaml'}\nname: '..'\noptions: {{duration_s: 1}}\n"
                                         "axes: {records: [synthetic], pga_g: [0.1]}\n")
    (tmp / "mu_study.yaml").write_text(f"profile: {PROFILES / 'nceer_4dof.yaml'}\nname: mu\noptions: {{duration_s: 1}}\n"
                                       "axes: {records: [synthetic], pga_g: [0.1]}\nmonte_carlo: {samples: 2, seed: 1, set: "
                                       "{bearing.mu_max: {kind: uniform, low: 1.2, high: 1.5}}}\n")


def _unchanged_inputs(inputs: Path) -> None:
    """What the rows of issue 30 must leave as it was: the run folder --json named, the earlier results."""
    import json

    assert json.loads((inputs / "quiet_run" / "metadata.json").read_text())["outcome"] == "completed"
    assert sorted(p.name for p in (inputs / "earlier_results").iterdir()) == [
        "excitation.json", "identification.json", "identified.yaml",
    ]
    assert not (inputs / "ident").exists() and not (inputs / "frf").exists()


@pytest.mark.parametrize("case", sorted(BAD_ARGUMENTS))
def test_bad_argument_gives_exit_2_and_names_what_was_expected(inputs, capsys, case):
    argv, expected = BAD_ARGUMENTS[case]
    if any(arg.startswith(KERNEL_PATHS) for arg in argv) and not Path("/proc/self").is_dir():
        pytest.skip("needs Linux's /proc and /sys")
    argv = [arg.replace("{tmp}", str(inputs)) for arg in argv]
    if argv[0] in ("simulate", "dry-run", "rig", "run") and "--duration" not in argv and case != "too_long_record":
        argv += ["--duration", "1"]
    if argv[0] in ("dry-run", "run") and "--log-dir" not in argv:
        argv += ["--log-dir", str(inputs / "logs")]
    if argv[0] == "sweep":
        argv += ["--out", str(inputs / "sweep_results"), "--quiet"]
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # a numpy overflow warning would leak to the terminal
        status = main(argv)
    out, err = capsys.readouterr()
    assert status == exit_codes.INPUT_ERROR, f"{argv}: status {status}\n{out}\n{err}"
    message = " ".join(err.split())  # rich wraps long messages
    for text in expected:
        assert text in message, f"{text!r} not in {message!r}"
    assert "Traceback" not in out + err
    assert all(ch.isprintable() or ch in "\n\t" for ch in err), "raw bytes echoed to the terminal"
    assert len(err) < 4000, "the message quotes too much of what it refused"
    assert not (inputs / "logs").exists() or not any((inputs / "logs").iterdir()), "a run folder was made"
    assert not (inputs / "sweep_results").exists(), "a sweep results folder was made"
    assert (inputs / "file.txt").read_text() == "not a folder\n"
    _unchanged_inputs(inputs)


def test_the_old_misleading_messages_are_gone(inputs, capsys):
    main(["dry-run", "--rate", "-500", "--duration", "1"])
    assert "physics sub-step" not in capsys.readouterr().err
    main(["simulate", "--record", str(inputs / "no_unit.csv"), "--duration", "1"])
    assert "--accel-unit" not in capsys.readouterr().err  # no such flag exists
    main(["simulate", "--record", str(inputs / "huge.csv"), "--duration", "1"])
    assert "inf g" not in capsys.readouterr().err
    main(["simulate", "--set", "bearing.mu_max=2", "--duration", "1"])
    assert "<= 1 1" not in capsys.readouterr().err  # a ratio's unit "1" was printed after its bound
    if Path("/dev/zero").exists():
        main(["simulate", "--overlay", "/dev/zero", "--duration", "1"])
        assert "not found" not in capsys.readouterr().err  # it exists: it is no regular file


def test_every_numeric_option_is_range_checked():
    """No option of any command takes a bare float or int: each goes through a range with its unit."""
    import argparse

    from harness.cli import build_parser

    parser = build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices
    for name, command in commands.items():
        for action in command._actions:
            assert action.type not in (float, int), f"harness {name} {action.option_strings}: unchecked number"


def test_the_cli_bounds_match_the_profile_schema():
    from dataclasses import fields

    from harness.config import input_limits
    from harness.control.config import ControlConfig

    rate = next(f for f in fields(ControlConfig) if f.name == "rate_hz")
    assert rate.metadata["le"] == input_limits.MAX_RATE_HZ
