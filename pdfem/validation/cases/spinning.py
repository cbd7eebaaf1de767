"""A bar spinning about an axis through its root: its radial stress (``spinning_bar.toml``) and
the rise of its first flapwise frequency with speed (``spinning_bar_southwell.toml``).

The bar (along x from the root face x = 0 to the tip x = R) is solved in a frame turning about
the z axis through its root (:class:`pdfem.motion.frame_structure.FrameStructure`). Once the speed is held
and the ramp's vibration has died out, equilibrium along the bar, d sigma / dr = -rho omega^2 r
with a free tip, gives the radial stress

    sigma_rr(r) = rho omega^2 (R^2 - r^2) / 2.

Measured: sigma_xx of the last frame's elastic displacement averaged (Gauss quadrature) over
each slab of elements along the bar, i.e. the slab's mean axial force over the area (the bending
the ramp's Euler load leaves cancels in it), against the slab mean of sigma_rr, at the slabs
centred in 0.2 R <= r <= 0.8 R (away from the clamped root, whose lateral
constraint disturbs the stress over about one bar depth, and from the tip where sigma -> 0).
The value is the station ratio sigma / sigma_rr furthest from 1; the reference is 1.

Flapwise frequency: the lowest mode bending along the axis (z) of K + K_sigma - spin softening
with the lumped mass (:meth:`pdfem.motion.frame_structure.FrameStructure.rotating_stiffness`) at the
case's speed, against Southwell's omega_f^2 = omega_0^2 + 1.193 omega^2 with the Euler-Bernoulli
omega_0 = 1.8751^2 / L^2 sqrt(E I / (rho A)).
SI units throughout.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from pdfem.case import Case
from pdfem.fem.elasticity import ElasticMaterial
from pdfem.fem.structure import ElasticStructure
from pdfem.fem.modes import generalized_modes
from pdfem.motion.frame_structure import FrameStructure
from pdfem.run.build_structures import build_structure
from pdfem.validation.case import Outcome, ValidationCase, replace_structure, unchanged

if TYPE_CHECKING:
    from matplotlib.figure import Figure

STATIONS = (0.2, 0.8)  # r / R range of the compared stations
SOUTHWELL = 1.193      # first flapwise Southwell coefficient, uniform cantilever, zero hub
SWEEP = (0.0, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0)  # speeds / the case's speed, for the plot


def stress_profile(outcome: Outcome, frame: int = -1
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Radii r (m) of the centres of the slabs of elements along the bar, the mean sigma_xx
    (Pa) over each slab in frame ``frame`` (default the last; Gauss quadrature: the slab's mean
    axial force over its area), and the mean of rho omega^2 (R^2 - r^2) / 2 over the same slab
    (Pa)."""
    s = outcome.case.structures[0]
    material = ElasticMaterial(s.density, s.youngs_modulus, s.poisson_ratio)
    bar = ElasticStructure.from_file(outcome.directory / f"{s.name}.msh", material,
                                     element_order=s.element_order)
    u = bar.dofmap.to_dofs(outcome.data["structure"][s.name]["u_elastic"][frame])
    grad = bar.basis.interpolate(u).grad                # (3, 3, Ne, Nq): du_i / dx_j
    lam, mu = material.lame
    sxx = (lam + 2.0 * mu) * grad[0, 0] + lam * (grad[1, 1] + grad[2, 2])
    dx = bar.basis.dx                                   # (Ne, Nq) quadrature weights (m^3)
    x = bar.points[bar.cells[:, :8], 0] - s.center[0]   # (Ne, 8) corner radii
    lo, hi = x.min(axis=1), x.max(axis=1)
    r, inverse = np.unique(np.round(0.5 * (lo + hi), 9), return_inverse=True)
    mean = np.bincount(inverse, weights=(sxx * dx).sum(axis=1)) / np.bincount(
        inverse, weights=dx.sum(axis=1))
    a = np.bincount(inverse, weights=lo) / np.bincount(inverse)
    b = np.bincount(inverse, weights=hi) / np.bincount(inverse)
    omega = float(np.linalg.norm(s.angular_velocity))
    tip = float(s.params["length_x"])
    return r, mean, 0.5 * s.density * omega**2 * (tip**2 - (a * a + a * b + b * b) / 3.0)


