"""Young's modulus and Poisson's ratio of the LPS ice from a block in tension
(``lps_block_tension.toml``).

Not a coupled run: the block is built from the case file (:func:`pdfem.run.build_ice.build_ice_body`)
and relaxed here under a traction on its end faces, which the case format cannot express.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pdfem.case import Case
from pdfem.geometry.shapes import Box
from pdfem.run.build_ice import build_ice_body, ice_material
from pdfem.validation.case import Outcome, ValidationCase, replace_ice, replace_run

if TYPE_CHECKING:
    from matplotlib.figure import Figure

STRESS = 1.0e6  # Pa, the uniaxial traction on the end faces


def _strains(x0: np.ndarray, u: np.ndarray, dx: float) -> tuple[float, float, float]:
    """Linear fits of u_x(x), u_y(y), u_z(z) over the core of the block: (eps_xx, eps_yy, eps_zz)."""
    centre = x0.mean(axis=0)
    length = x0[:, 0].max() - x0[:, 0].min() + dx
    core = (np.abs(x0[:, 1] - centre[1]) < 4 * dx) & (np.abs(x0[:, 2] - centre[2]) < 4 * dx)
    core &= (x0[:, 0] > x0[:, 0].min() + 0.3 * length) & (x0[:, 0] < x0[:, 0].max() - 0.3 * length)
    return tuple(float(np.polyfit(x0[core, a], u[core, a], 1)[0]) for a in range(3))


def relax(case: Case, directory: Path) -> dict:
    """Relax the block under the end tractions for ``run.end_time``.

    Returns
    -------
    dict
        ``x0`` (N,3) and ``u`` (N,3) at the end (m), ``strain`` (3,) the fitted eps_xx, eps_yy,
        eps_zz, ``stress`` (Pa), and ``time`` (s) / ``youngs_modulus`` (Pa) every 50 steps.
    """
    cfg = case.ice[0]
    body = build_ice_body(cfg, case.run, case.file)
    rho, dx = cfg.material.density, cfg.dx
    x = body.x0[:, 0]
    traction = np.zeros_like(body.x0)  # force density (N/m^3) on the end layers
    for end, sign in ((x < x.min() + 0.5 * dx, -1.0), (x > x.max() - 0.5 * dx, 1.0)):
        traction[end, 0] = sign * STRESS * dx * dx / body.vol[end]
    dt = case.run.safety_factor * body.stable_time_step()
    length = x.max() - x.min() + dx
    damp = math.exp(-math.pi * ice_material(cfg.material).wave_speed / length * dt)  # near critical, axial mode
    body.start()
    body.f += traction
    times, moduli = [], []
    steps = max(1, math.ceil(case.run.end_time / dt))
    for k in range(1, steps + 1):
        body.v += 0.5 * dt * body.f / rho
        body.v *= damp
        body.y += dt * body.v
        body.compute_forces()
        body.f += traction
        body.v += 0.5 * dt * body.f / rho
        if k % 50 == 0 or k == steps:
            times.append(k * dt)
            moduli.append(STRESS / _strains(body.x0, body.y - body.x0, dx)[0])
    u = body.y - body.x0
    return {"x0": body.x0.copy(), "u": u, "strain": np.array(_strains(body.x0, u, dx)),
            "stress": STRESS, "time": np.array(times), "youngs_modulus": np.array(moduli)}


def youngs_modulus(outcome: Outcome) -> float:
    """E = sigma / eps_xx (Pa)."""
    return outcome.data["stress"] / outcome.data["strain"][0]


def poisson_ratio(outcome: Outcome) -> float:
    """nu = -(eps_yy + eps_zz) / (2 eps_xx)."""
    e = outcome.data["strain"]
    return -0.5 * (e[1] + e[2]) / e[0]


def quick(case: Case) -> Case:
    """A 0.28 m x 0.12 m x 0.12 m block (28 x 12 x 12 particles, 57 % of them) relaxed for 1 ms."""
    return replace_run(replace_ice(case, shape=Box((0.0, 0.0, 0.0), (0.28, 0.12, 0.12))), end_time=1.0e-3)


def plot_modulus(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """E estimated from the core strain during the relaxation."""
    ax = fig.add_subplot()
    d = outcome.data
    ax.plot(d["time"] * 1e3, d["youngs_modulus"] / 1e9, "o-", ms=3, label="pdfem (core strain)")
    ax.axhline(ref / 1e9, color="k", ls="--", label="input E")
    ax.set_xlabel("relaxation time [ms]")
    ax.set_ylabel("E = sigma / eps_xx [GPa]")
    ax.set_ylim(0.8 * ref / 1e9, 1.2 * ref / 1e9)
    ax.legend()


def plot_ratio(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """Lateral against axial displacement of the block's core at rest."""
    d = outcome.data
    x0, u = d["x0"], d["u"]
    yc = x0[:, 1].mean()
    ax = fig.add_subplot()
    ax.plot(x0[:, 1] - yc, u[:, 1] * 1e6, ".", ms=2, color="0.6", label="pdfem, all particles")
    y = np.linspace((x0[:, 1] - yc).min(), (x0[:, 1] - yc).max(), 2)
    ax.plot(y, -ref * d["strain"][0] * y * 1e6, "k--", label=f"-nu eps_xx y, nu = {ref:g}")
    ax.plot(y, d["strain"][1] * y * 1e6, "r-", label=f"core fit (nu = {value:.3f})")
    ax.set_xlabel("y - y_c [m]")
    ax.set_ylabel("u_y [µm]")
    ax.legend()


_COMMON = dict(case_file="lps_block_tension.toml", execute=relax, quick=quick,
               quick_note="28 x 12 x 12 particles relaxed for 1 ms instead of 36 x 14 x 14 for 2 ms")
CASES = (
    ValidationCase(
        name="youngs_modulus", quantity="Young's modulus (LPS)", unit="Pa",
        measure=youngs_modulus, reference=lambda case: case.ice[0].material.youngs_modulus,
        plot=plot_modulus, tolerance=0.03, **_COMMON,
        source="Hooke's law, E = sigma/eps_xx under uniaxial stress; input E of the LPS "
               "(Silling et al. 2007, J. Elasticity 88, 151-184)"),
    ValidationCase(
        name="poisson_ratio", quantity="Poisson's ratio (LPS)", unit="-",
        measure=poisson_ratio, reference=lambda case: case.ice[0].material.poisson_ratio,
        plot=plot_ratio, tolerance=0.03, **_COMMON,
        source="Hooke's law, nu = -eps_yy/eps_xx; the state-based LPS admits any nu "
               "(Silling et al. 2007, J. Elasticity 88, 151-184), bond-based PD only 1/4"),
)
