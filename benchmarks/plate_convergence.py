"""Element convergence study for thin steel plates (clamped and simply supported).

A square steel plate (a = 1 m, h = 12 mm, E = 210 GPa, nu = 0.3, rho = 7850 kg/m3) is
modelled as a 3-D solid with scikit-fem elements and compared with thin-plate theory:

* first natural frequency f1 = lambda / (2 pi a^2) sqrt(D / (rho h)), lambda = 35.985
  clamped (Leissa 1969, NASA SP-160), 2 pi^2 simply supported;
* centre deflection under uniform pressure q: w = c q a^4 / D, c = 0.00126 clamped,
  0.00406 simply supported (Timoshenko & Woinowsky-Krieger 1959, tables 8 and 35),

with D = E h^3 / (12 (1 - nu^2)).  Only the quarter plate [0, a/2]^2 x [-h/2, h/2] is
meshed: the planes x = a/2 and y = a/2 are symmetry planes (u_x = 0, resp. u_y = 0), which
keeps the doubly symmetric first mode and the symmetric static response exact and makes
every case four times smaller.

Boundary conditions on the edges x = 0 and y = 0:

* clamped: all three displacement components on the whole edge faces;
* simply supported: only the transverse displacement u_z on the bottom edge lines
  (z = -h/2).  Every mesh family has nodes there (one layer of trilinear hexes has no
  mid-plane node), so all candidates get the same support; the reaction is purely
  vertical, so membrane and bending stay uncoupled as in plate theory.  ``--ss-line mid``
  uses the mid-plane lines instead (needs mid-plane nodes) to measure the difference.

Mass: consistent, and HRZ-lumped (Hinton, Rock & Zienkiewicz 1976): per element and
direction m_ii = M_ii m_e / sum_j M_jj, which is strictly positive for every element
(row-sum lumping is not for quadratic tets/serendipity hexes; its minimum is reported).
The explicit stable step is 2 / omega_max with omega_max^2 the largest eigenvalue of
M_lumped^-1 K (constrained DOFs removed); the explicit cost per simulated second is
DOFs / dt.

Run ``python benchmarks/plate_convergence.py [--quick] [--json]``; uses scikit-fem, numpy
and scipy only (meshes are structured hexes from ``MeshHex.init_tensor``, tets by splitting
each hex with ``MeshHex.to_meshtet``).
"""

from __future__ import annotations

import argparse
import json
import platform
import resource
import sys
import time
from dataclasses import asdict, dataclass
from typing import Callable

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import LinearOperator, eigsh, factorized
from skfem import (
    Basis,
    BilinearForm,
    ElementHex1,
    ElementHex2,
    ElementHexS2,
    ElementTetP1,
    ElementTetP2,
    ElementVector,
    FacetBasis,
    LinearForm,
    MeshHex,
    asm,
)
from skfem.helpers import dot
from skfem.models.elasticity import lame_parameters, linear_elasticity

A = 1.0  # plate side [m]
H = 0.012  # thickness [m]
E_MOD = 210e9  # Young's modulus [Pa]
NU = 0.3
RHO = 7850.0  # density [kg/m3]
Q = 10e3  # uniform pressure [Pa]
D_PLATE = E_MOD * H**3 / (12.0 * (1.0 - NU**2))

LAMBDA = {"clamped": 35.985, "simply_supported": 2.0 * np.pi**2}
C_DEFL = {"clamped": 0.00126, "simply_supported": 0.00406}

# family -> (element class, quadrature order integrating the mass exactly, split hexes into tets?)
FAMILIES: dict[str, tuple[Callable, int, bool]] = {
    "TetP1": (ElementTetP1, 2, True),
    "TetP2": (ElementTetP2, 4, True),
    "Hex1": (ElementHex1, 2, False),
    "HexS2": (ElementHexS2, 4, False),
    "Hex2": (ElementHex2, 4, False),
}
SIZES = (0.05, 0.025, 0.0125, 0.00625)
LAYERS = (1, 2)
QUICK_CASES = (  # (family, layers, size): one coarse case per family
    ("TetP1", 2, 0.025),
    ("TetP2", 1, 0.05),
    ("Hex1", 1, 0.025),
    ("HexS2", 1, 0.025),
    ("Hex2", 1, 0.05),
)


