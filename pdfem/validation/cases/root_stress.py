"""The nominal blade root stress (:mod:`pdfem.fem.section_stress`, the ``root_stress_*`` rows of
``shaft/<structure>.blade<k>``): its definition against beam theory on a spinning bar
(``spinning_bar_root_stress.toml``), and its convergence under mesh refinement on the milling
propeller (``propeller_root_stress.toml``).

Both structures turn at full speed from t = 0 under a held surface load and are measured in
their steady state, the static equilibrium of the rotating frame with the load
(:meth:`pdfem.motion.frame_structure.FrameStructure.steady_displacement`, stress stiffening and
spin softening included), through the rows the run writes (:meth:`ShaftLoads.rows
<pdfem.motion.shaft_loads.ShaftLoads.rows>`); a run's structure starts there, its loads
included (:meth:`pdfem.motion.frame_structure.FrameStructure.add_surface_load`).

* ``bar_root_stress_tension`` and ``_compression``: the 0.5 m x 0.1 m x 0.1 m steel bar of the
  spinning cases at omega = 100 rad/s about z through its root face's centre, and a traction
  q = 1 MPa along z on its tip face (F = q b h = 10 kN at L = 0.5 m). The nominal root stress
  of a cantilever (statics: the root carries the centrifugal force rho A omega^2 L^2 / 2 and
  the moment F L; flexure formula, c = h/2, I = b h^3/12):

      sigma = rho omega^2 L^2 / 2 +- 6 F L / (b h^2) = 9.8125 +- 30 MPa.

  Measured 39.736 and -20.110 MPa (-0.19 %, -0.38 %): the axial part 9.8128 MPa (+0.003 %),
  the bending part 29.923 MPa (-0.26 %: the centrifugal load's moment on the bent bar, the
  stress stiffening, which beam theory leaves out; about -0.3 % estimated). Tolerance 1 %.
* ``propeller_root_stress``: blade 1's nominal root stress in tension of the propeller of the
  milling case (0.1 m, 10-node tetrahedra) under the centrifugal load of 300 rpm and 1 MPa on
  blade 1's back, against the same propeller meshed at 0.05 m: ``|sigma_h - sigma_h/2| /
  sigma_h/2`` must stay below 5 % (the project's requirement for the milling blade root
  stress). The elastic stress at the clamped root edge, which the milling case's monitor reads,
  does not converge (benchmarks/blade_root_convergence.py). ``--quick``: the single blade of
  ``models/propeller_blade.py`` (the same hub radius, root thickness 70 mm) at 0.1 m and
  0.05 m under its centrifugal load alone (skewed, it bends: 10.1 MPa in tension, of which
  2.3 MPa axial).

SI units: m, Pa, N.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pdfem.case import Case
from pdfem.run.build_structures import build_structure
from pdfem.validation.case import Outcome, ValidationCase, replace_structure, unchanged

if TYPE_CHECKING:
    from matplotlib.figure import Figure

REFINEMENT = 2.0
"""The reference mesh's element size is the case's divided by this."""

STRESSES = ("root_stress_tension", "root_stress_compression", "root_stress_axial")
"""The nominal root stress rows (Pa) of a blade."""


def steady_rows(case: Case, directory: Path) -> dict:
    """The first structure of ``case`` built as a run builds it, in its steady state with its
    loads: ``{blade: {row: Pa}}`` of the nominal root stresses, and ``nodes``."""
    cfg = case.structures[0]
    s = build_structure(cfg, directory, case.file)
    rows = s.shaft.rows()
    return {"blades": {b: {k: rows[b][k] for k in STRESSES} for b in rows if b},
            "nodes": s.n_nodes, "element_size": float(cfg.params.get("element_size", np.nan))}


def solve_pair(case: Case, directory: Path) -> dict:
    """:func:`steady_rows` of the case (``model``) and of the case with the element size
    divided by ``REFINEMENT`` (``reference``)."""
    s = case.structures[0]
    fine = replace_structure(case, params=dict(s.params,
                                               element_size=s.params["element_size"] / REFINEMENT))
    return {"model": steady_rows(case, directory / "model"),
            "reference": steady_rows(fine, directory / "reference")}


def convergence(outcome: Outcome) -> float:
    """``|sigma - sigma_ref| / |sigma_ref|`` (-) of blade 1's nominal root stress in tension,
    model against the mesh refined 2x."""
    a = outcome.data["model"]["blades"]["blade1"]["root_stress_tension"]
    b = outcome.data["reference"]["blades"]["blade1"]["root_stress_tension"]
    return abs(a - b) / abs(b)


def zero(case: Case) -> float:
    """Zero: a converged quantity does not change when the mesh is refined."""
    return 0.0


def single_blade(case: Case) -> Case:
    """The ``--quick`` variant: the single blade of ``models/propeller_blade.py`` (hub radius
    0.3 m, tip 1 m, root thickness 70 mm, chord 0.349 m at the hub; 10-node tetrahedra of the
    case's element size), its root clamped, at the case's speed, under its centrifugal load
    alone (its skew bends it: about three quarters of the root stress is bending). A surface load on
    this blade's surface group ``contact`` cannot be built (scikit-fem's inverse isoparametric
    mapping does not converge on some of its curved faces)."""
    s = case.structures[0]
    return replace_structure(case, mesh="propeller_blade", loads=(), params={
        "element_size": s.params["element_size"], "sections": 10, "element_order": 2})


def pair_plot(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """The nominal root stresses of every blade on both meshes."""
    ax = fig.add_subplot()
    for key, marker in (("model", "o"), ("reference", "x")):
        d = outcome.data[key]
        blades = list(d["blades"])
        for j, row in enumerate(STRESSES):
            ax.plot(np.arange(len(blades)) + 0.2 * (j - 1),
                    [d["blades"][b][row] / 1e6 for b in blades], marker, ms=7,
                    color=f"C{j}", label=f"{row}, {d['element_size'] * 1e3:g} mm "
                                         f"({d['nodes']:,} nodes)")
    ax.set_xticks(range(len(blades)), blades)
    ax.set_ylabel("nominal root stress [MPa]")
    ax.legend(fontsize=7)


def bar_stress(case: Case) -> tuple[float, float]:
    """The bar's centrifugal root stress rho omega^2 L^2 / 2 and bending root stress
    6 F L / (b h^2) = 6 q L / h (Pa) of a traction q on its tip face (beam theory)."""
    s = case.structures[0]
    length, h = s.params["length_x"], s.params["length_z"]
    omega = float(np.linalg.norm(s.angular_velocity))
    q = abs(s.loads[0].traction[2])
    return 0.5 * s.density * omega**2 * length**2, 6.0 * q * length / h


def bar_measure(side: str):
    """``measure(outcome)``: the bar's nominal root stress (Pa) in ``side``, ``"tension"``
    or ``"compression"``."""
    def measure(outcome: Outcome) -> float:
        return outcome.data["blades"]["blade1"][f"root_stress_{side}"]
    return measure


def bar_reference(sign: float):
    """``reference(case)``: rho omega^2 L^2 / 2 + ``sign`` 6 F L / (b h^2) (Pa)."""
    def reference(case: Case) -> float:
        axial, bending = bar_stress(case)
        return axial + sign * bending
    return reference


BEAM_SOURCE = ("statics of a cantilever (the root carries the centrifugal force rho A omega^2 "
               "L^2 / 2 and the tip load's moment F L) and the flexure formula sigma = N / A "
               "+- M c / I, c = h/2, I = b h^3 / 12 (any strength-of-materials text; the "
               "cantilever-beam method of propeller blade strength: Carlton, The strength of "
               "marine propeller blades, Lloyd's Register Technical Association 1980-81)")

CASES = tuple(
    ValidationCase(
        name=f"bar_root_stress_{side}", case_file="spinning_bar_root_stress.toml",
        quantity=f"nominal root stress, {side}, bar spinning with a tip load", unit="Pa",
        measure=bar_measure(side), reference=bar_reference(sign), execute=steady_rows,
        quick=unchanged, tolerance=0.01, source=BEAM_SOURCE,
        quick_note="unchanged (one static solve)")
    for side, sign in (("tension", 1.0), ("compression", -1.0))) + (
    ValidationCase(
        name="propeller_root_stress", case_file="propeller_root_stress.toml",
        quantity="blade 1 nominal root stress vs mesh refined 2x (rel. diff.)", unit="-",
        measure=convergence, reference=zero, plot=pair_plot, quick=single_blade,
        execute=solve_pair, tolerance=0.05, relative=False,
        source="mesh convergence: the same propeller with the element size halved (the "
               "project's requirement: the milling blade root stress with 10-node blades "
               "within 5 % of a mesh refined 2x)",
        quick_note="the single blade of models/propeller_blade.py at 0.1 m and 0.05 m under its "
                   "centrifugal load"),
)
