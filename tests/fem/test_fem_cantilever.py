"""Verification of the FE structure solver on a clamped steel cantilever (L = 1 m, 0.1 x 0.1 m).

References, named per test: Timoshenko beam theory (static tip deflection with Cowper's shear
coefficient), the FE model's own eigenvalues (scipy eigsh), energy conservation of the undamped
central difference scheme, the stability limit dt = 2/omega_max, the free decay of a damped oscillator, and a static FE solution
for prescribed displacements. The first bending frequency of the free vibration is the
validation entry ``cantilever_frequency`` (tests/validation/test_cantilever.py).

Meshes: first-order hexahedra from gmsh (transfinite + recombine; the ``gmsh_box`` fixture of
conftest.py), 2:1 elements along the beam.
Fully integrated trilinear hexahedra lock in bending, so the static error falls from 21 % to
6.9 % to 2.4 % over three meshes; first-order tetrahedra are much stiffer still (about -17 % at
h = 0.025 m), which is why the hexahedral path is used here.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse.linalg as sla

from pdfem.errors import InstabilityError
from pdfem.fem.elasticity import ElasticMaterial
from pdfem.fem.mesh import load_mesh
from pdfem.fem.stress import strain_energy
from pdfem.fem.structure import ElasticStructure

L, H = 1.0, 0.1
E, NU, RHO = 210e9, 0.3, 7850.0
STEEL = ElasticMaterial(density=RHO, youngs_modulus=E, poisson_ratio=NU)
P = 1.0e3                      # tip load, N (downwards, -z)
A, I = H * H, H**4 / 12.0
G = E / (2.0 * (1.0 + NU))
KAPPA = 10.0 * (1.0 + NU) / (12.0 + 11.0 * NU)   # Cowper's coefficient for a rectangle
DELTA_TIMOSHENKO = P * L**3 / (3 * E * I) + P * L / (KAPPA * G * A)
F1_EULER_BERNOULLI = 1.875104**2 / (2 * math.pi) * math.sqrt(E * I / (RHO * A * L**4))


@pytest.fixture(scope="module")
def cantilever(tmp_path_factory, gmsh_box):
    """Factory: the clamped cantilever on a hexahedral mesh of [0,L]x[0,H]x[0,H] with
    n = (nx, ny, nz) elements; groups beam, root (x = 0, clamped), tip (x = L). Each mesh is
    generated once per module; every call gives a new structure."""
    meshes = {}
    folder = tmp_path_factory.mktemp("beam")

    def make(n, **kwargs) -> ElasticStructure:
        n = tuple(n)
        if n not in meshes:
            path = gmsh_box(folder / f"beam_{n[0]}_{n[1]}_{n[2]}.msh", (L, H, H), volume_groups=["beam"],
                            face_groups={"root": ["x0"], "tip": ["x1"]}, divisions=n)
            meshes[n] = load_mesh(path)
        return ElasticStructure(meshes[n], STEEL, fixed_groups=["root"], name="beam", **kwargs)
    return make


def static_tip_load(s: ElasticStructure) -> np.ndarray:
    """Static displacement (Nn, 3) under the tip load P (uniform shear traction on the tip face),
    solved with the structure's own K (scipy spsolve), root clamped."""
    s.clear_loads()
    s.add_surface_load("tip", traction=(0.0, 0.0, -P / A))
    f = s.external_force_dofs()
    free = s.solver.free
    u = np.zeros_like(f)
    u[free] = sla.spsolve(s.K[free][:, free].tocsc(), f[free])
    return s.dofmap.to_nodal(u)


def tip_deflection(s: ElasticStructure, u: np.ndarray) -> float:
    return float(-u[s.group_nodes("tip"), 2].mean())


def lowest_and_highest_eigenvalues(s: ElasticStructure) -> tuple[float, float, np.ndarray]:
    """Smallest and largest eigenvalue of the constrained M^-1 K (scipy eigsh, the reference),
    and the (Nn, 3) mode shape of the smallest."""
    free = s.solver.free
    d = 1.0 / np.sqrt(s.mass[free])
    Kff = s.K[free][:, free]
    A_ = Kff.multiply(d[:, None]).multiply(d[None, :]).tocsc()
    lo, vec = sla.eigsh(A_, k=1, sigma=0.0, which="LM")
    hi = sla.eigsh(A_, k=1, which="LA", return_eigenvectors=False, tol=1e-8)[0]
    mode = np.zeros(s.dofmap.n_dofs)
    mode[free] = d * vec[:, 0]
    return float(lo[0]), float(hi), s.dofmap.to_nodal(mode)