def reference(support: str) -> tuple[float, float]:
    """Thin-plate first frequency [Hz] and centre deflection [m] for ``support``."""
    f1 = LAMBDA[support] / (2.0 * np.pi * A**2) * np.sqrt(D_PLATE / (RHO * H))
    w = C_DEFL[support] * Q * A**4 / D_PLATE
    return f1, w


@dataclass
class Case:
    """One row of the study."""

    family: str
    layers: int
    size_mm: float
    support: str
    dofs: int
    f1_cons: float
    f1_hrz: float
    err_f1_cons: float
    err_f1_hrz: float
    w_centre: float
    err_w: float
    min_hrz_mass: float
    min_rowsum_mass: float
    dt_stable: float
    cost: float
    t_assemble: float
    t_solve: float


def plate_mesh(family: str, size: float, layers: int):
    """Quarter-plate mesh: structured hexes, or each hex split into tets."""
    n = int(round(0.5 * A / size))
    x = np.linspace(0.0, 0.5 * A, n + 1)
    z = np.linspace(-0.5 * H, 0.5 * H, layers + 1)
    mesh = MeshHex.init_tensor(x, x, z)
    return mesh.to_meshtet() if FAMILIES[family][2] else mesh


def _hrz_and_rowsum(sbasis: Basis) -> tuple[np.ndarray, np.ndarray, sp.csr_matrix]:
    """Scalar HRZ and row-sum lumped masses and the scalar consistent mass."""
    dx = sbasis.dx  # (nelems, nqp)
    phi = np.array([b[0].value for b in sbasis.basis])  # (nbfs, nelems, nqp)
    diag_e = RHO * np.einsum("ieq,eq->ie", phi**2, dx)
    m_e = RHO * dx.sum(axis=1)
    hrz_e = diag_e * (m_e / diag_e.sum(axis=0))
    rows_e = RHO * np.einsum("ieq,eq->ie", phi, dx)
    dofs = sbasis.element_dofs
    n = sbasis.N
    hrz = np.bincount(dofs.ravel(), hrz_e.ravel(), minlength=n)
    rowsum = np.bincount(dofs.ravel(), rows_e.ravel(), minlength=n)
    mass = asm(BilinearForm(lambda u, v, w: RHO * u * v), sbasis)
    return hrz, rowsum, mass


def constrained_dofs(vbasis: Basis, support: str, ss_line: str) -> np.ndarray:
    """Indices of the constrained DOFs (edges x = 0, y = 0 and the two symmetry planes)."""
    comp = np.empty(vbasis.N, dtype=int)
    for c, idx in enumerate(vbasis.split_indices()):
        comp[idx] = c
    x, y, z = vbasis.doflocs
    tol = 1e-9
    edge = (x < tol) | (y < tol)
    fixed = ((comp == 0) & (np.abs(x - 0.5 * A) < tol)) | ((comp == 1) & (np.abs(y - 0.5 * A) < tol))
    if support == "clamped":
        fixed |= edge
    else:
        z_line = -0.5 * H if ss_line == "bottom" else 0.0
        on_line = np.abs(z - z_line) < tol
        if not np.any(edge & on_line):
            raise ValueError("no nodes on the mid-plane edge lines: use --ss-line bottom")
        fixed |= edge & on_line & (comp == 2)
    return np.flatnonzero(fixed)


