"""The study file of ``harness sweep``: validated like a profile, expanded into keyed cases."""

from __future__ import annotations

import re
import textwrap
from pathlib import Path

import numpy as np
import pytest

from harness.errors import ProfileError
from harness.sweep import cases as study_cases
from harness.sweep.cases import case_count, expand
from harness.sweep.distributions import LogNormal, Normal, Uniform, draw, unit_samples
from harness.sweep.study import MAX_CASES, load_study
from tests.conftest import PROFILES

BASE = f"""\
name: small
profile: {PROFILES / "eight_story.yaml"}
options: {{duration_s: 2}}
axes:
  records: ["synthetic:1", "synthetic:2"]
  pga_g: [0.1, 0.2]
  controllers: [FSF-I, OF-I]
  set: {{control.design_stiffness_scale: [0.7, 1.3]}}
monte_carlo:
  samples: 3
  seed: 7
  set: {{bearing.mu_max: {{kind: uniform, low: 0.05, high: 0.12}}}}
  scale: {{structure.story_stiffness_N_per_m: {{kind: normal, mean: 1.0, std: 0.1, low: 0.7, high: 1.3}}}}
"""


def _study_file(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "study.yaml"
    path.write_text(textwrap.dedent(text))
    return path


def _refused(tmp_path: Path, text: str) -> ProfileError:
    path = _study_file(tmp_path, text)
    with pytest.raises(ProfileError) as caught:
        expand(load_study(path))
    assert caught.value.source is not None and Path(caught.value.source).name == "study.yaml"
    return caught.value


def test_a_study_expands_into_the_product_of_its_axes(tmp_path):
    cases = expand(load_study(_study_file(tmp_path, BASE)))
    assert len(cases) == 2 * 2 * 2 * 2 * 3
    assert len({case.key for case in cases}) == len(cases), "every case has its own key"
    first = cases[0]
    assert first.record.label == "synthetic:1" and first.pga_g == 0.1 and first.controller == "FSF-I"
    inputs = dict(first.inputs)
    assert inputs["control.design_stiffness_scale"] == 0.7 and inputs["sample"] == 0
    assert 0.05 <= inputs["bearing.mu_max"] <= 0.12 and 0.7 <= inputs["scale:structure.story_stiffness_N_per_m"] <= 1.3
    assert dict(first.options) == {"duration_s": 2.0}


def test_the_count_from_the_axes_is_the_number_of_cases_expanded(tmp_path):
    folder = tmp_path / "records"
    folder.mkdir()
    for k, name in enumerate(("a.csv", "notes.md")):  # a record file; the notes are not a record
        (folder / name).write_text("t_s,accel_g\n" + "".join(f"{i * 0.01:.2f},{0.01 * k * (-1) ** i}\n" for i in range(50)))
    at2 = "PEER\nb\nACCELERATION TIME SERIES IN UNITS OF G\nNPTS=   50, DT=  .0100 SEC\n"
    (folder / "b.AT2").write_text(at2 + "".join(f"{0.02 * (-1) ** i}\n" for i in range(50)))  # suffix in any case
    text = BASE.replace('records: ["synthetic:1", "synthetic:2"]', 'records: ["synthetic:1", records]')
    text = text.replace("set: {control.design_stiffness_scale: [0.7, 1.3]}",
                        "set: {control.design_stiffness_scale: [0.7, 1.3]}\n  scale: {bearing.mu_delta: [0.9, 1.0, 1.1]}")
    study = load_study(_study_file(tmp_path, text))
    count = case_count(study)
    assert (count.records, count.pga_levels, count.controllers, count.grid_points, count.samples) == (3, 2, 2, 6, 3)
    assert count.total == len(expand(study)) == 216
    assert count.describe() == "3 records x 2 PGA levels x 2 controllers x 6 grid points x 3 samples"


def test_a_study_beyond_the_case_limit_is_refused_from_its_axes_before_any_case_is_built(tmp_path, monkeypatch):
    """--plan on 10^7 cases printed nothing for 120 s and grew past 2.3 GB: the axes were capped one by one only."""
    def never(*args):
        raise AssertionError("a case was built before the count was checked")

    for name in ("grid_points", "sample_points", "_records", "case_key"):
        monkeypatch.setattr(study_cases, name, never)
    huge = BASE.replace("pga_g: [0.1, 0.2]", "pga_levels: {start_g: 0.1, stop_g: 1.0, count: 1000}")
    huge = huge.replace("samples: 3", "samples: 5000")  # 2 x 1000 x 2 x 2 x 5000 = 4e7 cases
    with pytest.raises(ProfileError) as caught:
        expand(load_study(_study_file(tmp_path, huge)))
    assert caught.value.key_path == "axes"
    assert (f"the study has 40000000 cases (2 records x 1000 PGA levels x 2 controllers x 2 grid points x 5000 samples), "
            f"expected at most {MAX_CASES} (MAX_CASES)") in caught.value.detail
    at_limit = huge.replace("samples: 5000", f"samples: {MAX_CASES // 8000}")  # 8000 x 12 = 96,000
    assert case_count(load_study(_study_file(tmp_path, at_limit))).total <= MAX_CASES


def test_keys_depend_on_the_inputs_only(tmp_path):
    once = [case.key for case in expand(load_study(_study_file(tmp_path, BASE)))]
    again = [case.key for case in expand(load_study(_study_file(tmp_path, BASE)))]
    assert once == again
    other_seed = [case.key for case in expand(load_study(_study_file(tmp_path, BASE.replace("seed: 7", "seed: 8"))))]
    assert not set(once) & set(other_seed)
    longer = [case.key for case in expand(load_study(_study_file(tmp_path, BASE.replace("duration_s: 2", "duration_s: 3"))))]
    assert not set(once) & set(longer)


def test_pga_levels_give_an_evenly_spaced_range(tmp_path):
    text = BASE.replace("pga_g: [0.1, 0.2]", "pga_levels: {start_g: 0.1, stop_g: 0.4, count: 4}")
    cases = expand(load_study(_study_file(tmp_path, text)))
    assert sorted({case.pga_g for case in cases}) == [0.1, 0.2, 0.3, 0.4]


@pytest.mark.parametrize(
    ("change", "key", "message"),
    [
        (("  pga_g: [0.1, 0.2]", "  pga_g: [0.1, 0.2]\n  pga: [0.3]"), "axes.pga",
         r"unknown key 'pga' \(did you mean pga_g, pga_levels\?\)"),
        (("  pga_g: [0.1, 0.2]", "  pga_g: [0.1, 20]"), r"axes.pga_g[1]", r"found 20, expected a value > 0 and <= 10 g"),
        (("  pga_g: [0.1, 0.2]", '  pga_g: ["0.1 m"]'), r"axes.pga_g[0]", r"found '0.1 m'"),
        (("duration_s: 2", "duration_s: -1"), "options.duration_s", r"found -1, expected a value > 0"),
        (("samples: 3", "samples: 0"), "monte_carlo.samples", r"found 0, expected a value >= 1"),
        (("kind: uniform", "kind: triangular"), "monte_carlo.set.bearing.mu_max",
         r"found kind 'triangular', expected kind one of"),
        (("low: 0.05, high: 0.12", "low: 0.12, high: 0.05"), "monte_carlo.set.bearing.mu_max", r"expected low < high"),
    ],
)
def test_the_schema_refuses_with_file_key_found_and_expected(tmp_path, change, key, message):
    err = _refused(tmp_path, BASE.replace(*change))
    assert err.key_path == key
    assert re.search(message, err.detail), err.detail


@pytest.mark.parametrize(
    ("change", "key", "message"),
    [
        (("control.design_stiffness_scale: [0.7, 1.3]", "bearing.mu_delta: [0.01, -0.2]"), "axes.set.bearing.mu_delta[1]",
         r"^found -0.2, expected a value >= 0 .*\(bearing.mu_delta of eight_story.yaml\)"),
        (("control.design_stiffness_scale: [0.7, 1.3]", "bearing.mu_max: [0.1]"), "monte_carlo",
         r"bearing.mu_max is also a grid axis"),
        (("control.design_stiffness_scale: [0.7, 1.3]", "bearing.a_mu_s_per_m: ['3 kg']"), "axes.set.bearing.a_mu_s_per_m[0]",
         r"found '3 kg'"),
        (("control.design_stiffness_scale: [0.7, 1.3]", "bearing.mu_maximum: [0.1]"), "axes.set.bearing.mu_maximum[0]",
         r"unknown key 'mu_maximum'"),
        (("controllers: [FSF-I, OF-I]", "controllers: [FSF-I, LQG]"), "axes.controllers[1]",
         r"found 'LQG', expected a design of the profile \(FSF-I, FSF-II, OF-I, OF-II\) or 'none'"),
        (('records: ["synthetic:1", "synthetic:2"]', 'records: ["synthetic:1", "no_such_record"]'), "axes.records[1]",
         r"found 'no_such_record': record 'no_such_record' not found"),
        (("low: 0.7, high: 1.3", "low: -1.0, high: 1.3"), "monte_carlo",
         r"sample \d+ \(.*scale:structure.story_stiffness_N_per_m = -?[\d.]+.*expected a value > 0"),
        (("control.design_stiffness_scale: [0.7, 1.3]", "control.design_stiffness_scale: [0.7, 0.7]"), "axes",
         r"same inputs"),
    ],
)
def test_values_the_profile_refuses_are_refused_at_the_study_key(tmp_path, change, key, message):
    text = BASE.replace(*change)
    if "low: -1.0" in text:
        text = text.replace("mean: 1.0, std: 0.1", "mean: 0.0, std: 1.0")
    err = _refused(tmp_path, text)
    assert err.key_path == key
    assert re.search(message, err.detail), err.detail


def test_a_missing_or_broken_file_is_refused(tmp_path):
    with pytest.raises(ProfileError, match="study file not found"):
        load_study(tmp_path / "absent.yaml")
    path = _study_file(tmp_path, "name: x\nname: y\nprofile: p.yaml\n")
    with pytest.raises(ProfileError, match="duplicate key 'name'"):
        load_study(path)


def test_latin_hypercube_samples_fill_every_stratum():
    points = unit_samples(10, 2, seed=3, sampling="latin_hypercube")
    for column in points.T:
        assert sorted(np.floor(column * 10).astype(int)) == list(range(10))
    assert np.array_equal(points, unit_samples(10, 2, seed=3, sampling="latin_hypercube"))


def test_distributions_map_probabilities_to_values():
    values = draw([Uniform("uniform", 0.05, 0.12), Normal("normal", 1.0, 0.1, 0.8, 1.2), LogNormal("lognormal", 2.0, 0.3)],
                  2000, seed=1, sampling="random")
    assert values.shape == (2000, 3)
    assert values[:, 0].min() >= 0.05 and values[:, 0].max() <= 0.12
    assert values[:, 1].min() >= 0.8 and values[:, 1].max() <= 1.2
    assert abs(np.mean(values[:, 1]) - 1.0) < 0.01
    assert abs(np.median(values[:, 2]) - 2.0) < 0.1


def test_white_noise_is_a_record_of_a_study_named_by_its_whole_spec(tmp_path):
    text = BASE.replace('records: ["synthetic:1", "synthetic:2"]', 'records: ["white_noise:0.5-20", "white_noise:1-10:0.05"]')
    study = load_study(_study_file(tmp_path, text))
    cases = expand(study)
    assert case_count(study).total == len(cases)
    labels = sorted({case.record.label for case in cases})
    assert labels == ["white_noise:0.5-20", "white_noise:1-10:0.05"]
    digests = {case.record.label: case.record.digest for case in cases}
    assert digests["white_noise:0.5-20"] == "white_noise:0.5-20:0.1"  # the amplitude spelled out: another default, another case
    bad = BASE.replace('records: ["synthetic:1", "synthetic:2"]', 'records: ["white_noise:20-5"]')
    assert "axes.records[0]" in str(_refused(tmp_path, bad))


SECRET_LINE = "root:$6$very-secret-hash-that-must-not-leak-into-results:19000:0:99999:7:::"


def test_a_record_path_naming_a_file_that_is_not_a_record_is_refused(tmp_path):
    secret = tmp_path / "shadow"
    secret.write_text(SECRET_LINE + "\n")
    err = _refused(tmp_path, BASE.replace('records: ["synthetic:1", "synthetic:2"]', f'records: ["synthetic:1", "{secret}"]'))
    assert err.key_path == "axes.records[1]"
    assert "is not a record file" in err.detail and "secret" not in err.detail.replace(str(secret), "")


def test_a_record_file_that_does_not_parse_is_refused_quoting_only_a_short_escaped_excerpt(tmp_path):
    secret = tmp_path / "notes.txt"
    secret.write_text(SECRET_LINE + "\u202e\n" + "more private text\n" * 3)  # a right-to-left override in it
    err = _refused(tmp_path, BASE.replace('records: ["synthetic:1", "synthetic:2"]', f'records: ["synthetic:1", "{secret}"]'))
    assert err.key_path == "axes.records[1]" and "is not a ground-motion record the loader reads" in err.detail
    quoted = err.detail.replace(str(secret), "")
    assert "must-not-leak" not in quoted and "\u202e" not in quoted, "at most a short, escaped excerpt of the file"
    assert "more characters)" in quoted


def test_the_loader_quotes_a_file_escaped_and_cut():
    from harness.motions.loaders import EXCERPT_CHARS, excerpt

    assert excerpt("a\u202eb\x1b") == "'a\\u202eb\\x1b'"
    long = "x" * (EXCERPT_CHARS + 10)
    assert excerpt(long) == f"'{'x' * EXCERPT_CHARS}'... (10 more characters)"
