"""Conservation of momentum and energy in a coupled impact (``coupled_impact.toml``; the same
with the block advanced by implicit Newmark steps, ``coupled_impact_implicit.toml``).

A free ice block hits a free steel block and rebounds. The ice's momentum comes from its
particle velocities, the block's from the motion of its mass centre over the last two frames
(free flight), both from the results file; the energies from the run's energy history.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from pdfem.case import Case
from pdfem.validation.case import Outcome, ValidationCase
from pdfem.validation.measure import ice_momentum, structure_mass_centre, structure_momentum

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def _densities(case: Case) -> tuple[float, float]:
    return case.ice[0].material.density, case.structures[0].density


def momentum_ratio(outcome: Outcome) -> float:
    """(p_ice + p_block) / p_ice(0) along the impact direction x, at the end of the run."""
    r = outcome.data
    rho_ice, rho_st = _densities(outcome.case)
    ice = r["ice"]["ice"]
    p0 = ice_momentum(ice, rho_ice, 0)
    p1 = ice_momentum(ice, rho_ice, -1) + structure_momentum(r["structure"]["block"], r["time"], rho_st)
    return float(p1[0] / p0[0])


def energy_ratio(outcome: Outcome) -> float:
    """(kinetic + strain of both bodies + contact loss) / initial kinetic energy, at the end."""
    e = outcome.data["histories"]["energy"]
    kept = e["kinetic"] + e["strain"] + e["structure_kinetic"] + e["structure_strain"]
    return float((kept[-1] + e["contact_dissipated"][-1]) / (e["kinetic"][0] + e["strain"][0]))


def plot_momentum(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """Momentum of the ice (frames) and of the block (between frames) along x."""
    r = outcome.data
    rho_ice, rho_st = _densities(outcome.case)
    t = r["time"]
    ice = r["ice"]["ice"]
    p_ice = np.array([ice_momentum(ice, rho_ice, k)[0] for k in range(len(t))])
    block = r["structure"]["block"]
    mu = np.array([structure_mass_centre(block, rho_st, k)[1][0] for k in range(len(t))])
    mid = 0.5 * (t[1:] + t[:-1])
    p_block = np.diff(mu) / np.diff(t)
    p_ice_mid = np.interp(mid, t, p_ice)
    ax = fig.add_subplot()
    ax.plot(t * 1e3, p_ice, "o-", ms=3, label="ice (particle velocities)")
    ax.plot(mid * 1e3, p_block, "s-", ms=3, label="block (mass centre, between frames)")
    ax.plot(mid[-1:] * 1e3, p_ice_mid[-1:] + p_block[-1:], "k*", ms=10,
            label=f"total at the end / initial = {value:.12f}")
    ax.axhline(p_ice[0], color="k", ls="--", lw=0.8, label="initial momentum")
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("momentum p_x [kg m/s]")
    ax.legend(fontsize="small")


def plot_energy(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """Energy history of the impact."""
    e = outcome.data["histories"]["energy"]
    t = e["time"] * 1e3
    ax = fig.add_subplot()
    parts = {"ice kinetic": e["kinetic"], "ice strain": e["strain"],
             "block kinetic": e["structure_kinetic"], "block strain": e["structure_strain"],
             "contact loss": e["contact_dissipated"]}
    ax.stackplot(t, *parts.values(), labels=parts.keys(), alpha=0.8)
    ax.axhline(e["kinetic"][0], color="k", ls="--", label="initial kinetic energy")
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("energy [J]")
    ax.legend(fontsize="small", loc="lower left")


_COMMON = dict(unit="-", reference=lambda case: 1.0,
               quick_note="unchanged (512 particles, 64 hexahedra, 0.3 ms)")
MOMENTUM = ("conservation of linear momentum (Newton's third law; the contact impulse "
            "leaving the ice reaches the structure exactly, Zhang et al. 2023, Eqs. 5-8)")
ENERGY = ("conservation of energy (no fracture, no friction); the explicit integrators "
          "add an O(dt^2) error")


def _entries(suffix: str, case_file: str, note: str) -> tuple[ValidationCase, ValidationCase]:
    """The momentum and energy entries of ``case_file``, named ``impact_*<suffix>``."""
    return (
        ValidationCase(
            name=f"impact_momentum{suffix}", quantity="momentum after/before",
            measure=momentum_ratio, plot=plot_momentum, tolerance=1e-9, case_file=case_file,
            source=MOMENTUM + note, **_COMMON),
        ValidationCase(
            name=f"impact_energy{suffix}", quantity="energy balance E/E0",
            measure=energy_ratio, plot=plot_energy, tolerance=0.02, case_file=case_file,
            source=ENERGY + note, **_COMMON),
    )


CASES = (_entries("", "coupled_impact.toml", "")
         + _entries("_implicit", "coupled_impact_implicit.toml",
                    "; the block by implicit Newmark steps, the contact impulses amending "
                    "each step (a Newmark step conserves the momentum it is given)"))
