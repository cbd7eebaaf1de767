"""A free ship carrying an elastic plate (``ship_attached_plate.toml``,
``ship_attached_plate_pull.toml``; :mod:`pdfem.motion.attached_frame`, docs/ship.md). SI
units.

The tiny free icebreaker floats at rest with a plate riding on it, centred on its centre of
gravity G. The ship's mass, G and radii of gyration are the whole ship's, the plate included,
so the rigid hull alone is what the plate leaves: at the ship's whole mass (100 %) the hull is
a massless shell that floats the plate.

* ``ship_attached_rest_drift``: nothing loads the system and gravity balances buoyancy; the
  plate weighs 1, 2.5 and 5 kg and the ship's whole mass (26.9 kg), each run at the automatic
  step (safety factor 0.8) and at a step ten times smaller (0.08), 1 s. Measured: the largest
  distance of G from its start over all eight runs; reference 0 (issue 31: within 1 mm; an
  explicit hand-over between ship and plate went unstable once the plate's inertia was a
  sizeable part of the ship's).
* ``ship_attached_newton``: the plate carrying the ship's whole mass is pulled along x by
  ``F = 10 N`` (a traction on its long sides, through G, ramped over 0.3 s). No water force
  acts on a surge (hydrostatics only), so the ship and plate accelerate as one rigid body at
  ``a = F / m``, m the ship's mass (Newton's second law for the combined body; the plate's
  mass counted once, neither twice nor not at all). Measured: the mean acceleration of G along
  x over the second half of the run (after the ramp); tolerance 0.1 %.
* ``ship_attached_energy``: the same run's energy balance, kinetic (ship and plate) + strain
  + damping loss = work of the pull, each term computed on its own: the largest |residual|
  over its frames / the work of the pull. In a pure translation the coupled step is central
  differences in world coordinates, so the balance closes to round-off (tolerance 1e-6).

Measured (``pdfem validate --case ship_attached_rest_drift --case ship_attached_newton --case
ship_attached_energy``): drift 1.5e-15 m (round-off; nothing moves); acceleration 0.371778
m/s^2 against F / m = 0.371791 m/s^2 (-3.7e-5); energy residual 1.2e-14 J of 1.343 J
(9.0e-15). The earlier scheme (the plate's lagged support impulses handed to a ship of the
whole mass) gave -0.252 m/s^2 in the pull: the ship's velocity swung by +-0.2 m/s and grew.
``--quick``: the rest runs to 0.02 s, the pull to 0.6 s.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from pdfem.case import Case
from pdfem.output import read_results
from pdfem.run.build_structures import build_structure, structure_mesh
from pdfem.run.driver import run_case
from pdfem.validation.case import (Outcome, ValidationCase, replace_run, replace_structure,
                                   run_and_read)

if TYPE_CHECKING:
    from matplotlib.figure import Figure

MASSES = (1.0, 2.5, 5.0, None)
"""Plate masses (kg) of the rest runs; ``None``: the ship's whole mass."""

STEP_FACTORS = (1.0, 0.1)
"""The rest runs' steps: the automatic step, and ten times smaller (on the safety factor)."""


def _plate_volume(case: Case) -> float:
    """Volume (m^3) of the box plate (``structure[1]``'s ``length_x, _y, _z``)."""
    p = case.structures[1].params
    return float(p["length_x"] * p["length_y"] * p["length_z"])


def meshed_case(case: Case, directory: Path) -> tuple[Case, float]:
    """``case`` with its hull and plate meshed once into ``directory`` (the runs read the
    .msh files) and the ship's mass (kg, its default: the displaced mass of the mesh)."""
    for k, cfg in enumerate(case.structures):
        path = structure_mesh(cfg, directory, case.file)
        case = replace_structure(case, k, mesh=str(path), params={})
    ship = build_structure(case.structures[0], directory, case.file)
    return case, ship.mass


def rest_runs(case: Case, directory: Path) -> dict[str, Any]:
    """Run ``case`` with the plate at every :data:`MASSES` and :data:`STEP_FACTORS`; per run
    the ship's motion and the energy history."""
    volume = _plate_volume(case)
    meshed, ship_mass = meshed_case(case, directory / "meshes")
    runs = {}
    for mass in MASSES:
        m = ship_mass if mass is None else mass
        for factor in STEP_FACTORS:
            label = (f"{m:.4g} kg" + (" (100 %)" if mass is None else "")
                     + f", step x {factor:g}")
            run = replace_structure(meshed, 1, density=m / volume)
            run = replace_run(run, safety_factor=case.run.safety_factor * factor)
            out = directory / f"plate{m:.4g}kg_step{factor:g}"
            h = read_results(run_case(run, out, quiet=True).results)["histories"]
            runs[label] = {"motion": h["motions/hull"], "energy": h["energy"]}
    return {"runs": runs, "ship_mass": ship_mass}