def measure(outcome: Outcome, frame: int = -1) -> float:
    """The ratio sigma / sigma_rr, among the stations 0.2 R..0.8 R, furthest from 1 (-), in
    frame ``frame`` (default the last)."""
    r, sigma, ref = stress_profile(outcome, frame)
    tip = float(outcome.case.structures[0].params["length_x"])
    keep = (r >= STATIONS[0] * tip) & (r <= STATIONS[1] * tip)
    ratio = sigma[keep] / ref[keep]
    return float(ratio[np.argmax(np.abs(ratio - 1.0))])


def frame_ratios(outcome: Outcome) -> np.ndarray:
    """:func:`measure` of every frame of the run, in order (-)."""
    frames = len(outcome.data["time"])
    return np.array([measure(outcome, k) for k in range(frames)])


def measure_every_frame(outcome: Outcome) -> float:
    """The ratio sigma / sigma_rr furthest from 1 over the stations 0.2 R..0.8 R and every
    frame of the run, the first (t = 0) included (-)."""
    ratios = frame_ratios(outcome)
    return float(ratios[np.argmax(np.abs(ratios - 1.0))])


def steady_plot(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """The worst station's sigma / sigma_rr in every frame against time."""
    ax = fig.add_subplot()
    ax.plot(outcome.data["time"] * 1e3, frame_ratios(outcome), "o-", ms=3,
            label="pdfem: worst station, 0.2 R..0.8 R")
    ax.axhline(1.0, color="k", ls="--", label="rho omega^2 (R^2 - r^2) / 2")
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("sigma / sigma_rr [-]")
    ax.legend()


def reference(case: Case) -> float:
    """1: the ratio of the measured to the analytical radial stress."""
    return 1.0


def quick(case: Case) -> Case:
    """10 x 1 x 1 hexahedra instead of 10 x 2 x 2."""
    s = case.structures[0]
    return replace_structure(case, params=dict(s.params, divisions_y=1, divisions_z=1))


def plot(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """Cross-section mean radial stress along the bar against rho omega^2 (R^2 - r^2) / 2."""
    r, sigma, theory = stress_profile(outcome)
    ax = fig.add_subplot()
    ax.plot(r, sigma / 1e6, "o", ms=4, label="pdfem: slab mean sigma_xx")
    ax.plot(r, theory / 1e6, "k--", label="rho omega^2 (R^2 - r^2) / 2")
    tip = float(outcome.case.structures[0].params["length_x"])
    ax.axvspan(STATIONS[0] * tip, STATIONS[1] * tip, color="0.9", label="compared stations")
    ax.set_xlabel("radius r [m]")
    ax.set_ylabel("radial stress [MPa]")
    ax.legend()


def flapwise_frequency(structure: FrameStructure) -> float:
    """Lowest flapwise (along the axis, z) natural frequency (Hz) of the spinning structure."""
    free = structure.solver.free
    lam, phi = generalized_modes(structure.rotating_stiffness()[free][:, free],
                                 structure.solver.m[free], 6)
    full = np.zeros(structure.dofmap.n_dofs)
    for k in range(lam.size):
        full[free] = phi[:, k]
        if np.argmax(np.abs(structure.dofmap.to_nodal(full)).sum(axis=0)) == 2:
            return math.sqrt(lam[k]) / (2.0 * math.pi)
    raise ValueError("no flapwise mode among the six lowest")


def solve_flapwise(case: Case, directory: Path) -> dict:
    """Flapwise frequencies (Hz) at the speeds ``SWEEP`` x the case's (rad/s)."""
    cfg = case.structures[0]
    w = np.asarray(cfg.angular_velocity, dtype=np.float64)
    speeds, freqs = [], []
    for k, factor in enumerate(SWEEP):
        spin = replace(cfg, angular_velocity=tuple(max(factor, 1e-9) * w), ramp_time=0.0)
        freqs.append(flapwise_frequency(build_structure(spin, directory, case.file, k == 0)))
        speeds.append(factor * float(np.linalg.norm(w)))
    return {"speed": np.array(speeds), "frequency": np.array(freqs)}


def southwell(case: Case, speed: np.ndarray | float) -> np.ndarray | float:
    """Southwell's f_f = sqrt(omega_0^2 + 1.193 omega^2) / (2 pi) (Hz), Euler-Bernoulli omega_0."""
    s = case.structures[0]
    length, b, h = s.params["length_x"], s.params["length_y"], s.params["length_z"]
    w0 = 1.875104**2 / length**2 * math.sqrt(s.youngs_modulus * h**2 / 12.0 / s.density)
    return np.sqrt(w0**2 + SOUTHWELL * np.asarray(speed) ** 2) / (2.0 * math.pi)


def flapwise_measure(outcome: Outcome) -> float:
    """Flapwise frequency (Hz) at the case's speed."""
    return float(outcome.data["frequency"][SWEEP.index(1.0)])


def flapwise_reference(case: Case) -> float:
    """Southwell's flapwise frequency (Hz) at the case's speed."""
    return float(southwell(case, float(np.linalg.norm(case.structures[0].angular_velocity))))


def flapwise_plot(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """Flapwise frequency against speed, pdfem and Southwell."""
    w, f = outcome.data["speed"], outcome.data["frequency"]
    ax = fig.add_subplot()
    ax.plot(w, f, "o", label="pdfem: K + K_sigma, lumped mass")
    grid = np.linspace(0.0, w.max(), 50)
    ax.plot(grid, southwell(outcome.case, grid), "k--", label="Southwell, 1.193")
    ax.set_xlabel("speed omega [rad/s]")
    ax.set_ylabel("first flapwise frequency [Hz]")
    ax.legend()


CASES = (
    ValidationCase(
        name="spinning_bar_stress", case_file="spinning_bar.toml",
        quantity="radial stress / rho omega^2 (R^2 - r^2)/2, worst station", unit="-",
        measure=measure, reference=reference, plot=plot, quick=quick, tolerance=0.03,
        source="equilibrium of a slender bar spinning about its root, d sigma/dr = -rho omega^2 r, "
               "sigma(R) = 0 (e.g. Timoshenko & Goodier, Theory of Elasticity, 1970, rotating "
               "bodies)",
        quick_note="10 x 1 x 1 hexahedra instead of 10 x 2 x 2"),
    ValidationCase(
        name="spinning_bar_steady_start", case_file="spinning_bar_steady.toml",
        quantity="radial stress / rho omega^2 (R^2 - r^2)/2, worst station and frame, started "
                 "at full speed", unit="-",
        measure=measure_every_frame, reference=reference, plot=steady_plot, quick=quick,
        tolerance=0.03,
        source="equilibrium of a slender bar spinning about its root, d sigma/dr = -rho omega^2 "
               "r, sigma(R) = 0 (e.g. Timoshenko & Goodier, Theory of Elasticity, 1970, "
               "rotating bodies), held in every frame: the steady state needs no ramp",
        quick_note="10 x 1 x 1 hexahedra instead of 10 x 2 x 2"),
    ValidationCase(
        name="spinning_bar_southwell", case_file="spinning_bar_southwell.toml",
        quantity="first flapwise frequency at omega ~ omega_0", unit="Hz",
        measure=flapwise_measure, reference=flapwise_reference, plot=flapwise_plot,
        quick=unchanged, execute=solve_flapwise, tolerance=0.05,
        source="Southwell's relation omega_f^2 = omega_0^2 + 1.193 omega^2 for a uniform "
               "cantilever spinning about its root (Wright et al., J. Appl. Mech. 49, 1982), "
               "Euler-Bernoulli omega_0",
        quick_note="unchanged (eigenvalues, no time stepping)"),
)