def run_case(family: str, layers: int, size: float, support: str, ss_line: str = "bottom") -> Case:
    """Assemble and solve one (element, mesh, support) case."""
    elem_cls, order, _ = FAMILIES[family]
    t0 = time.perf_counter()
    mesh = plate_mesh(family, size, layers)
    sbasis = Basis(mesh, elem_cls(), intorder=order)
    vbasis = sbasis.with_element(ElementVector(elem_cls()))
    n_s = sbasis.N
    # ElementVector numbers the DOFs interleaved: component c of scalar DOF k is 3 k + c
    assert all(np.array_equal(idx, 3 * np.arange(n_s) + c) for c, idx in enumerate(vbasis.split_indices()))
    lam, mu = lame_parameters(E_MOD, NU)
    K = asm(linear_elasticity(lam, mu), vbasis).tocsr()
    hrz_s, rowsum_s, m_s = _hrz_and_rowsum(sbasis)
    M = sp.kron(m_s, sp.identity(3), format="csr")
    m_hrz = np.repeat(hrz_s, 3)
    top = mesh.facets_satisfying(lambda p: np.abs(p[2] - 0.5 * H) < 1e-9)
    fbasis = FacetBasis(mesh, ElementVector(elem_cls()), facets=top, intorder=order)
    load = asm(LinearForm(lambda v, w: -Q * v[2]), fbasis)
    fixed = constrained_dofs(vbasis, support, ss_line)
    free = np.setdiff1d(np.arange(vbasis.N), fixed)
    Kf = K[free][:, free].tocsc()
    Mf = M[free][:, free].tocsc()
    mf = m_hrz[free]
    t_asm = time.perf_counter() - t0

    t0 = time.perf_counter()
    u = np.zeros(vbasis.N)
    solve = factorized(Kf)  # one LU of K serves the static solve and both shift-invert eigsh
    u[free] = solve(load[free])
    op_inv = LinearOperator(Kf.shape, matvec=solve, dtype=float)
    x, y, _ = vbasis.doflocs
    centre = (np.abs(x - 0.5 * A) < 1e-9) & (np.abs(y - 0.5 * A) < 1e-9)
    centre[np.arange(vbasis.N) % 3 != 2] = False
    w = -float(np.mean(u[centre]))
    lam_c, lam_l = (
        eigsh(Kf, k=1, M=mass, sigma=0, which="LM", OPinv=op_inv, return_eigenvectors=False)[0]
        for mass in (Mf, sp.diags(mf).tocsc())
    )
    s = sp.diags(1.0 / np.sqrt(mf))
    lam_max = eigsh(s @ Kf @ s, k=1, which="LA", tol=1e-5, return_eigenvectors=False)[0]
    t_sol = time.perf_counter() - t0

    f_ref, w_ref = reference(support)
    f_c = float(np.sqrt(lam_c) / (2 * np.pi))
    f_l = float(np.sqrt(lam_l) / (2 * np.pi))
    dt = float(2.0 / np.sqrt(lam_max))
    return Case(
        family=family,
        layers=layers,
        size_mm=size * 1e3,
        support=support,
        dofs=int(free.size),
        f1_cons=f_c,
        f1_hrz=f_l,
        err_f1_cons=f_c / f_ref - 1.0,
        err_f1_hrz=f_l / f_ref - 1.0,
        w_centre=w,
        err_w=w / w_ref - 1.0,
        min_hrz_mass=float(hrz_s.min()),
        min_rowsum_mass=float(rowsum_s.min()),
        dt_stable=dt,
        cost=free.size / dt,
        t_assemble=t_asm,
        t_solve=t_sol,
    )


def predicted_dofs(family: str, size: float, layers: int) -> int:
    """Rough vector DOF count of a quarter-plate mesh before it is built."""
    n = int(round(0.5 * A / size))
    quad = family in ("TetP2", "HexS2", "Hex2")
    k = 2 if quad else 1
    return 3 * (k * n + 1) ** 2 * (k * layers + 1)