def drift(outcome: Outcome) -> float:
    """Largest distance (m) of G from its start over all runs."""
    return max(float(np.linalg.norm(r["motion"]["position"] - r["motion"]["position"][0],
                                    axis=1).max()) for r in outcome.data["runs"].values())


def plot_drift(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """Distance of G from its start in every run (log scale)."""
    ax = fig.add_subplot()
    for label, r in outcome.data["runs"].items():
        x = r["motion"]["position"]
        ax.semilogy(r["motion"]["time"], np.linalg.norm(x - x[0], axis=1) + 1e-18, label=label)
    ax.axhline(1e-3, color="k", lw=0.8, ls="--", label="1 mm")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("|G - G(0)| [m]")
    ax.legend(fontsize="x-small")


def _pull(case: Case) -> tuple[float, float]:
    """The pull (N, along x: the traction of the plate's load times its two long sides'
    area) and its ramp (s)."""
    load = case.structures[1].loads[0]
    p = case.structures[1].params
    return 2.0 * p["length_x"] * p["length_z"] * load.traction[0], load.pulse.rise


def acceleration(outcome: Outcome) -> float:
    """Mean acceleration (m/s^2) of G along x over the second half of the run (after the
    ramp)."""
    m = outcome.data["histories"]["motions/hull"]
    t, v = m["time"], m["velocity"][:, 0]
    start = max(_pull(outcome.case)[1], 0.5 * t[-1])
    k = int(np.searchsorted(t, start))
    return float((v[-1] - v[k]) / (t[-1] - t[k]))


def newton(case: Case) -> float:
    """``F / m`` (m/s^2): the pull over the ship's mass (its mesh's displaced mass)."""
    with tempfile.TemporaryDirectory() as tmp:
        mass = meshed_case(case, Path(tmp))[1]
    return _pull(case)[0] / mass


def energy_residual(outcome: Outcome) -> float:
    """Largest |residual| of the energy balance over the frames / the pull's work."""
    e = outcome.data["histories"]["energy"]
    return float(np.max(np.abs(e["residual"])) / e["load_work"][-1])


def plot_pull(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """Velocity of G along x against the rigid body's ``F (t - t_r / 2) / m`` after the ramp."""
    m = outcome.data["histories"]["motions/hull"]
    t = m["time"]
    force, rise = _pull(outcome.case)
    rigid = np.where(t < rise, 0.5 * ref * t * t / rise, ref * (t - 0.5 * rise))
    ax = fig.add_subplot()
    ax.plot(t, m["velocity"][:, 0], label="G, pdfem")
    ax.plot(t, rigid, "--", label="F / m, one rigid body")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("velocity of G along x [m/s]")
    ax.legend(fontsize="small")


def _shorter(end_time: float):
    def quick(case: Case) -> Case:
        return replace_run(case, end_time=end_time)
    quick.__doc__ = f"Run to {end_time:g} s."
    return quick


_QUICK_PULL = _shorter(0.6)
_PULL = dict(case_file="ship_attached_plate_pull.toml", quick=_QUICK_PULL,
             execute=run_and_read, quick_note="run to 0.6 s instead of 1 s")

CASES = (
    ValidationCase(
        name="ship_attached_rest_drift", case_file="ship_attached_plate.toml",
        quantity="drift of G of a free ship at rest carrying a plate (1, 2.5, 5 kg, its "
                 "whole mass; two steps), 1 s", unit="m",
        measure=drift, reference=lambda case: 0.0, execute=rest_runs, quick=_shorter(0.02),
        plot=plot_drift, tolerance=1e-3, relative=False,
        source="hydrostatic equilibrium: a ship at rest at its equilibrium stays there, "
               "whatever share of its mass rides on it elastically (issue 31: within 1 mm "
               "over 1 s at any step)",
        quick_note="eight runs to 0.02 s instead of 1 s"),
    ValidationCase(
        name="ship_attached_newton",
        quantity="acceleration of a free ship pulled through the plate that carries its "
                 "whole mass", unit="m/s^2",
        measure=acceleration, reference=newton, plot=plot_pull, tolerance=1e-3,
        source="Newton's second law for the combined rigid body: a = F / m, m the whole "
               "ship's mass (hull and plate), no water force on a surge", **_PULL),
    ValidationCase(
        name="ship_attached_energy",
        quantity="max |energy residual| / work of the pull", unit="-",
        measure=energy_residual, reference=lambda case: 0.0, tolerance=1e-6, relative=False,
        source="conservation of energy: kinetic (ship and plate) + strain + damping loss = "
               "work of the pull, each term computed on its own (round-off in a pure "
               "translation: central differences in world coordinates)", **_PULL),
)
