"""The one list of safety checks (harness/safety/checks.py): nothing added in one place only, no bit moved.

The supervisor's detectors, the bit order of :data:`CHECK_NAMES` and the safety table are all
built from :data:`CHECKS`; these tests fail when a check class exists outside the list, when a
recorded bit would change meaning, or when the list and the supervisor's fixed stages disagree.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import pkgutil

import pytest

import harness.safety
from harness.safety.checks import CHECK_NAMES, CHECKS, Check, _in_bit_order, bit, build_detectors, names_of
from harness.safety.checks_doc import SAFETY_TABLE
from harness.safety.config import SafetyConfig
from harness.safety.detector_base import Detector
from harness.safety.events import Action
from harness.safety.interlocks import ForceClamp, ForceRateLimit, StrokeHardLimit, StrokePredictiveLimit, StrokeSoftFade
from harness.safety.supervisor import Supervisor
from harness.safety.supervisor_checks import ControllerOutput, LoopTiming, StopRamp, TickException
from harness.safety.table_record import TableRecordCheck
from tests.conftest import REPO

#: The bits as recorded in runs and the status block since they were given (append only: a new
#: check goes after these, with the next bit; none of these may move or go).
RECORDED_BITS = (
    "force_clamp", "force_rate", "stroke_soft", "stroke_hard", "stroke_predictive", "sensor_invalid",
    "sensor_stale", "sensor_jump", "sensor_stuck", "sensor_disagree", "e2e_rejects", "bus_error_frames",
    "bus_error_passive", "bus_off", "bus_send_failures", "bus_gone", "foreign_command", "drive_fault",
    "hydraulic_pressure", "actuator_status_stale", "force_tracking", "loop_stall", "loop_timing", "tick_exception",
    "controller_output", "estop", "operator_stop", "operator_trip", "stop_ramp", "sensor_sign_flip", "estop_lost",
    "table_record_mismatch", "table_record_marginal", "compensation_fault", "force_oscillation", "load_cell_limit",
    "sensor_polarity",
)


def _safety_classes() -> set[type]:
    """Every class defined in a module of harness.safety that names a check (a non-empty ``NAME``)."""
    found = set()
    for info in pkgutil.iter_modules(harness.safety.__path__):
        module = importlib.import_module(f"harness.safety.{info.name}")
        for _, cls in inspect.getmembers(module, inspect.isclass):
            if cls.__module__ == module.__name__ and isinstance(getattr(cls, "NAME", None), str) and cls.NAME:
                found.add(cls)
    return found


def _detector_subclasses(base: type = Detector) -> set[type]:
    return {sub for cls in base.__subclasses__() for sub in {cls, *_detector_subclasses(cls)}}


def test_recorded_bits_keep_their_meaning() -> None:
    assert CHECK_NAMES[: len(RECORDED_BITS)] == RECORDED_BITS
    assert bit("force_clamp") == 1 and bit("stroke_soft") == 4 and bit("table_record_marginal") == 1 << 32


def test_bit_numbers_run_from_zero_without_gap_or_repeat() -> None:
    assert sorted(check.bit_number for check in CHECKS) == list(range(len(CHECKS)))
    assert len(CHECK_NAMES) == len(CHECKS) == len(set(CHECK_NAMES))
    assert names_of(bit("estop") | bit("force_rate")) == ("force_rate", "estop")


def test_a_gap_or_a_repeat_in_the_bits_is_refused_at_import() -> None:
    with pytest.raises(RuntimeError, match="expected each of 0..1 once"):
        _in_bit_order((Check(0, ForceClamp), Check(2, ForceRateLimit)))
    with pytest.raises(RuntimeError, match="expected each of 0..1 once"):
        _in_bit_order((Check(0, ForceClamp), Check(0, ForceRateLimit)))
    with pytest.raises(RuntimeError, match="names repeat"):
        _in_bit_order((Check(0, ForceClamp), Check(1, ForceClamp)))


def test_every_check_class_of_the_safety_package_is_in_the_list_once() -> None:
    kinds = [check.kind for check in CHECKS]
    assert len(kinds) == len(set(kinds))
    outside = {cls.__name__ for cls in _safety_classes()} - {kind.__name__ for kind in kinds}
    assert not outside, f"check classes missing from harness/safety/checks.py CHECKS: {sorted(outside)}"
    named_detectors = {cls for cls in _detector_subclasses() if cls.NAME}
    assert named_detectors <= set(kinds), f"detectors outside CHECKS: {named_detectors - set(kinds)}"


def test_every_check_documents_itself() -> None:
    for check in CHECKS:
        kind = check.kind
        assert isinstance(kind.ACTION, Action), kind
        for text in (kind.NAME, kind.DETECTS, kind.BOUND, kind.RESET):
            assert isinstance(text, str) and text.strip(), f"{kind.__name__}: an empty documentation attribute"
        assert "Detects:" not in (kind.__doc__ or ""), f"{kind.__name__}: the docstring repeats DETECTS"


def test_detectors_are_built_by_their_entry_and_a_check_the_supervisor_performs_has_no_builder() -> None:
    built = build_detectors(SafetyConfig(), TableRecordCheck(0.02))
    detector_checks = [check for check in CHECKS if check.build is not None]
    assert [type(d) for d in built] == [check.kind for check in detector_checks]
    for check in CHECKS:
        assert (check.build is not None) == issubclass(check.kind, Detector), check.name


def test_the_supervisor_runs_the_lists_detectors_in_its_order() -> None:
    supervisor = Supervisor(SafetyConfig())
    assert [d.NAME for d in supervisor.detectors] == [check.name for check in CHECKS if check.build is not None]
    assert supervisor.detectors[0].NAME == "estop"
    assert [supervisor._slots[k] for k in range(len(supervisor.detectors))] == [
        CHECK_NAMES.index(d.NAME) for d in supervisor.detectors
    ]


def test_the_list_places_the_supervisors_own_stages_where_its_code_runs_them() -> None:
    own = [check.kind for check in CHECKS if check.build is None]
    assert own == [
        LoopTiming, ControllerOutput, StrokeHardLimit, StrokePredictiveLimit, ForceClamp, StopRamp, ForceRateLimit,
        StrokeSoftFade, TickException,
    ]
    positions = [k for k, check in enumerate(CHECKS) if check.build is not None]
    assert positions == list(range(1, 1 + len(positions))), "the detectors run as one block, right after loop_timing"


def test_every_check_the_supervisor_performs_itself_is_named_in_its_code() -> None:
    tree = ast.parse((REPO / "harness" / "safety" / "supervisor.py").read_text())
    names = {node.id for node in ast.walk(tree) if isinstance(node, ast.Name)}
    missing = [check.kind.__name__ for check in CHECKS if check.build is None and check.kind.__name__ not in names]
    assert not missing, f"checks in CHECKS that the supervisor never performs: {missing}"


def test_the_safety_table_follows_the_bits() -> None:
    assert tuple(record.name for record in SAFETY_TABLE) == CHECK_NAMES
    by_name = {record.name: record for record in SAFETY_TABLE}
    assert by_name["bus_error_frames"].action == "safe_stop" and by_name["stop_ramp"].bound == "stopping_ramp_s"
