"""``pdfem validate``: every quick validation case passes against its reference; the JSON,
table and markdown reports; exit status 1 when a case fails.

The quick run is the whole validation suite in its ``--quick`` variant (about a minute on two
cores once numba has compiled); the references and tolerances are those of
``pdfem/validation/cases/``.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from pdfem.cli.main import main
from pdfem.validation import ValidationCase, all_cases, run_validation
from pdfem.validation.case import case_path

ROOT = Path(__file__).resolve().parents[2]


LONG = {"icebreaking_resistance", "icebreaking_pieces_under_hull", "floating_plate_winkler",
        "floating_plate_winkler_length"}
"""Cases whose ``--quick`` run alone takes minutes (the towed icebreaker: 27,000 steps; the
Winkler plate: 48,600 particles, nothing smaller passes); their measures are checked in
tests/validation/test_icebreaking.py (a constructed run) and tests/validation/test_winkler.py (the coarse plate
against its lattice plate)."""


ELSEWHERE = {"flexural_strength_three_point", "flexural_strength_four_point",
             "flexural_strength_three_point_half_dx", "flexural_strength_four_point_half_dx",
             "panel_modes", "plate_clamped_frequency", "plate_clamped_deflection",
             "plate_simply_supported_frequency", "plate_simply_supported_deflection",
             "floating_draught", "floating_heave_period", "step_energy_residual",
             "step_dissipation_sign", "step_load_convergence", "milling_torque_spectrum",
             "cantilever_frequency", "cantilever_frequency_implicit",
             "cantilever_frequency_implicit_large_step", "bar_root_stress_tension",
             "bar_root_stress_compression", "propeller_root_stress"}
"""Cases whose ``--quick`` run has its own test (tests/pd/test_strength.py, test_validation_plate.py,
test_water.py, test_step_sweep.py, test_propeller.py, test_cantilever.py, test_root_stress.py):
run once, there, beside the others."""


@pytest.mark.slow
def test_quick_validation_passes(capfd):
    """``pdfem validate --quick --json`` on every case but :data:`LONG` and :data:`ELSEWHERE`:
    exactly one JSON object on stdout (checked at the file descriptor, so nothing from gmsh or
    numba either), at least 8 cases, every one passing within its tolerance, exit status 0."""
    names = [c.name for c in all_cases() if c.name not in LONG | ELSEWHERE]
    assert LONG | ELSEWHERE <= {c.name for c in all_cases()}
    status = main(["validate", "--quick", "--json"] + [a for n in names for a in ("--case", n)])
    out = capfd.readouterr().out
    report = json.loads(out)  # nothing but the one object on stdout
    failed = {r["name"]: (r["value"], r["reference"], r["error"], r["message"])
              for r in report["results"] if not r["passed"]}
    assert not failed, failed
    assert status == 0 and report["passed"] and report["quick"]
    assert report["cases"] == len(report["results"]) >= 8
    names = {r["name"] for r in report["results"]}
    assert {"wave_speed", "youngs_modulus", "poisson_ratio",
            "impact_momentum", "impact_energy", "pair_vs_full_family", "wall_contact_duration",
            "wall_contact_force", "panel_reaction"} <= names
    for r in report["results"]:
        assert r["error"] <= r["tolerance"] and r["source"] and r["quick_note"]


def test_report_writes_markdown_and_plots(tmp_path, capsys):
    """``--report DIR`` writes DIR/validation.md with the table and one PNG per case, and the
    table goes to stdout (a cheap subset of the cases via ``--case``)."""
    names = ["wave_speed", "impact_momentum", "impact_energy"]
    args = ["validate", "--quick", "--report", str(tmp_path / "report")]
    for n in names:
        args += ["--case", n]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "3 of 3 quick validation cases pass" in out
    assert all(n in out for n in names)
    md = (tmp_path / "report" / "validation.md").read_text()
    assert "| case | quantity | pdfem | reference | unit | error | tolerance | pass |" in md
    for n in names:
        png = tmp_path / "report" / f"{n}.png"
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert f"![{n}]({n}.png)" in md
    assert (tmp_path / "report" / "runs").is_dir()


def test_a_failing_case_fails_the_command(monkeypatch, capsys, tmp_path):
    """A case outside its tolerance, or one whose run raises, fails (exit status 1) without
    stopping the others; the JSON names the failed cases."""
    def fake(name, value, execute=lambda case, directory: {}):
        return ValidationCase(name=name, case_file="cantilever_frequency.toml", quantity="q",
                              unit="-", measure=lambda outcome: value, reference=lambda case: 1.0,
                              source="none", tolerance=0.01, quick_note="-", execute=execute)

    def broken(case, directory):
        raise RuntimeError("no run")

    cases = (fake("good", 1.001), fake("bad", 1.5), fake("crashed", 1.0, broken))
    monkeypatch.setattr("pdfem.validation.all_cases", lambda: cases)
    assert main(["validate", "--json"]) == 1
    report = json.loads(capsys.readouterr().out)
    assert report["failed"] == ["bad", "crashed"] and not report["passed"]
    by_name = {r["name"]: r for r in report["results"]}
    assert by_name["bad"]["error"] == pytest.approx(0.5)
    assert "RuntimeError: no run" in by_name["crashed"]["message"]
    results = run_validation(cases[:2], tmp_path)
    assert [r.passed for r in results] == [True, False]


def test_cases_are_registered_and_shipped():
    """Every registered case has a unique name, a cited reference, a positive tolerance and a
    case file in models/validation/ that the package finds (package data of pdfem.models)."""
    cases = all_cases()
    assert len({c.name for c in cases}) == len(cases) >= 8
    for c in cases:
        assert c.tolerance > 0 and c.source and c.unit
        assert (ROOT / "models" / "validation" / c.case_file).is_file()
        with case_path(c.case_file) as p:
            assert p.is_file()


def test_unknown_case_is_bad_input(capsys):
    assert main(["validate", "--case", "no_such_case"]) == 2
    assert "wave_speed" in capsys.readouterr().err