def run_study(
    quick: bool,
    max_dofs: int,
    max_seconds: float,
    supports: tuple[str, ...],
    ss_line: str = "bottom",
    families: tuple[str, ...] = tuple(FAMILIES),
    log=sys.stderr,
) -> list[Case]:
    """All cases (or the quick ones); skips a size whose predicted time or size is too large."""
    plan = (
        [(f, l, [s]) for f, l, s in QUICK_CASES if f in families]
        if quick
        else [(f, l, list(SIZES)) for f in families for l in LAYERS]
    )
    rows: list[Case] = []
    for family, layers, sizes in plan:
        last = 0.0
        for size in sizes:
            ndof = predicted_dofs(family, size, layers)
            if not quick and (ndof > max_dofs or last * 4.5 > max_seconds):
                print(f"skip {family} {layers}L {size*1e3:g} mm: ~{ndof} DOFs, last {last:.0f} s", file=log)
                break
            last = 0.0
            for support in supports:
                c = run_case(family, layers, size, support, ss_line)
                last += c.t_assemble + c.t_solve
                rows.append(c)
                print(
                    f"{family:6s} {layers}L {c.size_mm:6.2f} mm {support[:7]:8s} dofs={c.dofs:7d} "
                    f"f1 {100*c.err_f1_cons:+7.2f}% hrz {100*c.err_f1_hrz:+7.2f}% w {100*c.err_w:+7.2f}% "
                    f"dt={c.dt_stable:.3e} t={c.t_assemble:.1f}+{c.t_solve:.1f}s",
                    file=log,
                    flush=True,
                )
    return rows


def markdown(rows: list[Case]) -> str:
    """Markdown tables, one per support."""
    out = []
    for support in dict.fromkeys(r.support for r in rows):
        f_ref, w_ref = reference(support)
        out.append(f"\n### {support.replace('_', ' ')} (f1 = {f_ref:.3f} Hz, w = {w_ref*1e3:.4f} mm)\n")
        out.append(
            "| element | layers | size [mm] | DOFs | f1 err cons. | f1 err HRZ | w err | dt [us] "
            "| cost DOFs/dt [1/s] | min HRZ m [kg] | min row-sum m [kg] | time [s] |"
        )
        out.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
        for r in rows:
            if r.support != support:
                continue
            out.append(
                f"| {r.family} | {r.layers} | {r.size_mm:g} | {r.dofs} | {100*r.err_f1_cons:+.2f} % "
                f"| {100*r.err_f1_hrz:+.2f} % | {100*r.err_w:+.2f} % | {r.dt_stable*1e6:.3f} | {r.cost:.3g} "
                f"| {r.min_hrz_mass:.3g} | {r.min_rowsum_mass:.3g} | {r.t_assemble:.1f}+{r.t_solve:.1f} |"
            )
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    """Command line entry: run the study, print markdown tables or JSON."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="one coarse case per family (QUICK_CASES)")
    p.add_argument("--json", action="store_true", help="print JSON instead of markdown")
    p.add_argument("--max-dofs", type=int, default=450_000, help="skip meshes with more DOFs")
    p.add_argument("--max-seconds", type=float, default=180.0, help="skip a size predicted to take longer")
    p.add_argument("--support", choices=("both", "clamped", "simply_supported"), default="both")
    p.add_argument("--ss-line", choices=("bottom", "mid"), default="bottom")
    p.add_argument("--family", action="append", choices=tuple(FAMILIES), help="restrict to these")
    args = p.parse_args(argv)
    supports = ("clamped", "simply_supported") if args.support == "both" else (args.support,)
    t0 = time.perf_counter()
    families = tuple(args.family or FAMILIES)
    rows = run_study(args.quick, args.max_dofs, args.max_seconds, supports, args.ss_line, families)
    meta = {
        "machine": platform.platform(),
        "python": platform.python_version(),
        "wall_s": time.perf_counter() - t0,
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "ss_line": args.ss_line,
        "reference": {s: dict(zip(("f1_hz", "w_m"), reference(s))) for s in supports},
    }
    if args.json:
        print(json.dumps({"meta": meta, "cases": [asdict(r) for r in rows]}, indent=1))
    else:
        print(markdown(rows))
        print(f"\nwall {meta['wall_s']:.0f} s, peak RSS {meta['peak_rss_mb']:.0f} MB, {meta['machine']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
