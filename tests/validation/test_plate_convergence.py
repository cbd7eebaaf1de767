"""Quick run of the thin-plate element convergence study (benchmarks/plate_convergence.py).

Runs ``--quick --json`` (one coarse case per element family, clamped and simply supported
quarter plate, a few seconds) and checks the two claims docs/structures_convergence.md
relies on: HRZ lumping gives strictly positive masses for the quadratic elements (row-sum
lumping does not), and the recommended element (serendipity hexes ElementHexS2, one layer
through the 12 mm thickness, 25 mm in-plane) meets the tolerances against thin-plate theory.
"""

import json
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "plate_convergence.py"

# Recommended element of docs/structures_convergence.md and its tolerances.
RECOMMENDED = ("HexS2", 1, 25.0)
TOL_F1 = 0.03
TOL_W = 0.05


@pytest.fixture(scope="module")
def quick_rows() -> list[dict]:
    out = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick", "--json"],
        check=True,
        capture_output=True,
        text=True,
        timeout=120,
    )
    return json.loads(out.stdout)["cases"]


@pytest.mark.slow
def test_quick_covers_every_family(quick_rows):
    families = {r["family"] for r in quick_rows}
    assert families == {"TetP1", "TetP2", "Hex1", "HexS2", "Hex2"}
    assert {r["support"] for r in quick_rows} == {"clamped", "simply_supported"}


def test_hrz_lumped_masses_positive_for_quadratic_elements(quick_rows):
    """HRZ (m_ii = M_ii m_e / sum_j M_jj) is positive; row-sum lumping of TetP2/HexS2 is not."""
    for r in quick_rows:
        if r["family"] in ("TetP2", "HexS2", "Hex2"):
            assert r["min_hrz_mass"] > 0.0, r
    rowsum = {r["family"]: r["min_rowsum_mass"] for r in quick_rows}
    assert rowsum["TetP2"] < 0.0 and rowsum["HexS2"] < 0.0


@pytest.mark.parametrize("support", ["clamped", "simply_supported"])
def test_recommended_element_meets_plate_theory(quick_rows, support):
    """HexS2, 1 layer, 25 mm against thin-plate theory, D = E h^3 / (12 (1 - nu^2)).

    a = 1 m, h = 12 mm, E = 210 GPa, nu = 0.3, rho = 7850 kg/m3, q = 10 kPa:
    f1 = lambda / (2 pi a^2) sqrt(D / (rho h)) = 107.57 Hz clamped (lambda = 35.985, Leissa
    1969, NASA SP-160) and 59.01 Hz simply supported (lambda = 2 pi^2); centre deflection
    w = c q a^4 / D = 0.379 mm clamped (c = 0.00126) and 1.222 mm simply supported
    (c = 0.00406, Timoshenko & Woinowsky-Krieger 1959).  Tolerances: f1 within 3 %
    (consistent and HRZ-lumped mass), w within 5 %.
    """
    family, layers, size = RECOMMENDED
    (row,) = [
        r
        for r in quick_rows
        if (r["family"], r["layers"], r["size_mm"], r["support"]) == (family, layers, size, support)
    ]
    assert abs(row["err_f1_cons"]) < TOL_F1
    assert abs(row["err_f1_hrz"]) < TOL_F1
    assert abs(row["err_w"]) < TOL_W
    # first-order elements lock: far outside the tolerance at the same size
    (hex1,) = [r for r in quick_rows if r["family"] == "Hex1" and r["support"] == support]
    assert hex1["err_f1_cons"] > 0.2
