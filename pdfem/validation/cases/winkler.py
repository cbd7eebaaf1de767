"""A floating ice plate pushed down at its centre (``floating_plate_winkler.toml``): the plate on
an elastic (Winkler) foundation of modulus k = rho_w g, stiffness P / w0 and characteristic
length l, against a Kirchhoff plate of the same size on the same foundation.

Theory (Hertz 1884; Wyman 1950, "Deflections of an infinite plate", Can. J. Res. A 28): an
infinite plate of bending stiffness D = E h^3 / (12 (1 - nu^2)) on a foundation k deflects as
``w(r) = -(P l^2 / (2 pi D)) kei(r / l)`` under a point load P, l = (D / k)^(1/4), so that
``P / w0 = 8 sqrt(D k)``. The case's plate is finite (free edges at about 3 l) and is pushed by
a small rigid square (the prescribed particle columns), so the reference is the same problem
solved with Morley's non-conforming Kirchhoff triangle (Morley 1968, "The constant-moment plate
bending element", J. Strain Analysis 6; scikit-fem ``ElementTriMorley``): the free square plate
of the case's size on the foundation, w = 1 prescribed on the punch (the cells of the pushed
particles), on a mesh graded from punch/4 (and punch/8) at the punch to l/8 at the edges, with
the two meshes' values extrapolated linearly in the fine size (the punch's corners make the
convergence first order; the extrapolation changes P / w0 by about 0.7 %).

Measured from the run (SI units): P is the mean reaction of the pushed region
(``loads/plate.load``) over the last eighth of the run (the plate has settled under the water's linear
drag), w0 the prescribed push. The characteristic length is the l of the best least-squares fit
``w(r) = A kei(r / l)`` to the deflection of the plate's middle rows (mean over the layers,
both sides of the load) for r between l_0 / 2 and 2.5 l_0 (l_0 = (D / k)^(1/4) of the case
input); the reference is the same fit to the Morley plate's deflection along its centre line.

The entries are not registered in ``pdfem validate``: a lattice sheet a few particles thick is
softer than Kirchhoff's plate (docs/water.md, "Winkler plate"). :func:`lattice_plate` solves the
case's plate as the orthotropic Kirchhoff plate with the lattice sheet's own plate moduli
(:mod:`pdfem.pd.plate_moduli`), which says how much of a run's deficit the moduli explain.
"""

from __future__ import annotations

import dataclasses
import math
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.special import kei

from pdfem.case import Case
from pdfem.geometry.shapes import Box
from pdfem.validation.case import Outcome, ValidationCase, replace_ice, replace_run

if TYPE_CHECKING:
    from matplotlib.figure import Figure

SETTLED = 0.125  # the reaction is averaged over this fraction of the run at its end


def _plate(case: Case) -> tuple[float, float, float, float]:
    """Half-width a (m), thickness h (m), D (N m) and foundation modulus k (N/m^3) of the case."""
    ice = case.ice[0]
    box, mat = ice.shape, ice.material
    h = float(box.max[2] - box.min[2])
    d = mat.youngs_modulus * h**3 / (12.0 * (1.0 - mat.poisson_ratio**2))
    return 0.5 * float(box.max[0] - box.min[0]), h, d, case.water.density * -case.run.gravity[2]


def punch_half_width(case: Case) -> float:
    """Half-width (m) of the square of the pushed particles' cells: the lattice x-coordinates
    (from the box's min corner, spacing dx) inside the prescribed region, plus dx/2."""
    ice = case.ice[0]
    region = ice.prescribed_velocity[0].region
    x = ice.shape.min[0] + ice.dx * (0.5 + np.arange(round((ice.shape.max[0] - ice.shape.min[0]) / ice.dx)))
    inside = x[(x >= region.min[0]) & (x <= region.max[0])]
    return float(np.max(np.abs(inside)) + 0.5 * ice.dx)


