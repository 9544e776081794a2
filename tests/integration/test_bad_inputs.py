"""Bad input files through the real command line: one clear error, exit status 2, never a traceback.

The profiles come from tests/unit/test_profile.py (each kind of bad profile); the records
are malformed accelerograms written here. Each goes through ``harness simulate`` (and the
profiles also through ``harness dry-run``) in-process: an exception escaping ``main``
would fail the test, so status 2 proves the error was handled and reported.
"""

from __future__ import annotations

import pytest

from harness import exit_codes
from harness.cli import main
from tests.unit.test_profile import BAD_PROFILES

GOOD_HEADER = "t_s,accel_g\n"
BAD_RECORDS = {
    "empty.csv": (b"", "empty"),
    "binary.csv": (bytes(range(256)) * 8, ""),
    "header_only.csv": (GOOD_HEADER.encode(), ""),
    "no_unit.csv": (b"t,acc\n" + b"".join(f"{i * 0.01:.2f},0.01\n".encode() for i in range(50)), "unit"),
    "text_value.csv": ((GOOD_HEADER + "".join(f"{i * 0.01:.2f},{'abc' if i == 7 else '0.01'}\n" for i in range(50))).encode(), ".csv:9:"),
    "nan_value.csv": ((GOOD_HEADER + "".join(f"{i * 0.01:.2f},{'nan' if i == 9 else '0.01'}\n" for i in range(50))).encode(), ""),
    "non_uniform.csv": ((GOOD_HEADER + "".join(f"{i * 0.01 + (0.004 if i == 20 else 0):.3f},0.01\n" for i in range(50))).encode(), ""),
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
    status = main([command, str(path), "--duration", "1", "--quiet", *(["--log-dir", str(tmp_path)] if command == "dry-run" else [])])
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
