"""Thin square steel plates, clamped and simply supported: first natural frequency and centre
deflection under uniform pressure against classical plate theory (``plate_clamped.toml``,
``plate_simply_supported.toml``).

The case files model a quarter of the square plate of side a = 1 m and thickness h = 12 mm,
``[0, a/2]^2 x [-h/2, h/2]`` (``models/validation/box.py``), with symmetry planes at x = a/2
(u_x = 0) and y = a/2 (u_y = 0): the first mode and the uniform load are doubly symmetric, so
both quantities are those of the whole plate. One layer of the default elements through the
thickness. No time stepping: the structure is built as a run builds it, then
:func:`pdfem.fem.modes.natural_modes` gives f1 and :func:`pdfem.fem.static.static_displacement`
the deflection under the case's pressure on the top face; w is the mean -u_z of the nodes on
the plate's centre line (x = y = a/2, every z). References, with D = E h^3 / (12 (1 - nu^2)):

- f1 = lambda / (2 pi a^2) sqrt(D / (rho h)), lambda = 35.985 clamped, 2 pi^2 simply supported
  (Leissa, Vibration of Plates, NASA SP-160, 1969);
- w = c q a^4 / D, c = 0.00126 clamped, 0.00406 simply supported (Timoshenko &
  Woinowsky-Krieger, Theory of Plates and Shells, 1959).

docs/structures_convergence.md explains why the thin-plate values are adequate (the 3-D
solution differs by about 1 %) and why the simple support is the bottom edge line. SI units.
"""

from __future__ import annotations

import math
from functools import partial
from pathlib import Path

import numpy as np

from pdfem.case import Case
from pdfem.fem.modes import natural_modes
from pdfem.fem.static import static_displacement
from pdfem.run.build import check_mesh
from pdfem.run.build_structures import build_structure
from pdfem.validation.case import Outcome, ValidationCase, replace_structure

LAMBDA = {"clamped": 35.985, "simply_supported": 2.0 * math.pi**2}
"""Frequency parameter lambda = omega a^2 sqrt(rho h / D) of the first mode (Leissa 1969)."""

C_CENTRE = {"clamped": 0.00126, "simply_supported": 0.00406}
"""Centre deflection coefficient c in w = c q a^4 / D, nu = 0.3 (Timoshenko & Woinowsky-Krieger
1959, tables 35 and 8)."""


def plate(case: Case) -> tuple[float, float, float]:
    """Side a (m: twice the quarter model's length_x), thickness h (m) and flexural rigidity
    D = E h^3 / (12 (1 - nu^2)) (N m) of the case's plate."""
    s = case.structures[0]
    a, h = 2.0 * s.params["length_x"], s.params["length_z"]
    return a, h, s.youngs_modulus * h**3 / (12.0 * (1.0 - s.poisson_ratio**2))


def solve_plate(case: Case, directory: Path) -> dict:
    """Build the plate (meshed into ``directory``) and return ``f1`` (Hz), ``w_centre`` (m,
    positive down along the load), ``n_nodes`` and ``n_elements``."""
    cfg = case.structures[0]
    st = build_structure(cfg, directory, case.file)
    check_mesh(st, cfg, case.file)
    freqs, _ = natural_modes(st, 1)
    u = static_displacement(st)
    points = st.points[:len(u)]
    corner = np.array([cfg.params.get("origin_x", 0.0) + cfg.params["length_x"],
                       cfg.params.get("origin_y", 0.0) + cfg.params["length_y"]])
    on_line = np.linalg.norm(points[:, :2] - corner, axis=1) < 1e-6 * cfg.params["length_x"]
    if not on_line.any():
        raise ValueError("the plate mesh has no node on its centre line x = y = a/2")
    return {"f1": float(freqs[0]), "w_centre": float(-u[on_line, 2].mean()),
            "n_nodes": int(len(points)), "n_elements": int(st.mesh.n_elements)}


def measure_f1(outcome: Outcome) -> float:
    """First natural frequency (Hz)."""
    return outcome.data["f1"]


def measure_w(outcome: Outcome) -> float:
    """Centre deflection (m)."""
    return outcome.data["w_centre"]


def reference_f1(support: str, case: Case) -> float:
    """f1 = lambda / (2 pi a^2) sqrt(D / (rho h)) (Hz) of the plate with ``support``
    (``clamped`` or ``simply_supported``)."""
    a, h, d = plate(case)
    return LAMBDA[support] / (2.0 * math.pi * a**2) * math.sqrt(d / (case.structures[0].density * h))


def reference_w(support: str, case: Case) -> float:
    """w = c q a^4 / D (m) of the plate with ``support``, q the pressure of the case's first
    load (Pa)."""
    a, _, d = plate(case)
    return C_CENTRE[support] * case.structures[0].loads[0].pressure * a**4 / d


def quick(case: Case) -> Case:
    """50 mm elements in plane instead of 25 mm (still one layer)."""
    s = case.structures[0]
    return replace_structure(case, params=dict(s.params, divisions_x=s.params["divisions_x"] // 2,
                                               divisions_y=s.params["divisions_y"] // 2))


def _cases(support: str, words: str) -> tuple[ValidationCase, ...]:
    file = f"plate_{support}.toml"
    note = "50 mm elements in plane instead of 25 mm"
    return (
        ValidationCase(
            name=f"plate_{support}_frequency", case_file=file,
            quantity=f"{words} plate f1", unit="Hz", measure=measure_f1, reference=partial(reference_f1, support),
            source=f"Leissa, Vibration of Plates, NASA SP-160 (1969): f1 = lambda/(2 pi a^2) "
                   f"sqrt(D/(rho h)), lambda = {LAMBDA[support]:.5g}",
            tolerance=0.03, quick=quick, execute=solve_plate, quick_note=note),
        ValidationCase(
            name=f"plate_{support}_deflection", case_file=file,
            quantity=f"{words} plate centre deflection", unit="m", measure=measure_w,
            reference=partial(reference_w, support),
            source=f"Timoshenko & Woinowsky-Krieger, Theory of Plates and Shells (1959): "
                   f"w = c q a^4 / D, c = {C_CENTRE[support]}",
            tolerance=0.05, quick=quick, execute=solve_plate, quick_note=note),
    )


CASES = _cases("clamped", "clamped square") + _cases("simply_supported", "simply supported square")