def push(case: Case) -> float:
    """The prescribed downward displacement w0 at the end of the run (m, positive down)."""
    return -float(case.ice[0].prescribed_velocity[0].path[-1][3])


def stiffness(outcome: Outcome) -> float:
    """P / w0 (N/m): mean reaction of the pushed region over the run's last eighth over the push."""
    h = outcome.data["histories"][f"loads/{outcome.case.ice[0].name}.load"]
    late = h["time"] >= (1.0 - SETTLED) * h["time"][-1]
    return float(-h["force"][late, 2].mean() / push(outcome.case))


def fit_length(r: np.ndarray, w: np.ndarray, l0: float) -> float:
    """l (m) of the least-squares fit w = A kei(r / l) (A free) over l_0/2 <= r <= 2.5 l_0."""
    keep = (r >= 0.5 * l0) & (r <= 2.5 * l0)
    r, w = r[keep], w[keep]

    def residual(length: float) -> float:
        g = kei(r / length)
        amp = (g @ w) / (g @ g)
        return float(np.sum((w - amp * g) ** 2))

    return float(minimize_scalar(residual, bounds=(0.5 * l0, 2.0 * l0), method="bounded").x)


def pd_profile(outcome: Outcome) -> tuple[np.ndarray, np.ndarray]:
    """Distances r (m) from the load and the deflection (m, up) of the two middle particle rows
    (|y| = dx/2 or 0), mean over the last five frames and over the layers."""
    body = outcome.data["ice"][outcome.case.ice[0].name]
    x0, uz = body["x0"], body["u"][-5:, :, 2].mean(axis=0)
    rows = np.abs(x0[:, 1]) <= np.abs(x0[:, 1]).min() + 1e-9
    key = np.round(x0[rows, 0] / outcome.case.ice[0].dx, 6)
    xs, inv = np.unique(key, return_inverse=True)
    w = np.bincount(inv, uz[rows]) / np.bincount(inv)
    x = xs * outcome.case.ice[0].dx
    return np.hypot(x, np.abs(x0[rows, 1]).min()), w


def length(outcome: Outcome) -> float:
    """Characteristic length (m) fitted to the run's deflected profile (module doc)."""
    _, _, d, k = _plate(outcome.case)
    return fit_length(*pd_profile(outcome), (d / k) ** 0.25)


def _axis(half: float, punch: float, fine: float, coarse: float) -> np.ndarray:
    """Symmetric node coordinates (m): spacing ``fine`` up to the punch edge, then growing by
    15 % per cell up to ``coarse``, ending at ``half``."""
    pts = list(np.linspace(0.0, punch, round(punch / fine) + 1))
    step = fine
    while pts[-1] < half - 1e-12:
        step = min(1.15 * step, coarse)
        pts.append(min(pts[-1] + step, half))
    if len(pts) > 2 and half - pts[-2] < 0.3 * step:
        pts.pop(-2)
    a = np.array(pts)
    return np.concatenate([-a[:0:-1], a])


