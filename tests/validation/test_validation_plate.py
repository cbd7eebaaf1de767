"""The plate and panel validation entries of ``pdfem validate`` in their ``--quick`` form:
clamped and simply supported square steel plates (first frequency vs Leissa, NASA SP-160,
1969; centre deflection vs Timoshenko & Woinowsky-Krieger, 1959) and the demo hull panel's
first five frequencies vs the same panel meshed twice as fine."""

from __future__ import annotations

import pytest

import math
import tomllib
from pathlib import Path


from pdfem.validation import all_cases, run_validation
from pdfem.validation.case import load_validation_case
from pdfem.validation.cases import plate

ROOT = Path(__file__).resolve().parents[2]
PLATE_CASES = ["plate_clamped_frequency", "plate_clamped_deflection",
               "plate_simply_supported_frequency", "plate_simply_supported_deflection"]


def test_plate_references_are_the_published_numbers():
    """1 m x 12 mm steel: D = 33 231 N m; f1 = 107.57 Hz clamped, 59.006 Hz simply supported
    (Leissa 1969); w = 0.3792 mm and 1.2218 mm under 10 kPa (Timoshenko & Woinowsky-Krieger
    1959)."""
    clamped = load_validation_case("plate_clamped.toml")
    ss = load_validation_case("plate_simply_supported.toml")
    a, h, d = plate.plate(clamped)
    assert (a, h) == (1.0, 0.012) and math.isclose(d, 33231.0, rel_tol=1e-4)
    assert math.isclose(plate.reference_f1("clamped", clamped), 107.57, rel_tol=1e-4)
    assert math.isclose(plate.reference_f1("simply_supported", ss), 59.006, rel_tol=1e-4)
    assert math.isclose(plate.reference_w("clamped", clamped), 0.3792e-3, rel_tol=1e-3)
    assert math.isclose(plate.reference_w("simply_supported", ss), 1.2218e-3, rel_tol=1e-3)


def test_plate_and_panel_cases_are_registered():
    names = {c.name for c in all_cases()}
    assert set(PLATE_CASES) | {"panel_modes"} <= names
    for c in all_cases():
        if c.name in PLATE_CASES:
            assert c.tolerance == (0.03 if c.name.endswith("frequency") else 0.05)


def test_quick_plate_cases_pass(tmp_path):
    """The quick plates (50 mm one-layer elements) are within 3 % (f1) and 5 % (w)."""
    cases = [c for c in all_cases() if c.name in PLATE_CASES]
    results = run_validation(cases, tmp_path, quick=True)
    failed = {r.name: (r.value, r.reference, r.error, r.message) for r in results if not r.passed}
    assert not failed, failed


@pytest.mark.slow
def test_quick_panel_modes_pass(tmp_path):
    """The demo panel (0.08 m) against the panel meshed at 0.04 m: the first five frequencies
    agree within 5 % (the quick variant is the full check, about a minute)."""
    cases = [c for c in all_cases() if c.name == "panel_modes"]
    (r,) = run_validation(cases, tmp_path, quick=True)
    assert r.passed, (r.value, r.message)


def test_panel_modes_case_is_the_demo_panel():
    """panel_modes.toml checks the demo's panel: the same model, parameters, material and
    supports as the structure 'panel' of demo_ice_sheet_panel.toml."""
    demo = tomllib.loads((ROOT / "models" / "demo_ice_sheet_panel.toml").read_text())
    case = tomllib.loads((ROOT / "models" / "validation" / "panel_modes.toml").read_text())
    keys = ("name", "kind", "mesh", "params", "material", "fixed_groups", "supports",
            "element_order")
    (panel,) = [s for s in demo["structure"] if s["name"] == "panel"]
    assert {k: panel.get(k) for k in keys} == {k: case["structure"][0].get(k) for k in keys}