@pytest.mark.slow
def test_static_tip_deflection_converges_to_timoshenko(cantilever):
    """Tip deflection vs Timoshenko beam theory delta = P L^3/(3EI) + P L/(kappa G A) (Cowper's
    kappa): the error decreases with refinement and is within 3 % on the finest mesh; the root
    reaction balances the tip load exactly (reference: static equilibrium); the bending stress
    of the top element layer is within 3 % of Navier's M z / I."""
    errors = []
    for n in [(20, 1, 1), (40, 2, 2), (80, 4, 4)]:
        s = cantilever(n)
        u = static_tip_load(s)
        errors.append(tip_deflection(s, u) / DELTA_TIMOSHENKO - 1.0)
    print("static tip deflection errors (20x1x1, 40x2x2, 80x4x4):", errors)
    assert abs(errors[0]) > abs(errors[1]) > abs(errors[2])
    assert abs(errors[2]) < 0.03
    # support reaction of the static state: K u - f summed over the clamped nodes = (0, 0, P)
    s.set_state(displacement=u)
    assert s.reaction("root") == pytest.approx([0.0, 0.0, P], abs=1e-6 * P)
    # bending stress of the top element layer at x = L/4, L/2, 3L/4 vs Navier's
    # sigma_xx = M z / I with the hogging moment M = P (L - x), z from the neutral axis
    sig = s.stresses()
    c = s.points[s.mesh.mesh.t.T].mean(axis=1)
    for xc in (0.25 * L, 0.5 * L, 0.75 * L):
        sel = (np.abs(c[:, 0] - xc) < 0.5 * L / 80) & (c[:, 2] > 0.75 * H)
        navier = P * (L - c[sel, 0]) * (c[sel, 2] - H / 2) / I
        assert sig[sel, 0, 0] == pytest.approx(navier, rel=0.03)


@pytest.mark.slow
def test_undamped_free_vibration_conserves_energy(cantilever):
    """Central difference without damping: kinetic + strain energy stays within 0.5 % of its
    initial value over 20 periods of the first mode, and the discrete invariant
    1/2 v(n-1/2).M v(n+1/2) + 1/2 u.K u is conserved to round-off (reference: energy
    conservation of the undamped system and of the leapfrog scheme)."""
    s = cantilever((20, 1, 1))
    u = static_tip_load(s)
    s.clear_loads()
    s.set_state(displacement=u)
    e0 = s.strain_energy()
    dt = s.stable_time_step()
    steps = int(20.5 / F1_EULER_BERNOULLI / dt)
    drift, inv_drift, inv0 = 0.0, 0.0, None
    v_prev = s.solver.v_half.copy()
    for k in range(steps):
        s.step(dt)
        if k % 10 == 0 or k == steps - 1:
            e = s.kinetic_energy() + s.strain_energy()
            drift = max(drift, abs(e / e0 - 1.0))
        if k > 0 and (k % 10 == 0 or k == steps - 1):
            # v_prev = v(n-1/2), v_half = v(n+1/2), u(n) = u(n+1) - dt v(n+1/2)
            inv = (0.5 * float(np.dot(s.mass * v_prev, s.solver.v_half))
                   + strain_energy(s.K, s.solver.u - dt * s.solver.v_half))
            inv0 = inv if inv0 is None else inv0
            inv_drift = max(inv_drift, abs(inv - inv0) / e0)
        v_prev = s.solver.v_half.copy()
    print(f"energy: max relative drift {drift:.2e} over {steps} steps (20 periods); "
          f"discrete invariant drift {inv_drift:.1e}")
    assert drift < 0.005
    assert inv_drift < 1e-9


def test_stable_step_is_sharp(cantilever):
    """Power iteration gives omega_max^2 within 1 % below scipy eigsh's largest eigenvalue; a run
    from a random displacement stays bounded at the stable step (0.9 x critical) and at
    0.99 x critical, and blows up at 1.1 x critical (reference: the central-difference limit
    dt = 2/omega_max)."""
    s = cantilever((20, 2, 2))
    lam = s.max_eigenvalue()
    _, lam_max, _ = lowest_and_highest_eigenvalues(s)
    print(f"omega_max^2: power iteration {lam:.6e} ({s.solver.power_iterations} iterations), "
          f"eigsh {lam_max:.6e}; critical step {s.solver.critical_time_step():.4e} s, "
          f"stable step {s.stable_time_step():.4e} s")
    assert lam <= lam_max * (1 + 1e-9)
    assert lam >= 0.99 * lam_max
    assert s.solver.power_iterations <= 200
    u0 = 1e-6 * np.random.default_rng(1).standard_normal((s.n_nodes, 3))

    def peak(dt, steps=600):
        s.set_state(displacement=u0)
        umax = 0.0
        try:
            for _ in range(steps):
                s.step(dt)
                umax = max(umax, float(np.abs(s.solver.u).max()))
        except InstabilityError:
            return math.inf
        return umax

    dt_c = s.solver.critical_time_step()
    assert peak(s.stable_time_step()) < 10 * np.abs(u0).max()
    assert peak(0.99 * dt_c) < 100 * np.abs(u0).max()
    assert peak(1.1 * dt_c) > 1e6 * np.abs(u0).max()