def morley_plate(half: float, punch: float, d: float, nu: float, k: float,
                 fine: float, coarse: float,
                 moduli: tuple[float, float, float] | None = None,
                 ) -> tuple[float, np.ndarray, np.ndarray]:
    """A free square Kirchhoff plate on a Winkler foundation pushed by a rigid square.

    Morley's triangle (Morley 1968) in scikit-fem; energy ``D ((1 - nu) w,ij w,ij + nu (w,ii)^2)
    / 2 + k w^2 / 2``, or with ``moduli`` the orthotropic ``(D11 (w,xx^2 + w,yy^2)
    + 2 D12 w,xx w,yy + 4 D66 w,xy^2) / 2 + k w^2 / 2``; w = 1 prescribed at the vertices in
    the punch.

    Parameters
    ----------
    half, punch
        Half-widths of the plate and of the punch (m).
    d, nu, k
        Bending stiffness (N m), Poisson's ratio, foundation modulus (N/m^3).
    fine, coarse
        Mesh spacing (m) at the punch and its cap far from it.
    moduli
        Optional (D11, D12, D66) / D of an orthotropic plate (e.g. a lattice sheet's,
        :class:`pdfem.pd.plate_moduli.PlateModuli`); None: isotropic (1, nu, (1 - nu) / 2).

    Returns
    -------
    tuple
        P / w0 (N/m), and the centre line's x >= 0 (m) and deflection (m per m of push).
    """
    from skfem import Basis, BilinearForm, ElementTriMorley, MeshTri, asm, condense, solve
    from skfem.helpers import dd

    a = _axis(half, punch, fine, coarse)
    mesh = MeshTri.init_tensor(a, a)
    basis = Basis(mesh, ElementTriMorley())

    d11, d12, d66 = (d, d * nu, 0.5 * d * (1.0 - nu)) if moduli is None else (
        d * moduli[0], d * moduli[1], d * moduli[2])

    @BilinearForm
    def form(u, v, _):
        a, b = dd(u), dd(v)
        return (d11 * (a[0, 0] * b[0, 0] + a[1, 1] * b[1, 1])
                + d12 * (a[0, 0] * b[1, 1] + a[1, 1] * b[0, 0])
                + 4.0 * d66 * a[0, 1] * b[0, 1] + k * u * v)

    A = asm(form, basis)
    x, y = mesh.p
    tol = 1e-9 * punch
    dofs = basis.nodal_dofs[0, (np.abs(x) <= punch + tol) & (np.abs(y) <= punch + tol)]
    w = np.zeros(A.shape[0])
    w[dofs] = 1.0
    w = solve(*condense(A, np.zeros(A.shape[0]), x=w, D=dofs))
    line = (np.abs(y) <= tol) & (x >= -tol)
    order = np.argsort(x[line])
    return float((A @ w)[dofs].sum()), x[line][order], w[basis.nodal_dofs[0, line]][order]


@lru_cache(maxsize=8)
def _reference(half: float, punch: float, d: float, nu: float, k: float,
               moduli: tuple[float, float, float] | None = None) -> tuple[float, float]:
    """Extrapolated Morley P / w0 (N/m) and fitted l (m) of the case's plate (module doc)."""
    l0 = (d / k) ** 0.25
    coarse = l0 / 8.0
    runs = [morley_plate(half, punch, d, nu, k, punch / m, coarse, moduli) for m in (4, 8)]
    p = [s for s, _, _ in runs]
    lengths = [fit_length(np.abs(xs), w, l0) for _, xs, w in runs]
    return 2.0 * p[1] - p[0], 2.0 * lengths[1] - lengths[0]


def reference_stiffness(case: Case) -> float:
    """P / w0 (N/m) of the Morley plate of the case (module doc)."""
    half, _, d, k = _plate(case)
    return _reference(half, punch_half_width(case), d, case.ice[0].material.poisson_ratio, k)[0]


def reference_length(case: Case) -> float:
    """Characteristic length (m) fitted to the Morley plate's deflection (module doc)."""
    half, _, d, k = _plate(case)
    return _reference(half, punch_half_width(case), d, case.ice[0].material.poisson_ratio, k)[1]


def lattice_plate(case: Case) -> tuple[float, float]:
    """P / w0 (N/m) and fitted l (m) of the case's plate as a Kirchhoff plate with the plate
    moduli of its particle lattice (:func:`pdfem.pd.plate_moduli.plate_moduli`: the imposed
    plate modes of a sheet as many particles thick at the same horizon / dx): what the run
    would give if the lattice sheet were that orthotropic plate (docs/water.md). Not a
    reference: a diagnosis of a run's deficit."""
    from pdfem.pd.plate_moduli import plate_moduli

    ice = case.ice[0]
    half, h, d, k = _plate(case)
    p = plate_moduli(round(h / ice.dx), ice.horizon / ice.dx, ice.material.poisson_ratio)
    return _reference(half, punch_half_width(case), d, ice.material.poisson_ratio, k,
                      (p.d11, p.d12, p.d66))


def resized(case: Case, half: float, dx: float, horizon_factor: float, end: float) -> Case:
    """The case with a plate ``half`` wide each way (m, same thickness and load), lattice
    spacing ``dx`` (m), horizon ``horizon_factor`` dx and run to ``end`` (s; the push's path
    cut there)."""
    ice = case.ice[0]
    bc = ice.prescribed_velocity[0]
    path = tuple(p for p in bc.path if p[0] < end) + ((end,) + tuple(bc.path[-1][1:]),)
    bcs = (dataclasses.replace(bc, path=path),) + ice.prescribed_velocity[1:]
    c = ice.shape
    mid = 0.5 * (c.min[0] + c.max[0]), 0.5 * (c.min[1] + c.max[1])
    shape = Box((mid[0] - half, mid[1] - half, c.min[2]), (mid[0] + half, mid[1] + half, c.max[2]))
    return replace_run(replace_ice(case, dx=dx, horizon=horizon_factor * dx, shape=shape,
                                   prescribed_velocity=bcs), end_time=end)


def plot_stiffness(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """Reaction over the push against the Morley plate's stiffness and Hertz's."""
    h = outcome.data["histories"][f"loads/{outcome.case.ice[0].name}.load"]
    _, _, d, k = _plate(outcome.case)
    ax = fig.add_subplot()
    ax.plot(h["time"], -h["force"][:, 2] / push(outcome.case), lw=0.9, label="pdfem: reaction / w0")
    ax.axhline(ref, color="k", ls="--", label=f"finite Kirchhoff plate (Morley) {ref:.0f} N/m")
    ax.axhline(8 * math.sqrt(d * k), color="grey", ls=":", label="infinite plate 8 sqrt(D k) (Hertz)")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("P / w0 [N/m]")
    ax.legend()


def plot_length(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """The run's profile with its kei fit and the fit of the Morley plate."""
    r, w = pd_profile(outcome)
    ax = fig.add_subplot()
    ax.plot(np.sign(r) * r, w * 1e3, "o", ms=3, label="pdfem: middle rows")
    for length_, style, name in ((value, "-", "fit to pdfem"), (ref, "--", "fit to Morley plate")):
        rr = np.linspace(0.0, r.max(), 200)
        ax.plot(rr, w.min() * 1e3 * kei(rr / length_) / kei(0.0), style,
                label=f"kei(r / l), l = {length_:.4f} m ({name})")
    ax.set_xlabel("r [m]")
    ax.set_ylabel("u_z [mm]")
    ax.legend()


_SOURCE = ("plate on a Winkler foundation k = rho_w g (Hertz 1884; Wyman 1950): the free square "
           "plate of the case solved with Morley's Kirchhoff triangle (Morley 1968), pushed by "
           "the pushed particles' square; infinite plate P / w0 = 8 sqrt(D k)")
_NOTE = ("the full case (the coarsest lattice that bends within 5 %, about 5 min of one core; a "
         "0.5 m plate gives 0.970 and 0.9495, docs/water.md)")

CASES = (
    ValidationCase(
        name="floating_plate_winkler", case_file="floating_plate_winkler.toml",
        quantity="stiffness P / w0 of a floating plate pushed at its centre", unit="N/m",
        measure=stiffness, reference=reference_stiffness, plot=plot_stiffness,
        tolerance=0.05, source=_SOURCE, quick_note=_NOTE),
    ValidationCase(
        name="floating_plate_winkler_length", case_file="floating_plate_winkler.toml",
        quantity="characteristic length of the deflected floating plate", unit="m",
        measure=length, reference=reference_length, plot=plot_length,
        tolerance=0.05, source=_SOURCE + "; l from a kei(r / l) fit to the profile",
        quick_note=_NOTE),
)