def test_rayleigh_mass_damping_decay(cantilever):
    """With C = alpha M the first mode (released from its eigenvector) decays with damping ratio
    xi = alpha/(2 omega1): the ratio of successive tip-displacement peaks is
    exp(-2 pi xi / sqrt(1 - xi^2)) (reference: damped single-degree-of-freedom oscillator); the
    damped critical step is (2/w)(sqrt(1+xi^2)-xi) (reference: Belytschko et al., Sec. 6.3)."""
    s0 = cantilever((20, 1, 1))
    lam1, _, mode = lowest_and_highest_eigenvalues(s0)
    w1 = math.sqrt(lam1)
    xi = 0.02
    s = ElasticStructure(s0.mesh, STEEL, fixed_groups=["root"], rayleigh_alpha=2 * xi * w1)
    z = s.dofmap.dofs_of(s.group_nodes("tip"), (2,))
    s.set_state(displacement=-1e-3 * mode / s.dofmap.to_dofs(mode)[z].mean())  # tip at -1 mm
    dt = s.stable_time_step()
    wmax = math.sqrt(s.max_eigenvalue())
    xi_max = xi * w1 / wmax
    assert s.solver.critical_time_step() == pytest.approx(
        2 / wmax * (math.sqrt(1 + xi_max**2) - xi_max), rel=1e-12)
    steps = int(3.2 * 2 * math.pi / w1 / dt)
    w = np.empty(steps)
    for k in range(steps):
        s.step(dt)
        w[k] = s.solver.u[z].mean()
    # successive minima (the beam starts at its most negative deflection)
    mins = [k for k in range(1, steps - 1) if w[k] < w[k - 1] and w[k] <= w[k + 1] and w[k] < 0]
    peaks = np.array([w[k] for k in mins])
    ratio = peaks[1:] / peaks[:-1]
    expected = math.exp(-2 * math.pi * xi / math.sqrt(1 - xi**2))
    print(f"damped peak ratios {ratio}, expected {expected:.4f}")
    assert len(ratio) >= 2
    assert ratio == pytest.approx(expected, abs=0.002)


def test_prescribed_displacement_reaches_static_solution(cantilever):
    """The tip face pulled by a prescribed axial displacement (ramped, with mass damping) settles
    to the static FE solution with the same Dirichlet data; the root reaction then balances the
    tip reaction and is within 2 % of E A delta / L (references: static FE solve, bar theory)."""
    s0 = cantilever((20, 1, 1))
    delta, ramp = 1e-5, 2e-3
    s = ElasticStructure(s0.mesh, STEEL, fixed_groups=["root"], rayleigh_alpha=2.0e3,
                         prescribed={"tip": lambda t: (delta * min(t / ramp, 1.0), 0.0, 0.0)})
    fixed = s.solver.fixed
    tip_x = s.dofmap.dofs_of(s.group_nodes("tip"), (0,))
    target = np.where(np.isin(fixed, tip_x), delta, 0.0)
    dt = s.stable_time_step()
    for _ in range(int(9e-3 / dt)):  # transient decays as exp(-alpha t / 2): 1e-4 at 9 ms
        s.step(dt)
    u_ref = np.zeros(s.dofmap.n_dofs)
    u_ref[fixed] = target
    free = s.solver.free
    u_ref[free] = sla.spsolve(s.K[free][:, free].tocsc(), -(s.K[free][:, fixed] @ target))
    err = np.abs(s.solver.u - u_ref).max() / delta
    r_root, r_tip = s.reaction("root"), s.reaction("tip")
    print(f"prescribed displacement: max |u - u_static| / delta = {err:.2e}; root reaction "
          f"{r_root}, E A delta / L = {E * A * delta / L:.4e}")
    assert err < 1e-3
    assert r_root + r_tip == pytest.approx(np.zeros(3), abs=1e-3 * E * A * delta / L)
    assert -r_root[0] == pytest.approx(E * A * delta / L, rel=0.02)
