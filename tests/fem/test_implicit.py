"""The implicit Newmark integrator (average acceleration, :mod:`pdfem.fem.implicit`).

References: the trapezoidal rule's exact discrete solution of the undamped oscillator (its
amplification matrix has the eigenvalues exp(+-i 2 arctan(omega dt / 2)): no amplitude error
at any step, period lengthened to 2 pi / omega_bar with omega_bar dt = 2 arctan(omega dt / 2);
Hughes, The Finite Element Method, 2000, Sec. 9.1); the energy identity of the scheme
(kinetic + strain = work of the loads and supports - damping loss, to round-off); static FE
solutions with the same K (scipy spsolve).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from pdfem.case.schema import load_case
from pdfem.errors import InputError
from pdfem.fem.elasticity import ElasticMaterial
from pdfem.fem.implicit import Newmark
from pdfem.fem.mesh import load_mesh
from pdfem.fem.structure import ElasticStructure

L, H = 1.0, 0.1
STEEL = ElasticMaterial(density=7850.0, youngs_modulus=210e9, poisson_ratio=0.3)


@pytest.mark.parametrize("omega_dt", [0.1, 1.0, 10.0, 1000.0])
def test_oscillator_follows_the_trapezoidal_rule_exactly(omega_dt):
    """u(t_n) = cos(n omega_bar dt), omega_bar dt = 2 arctan(omega dt / 2), for steps far above
    the explicit limit omega dt = 2: unconditionally stable, no amplitude error."""
    k, m = 4.0e6, 2.5
    omega = math.sqrt(k / m)
    dt = omega_dt / omega
    s = Newmark(sp.csr_matrix([[k]]), np.array([m]))
    s.initialize(u=np.array([1.0]))
    wbar_dt = 2.0 * math.atan(0.5 * omega_dt)
    for n in range(1, 201):
        s.step(dt)
        assert s.u[0] == pytest.approx(math.cos(n * wbar_dt), abs=1e-10)
    assert math.isinf(s.stable_time_step()) and s.factorizations == 1
    assert s.kinetic_correction() == 0.0


@pytest.fixture(scope="module")
def beam_mesh(tmp_path_factory, gmsh_box):
    path = gmsh_box(tmp_path_factory.mktemp("beam") / "beam.msh", (L, H, H),
                    volume_groups=["beam"], face_groups={"root": ["x0"], "tip": ["x1"]},
                    divisions=(10, 1, 1))
    return load_mesh(path)


def _balance(s: ElasticStructure, e0: float, impulse_work: float) -> float:
    """Stored + damping loss - (initial + work of loads, supports and impulses), J."""
    stored = s.kinetic_energy() + s.strain_energy()
    return (stored + s.solver.damping_dissipated
            - (e0 + s.solver.work_external + s.solver.work_supports + impulse_work))


def _damped_cantilever(beam_mesh) -> tuple[ElasticStructure, float]:
    """The implicit cantilever with Rayleigh damping, a root moving as prescribed and a tip
    load ramp, and a step (s) 30 times its explicit critical step."""
    s = ElasticStructure(beam_mesh, STEEL, fixed_groups=["root"], rayleigh_alpha=50.0,
                         rayleigh_beta=2e-6, integrator="implicit",
                         prescribed={"root": lambda t: (0.0, 0.0, 1e-5 * math.sin(2e3 * t))})
    s.add_surface_load("tip", traction=(0.0, 0.0, -1e5), history=lambda t: min(t / 1e-3, 1.0))
    explicit = ElasticStructure(beam_mesh, STEEL, fixed_groups=["root"])
    return s, 30.0 * explicit.critical_time_step()


def test_energy_balance_closes_with_loads_damping_supports_and_impulses(beam_mesh):
    """A cantilever with Rayleigh damping (mass and stiffness), a pressure pulse on the tip, a
    root that moves (prescribed), impulses on the tip nodes; steps 30x the explicit critical
    step: the balance closes to 1e-9 of the energy put in, and the damping loss only grows."""
    s, dt = _damped_cantilever(beam_mesh)
    tip = s.group_nodes("tip")
    e0, impulses, lost, worst = 0.0, 0.0, 0.0, 0.0
    for n in range(300):
        if n % 50 == 7:
            dofs = s.dofmap.dofs_of(tip, (2,))
            jz = np.full(len(dofs), -0.05)
            impulses += float(np.sum(s.solver.v[dofs] * jz + 0.5 * jz * jz / s.solver.m[dofs]))
            s.solver.apply_impulse(dofs, jz)
        s.step(dt)
        assert s.solver.damping_dissipated >= lost
        lost = s.solver.damping_dissipated
        worst = max(worst, abs(_balance(s, e0, impulses)))
    put_in = abs(s.solver.work_external) + abs(s.solver.work_supports) + impulses
    print(f"energy put in {put_in:.4e} J, damping {lost:.3e} J, worst residual {worst:.2e} J")
    assert lost > 0.0 and put_in > 0.0
    assert worst < 1e-9 * put_in


def test_held_load_swings_about_the_static_deflection(beam_mesh):
    """Undamped, a tip load put on at t = 0 and held: the mean tip deflection over whole
    periods is the static FE deflection (within 1 %), and the peak is twice it (dynamic factor
    2 of a suddenly applied load, within 2 %), at 50 steps per period of the first mode."""
    s = ElasticStructure(beam_mesh, STEEL, fixed_groups=["root"], integrator="implicit")
    s.add_surface_load("tip", traction=(0.0, 0.0, -1e5))
    f = s.external_force_dofs()
    free = s.solver.free
    u = np.zeros_like(f)
    u[free] = sla.spsolve(s.K[free][:, free].tocsc(), f[free])
    tip = s.group_nodes("tip")
    static = float(-s.dofmap.to_nodal(u)[tip, 2].mean())
    d = 1.0 / np.sqrt(s.mass[free])
    scaled = s.K[free][:, free].multiply(d[:, None]).multiply(d[None, :]).tocsc()
    lam1 = sla.eigsh(scaled, k=1, sigma=0.0, which="LM", return_eigenvectors=False)[0]
    period = 2.0 * math.pi / math.sqrt(lam1)
    dt = period / 50.0
    w = []
    for _ in range(50 * 10):
        s.step(dt)
        w.append(float(-s.displacement()[tip, 2].mean()))
    w = np.array(w)
    assert w.mean() == pytest.approx(static, rel=0.01)
    assert w.max() == pytest.approx(2.0 * static, rel=0.02)


def test_implicit_structure_on_a_ship_is_refused(tmp_path):
    """An implicit structure attached to a ship, or a ship itself, stops with one clear
    message (exit 2) naming the integrator; ice contact and a moving frame are accepted."""
    base = """
[run]
end_time = 1e-3
output_interval = 1e-3
[[ice]]
name = "ice"
dx = 0.05
shape = { box = { min = [0.0, 0.0, 0.1], max = [0.2, 0.2, 0.3] } }
material = { density = 900.0, youngs_modulus = 4e9, poisson_ratio = 0.3 }
[[structure]]
name = "plate"
mesh = "hull_panel"
fixed_groups = ["fixed"]
integrator = "implicit"
"""
    src = tmp_path / "case.toml"
    src.write_text(base + 'motion = { angular_velocity = [0.0, 0.0, 1.0] }\n')
    assert load_case(src).structures[0].integrator == "implicit"
    src.write_text(base.replace('name = "plate"', 'name = "plate"\nkind = "ship"')
                   .replace('fixed_groups = ["fixed"]\n', ""))
    with pytest.raises(InputError) as err:
        load_case(src)
    assert err.value.field == "structure[0].integrator"
    assert "ship" in err.value.message


def _small_system(n=7, seed=3):
    """A random SPD stiffness (N/m), lumped masses (kg), one held DOF, Rayleigh damping."""
    rng = np.random.default_rng(seed)
    b = rng.standard_normal((n, n))
    k = b @ b.T * 2e4 + np.eye(n) * 5e3
    m = rng.uniform(0.05, 2.0, n)
    return k, m, rng


def test_end_impulse_adds_half_step_times_A_inverse_J():
    """Average-acceleration Newmark, step dt, a contact impulse J on the step just taken: the
    amended end state differs from the free step by u: (dt/2) A^-1 J, v: A^-1 J with
    A = (1 + alpha dt/2) M + (beta dt/2 + dt^2/4) K on the free DOFs (dense solve), the
    impulse on the held DOF goes to its support, and after it M a + C v + K u = f holds on the
    free DOFs (the force 2 J / dt is out of the state); the same as a step taken with the
    extra end force 2 J / dt. Its returned work is J . (u_new - u) / dt."""
    k, m, rng = _small_system()
    n, dt, alpha, beta = len(m), 4e-3, 3.0, 1e-4

    def make():
        s = Newmark(sp.csr_matrix(k), m, fixed_dofs=[n - 1], rayleigh_alpha=alpha,
                    rayleigh_beta=beta)
        s.initialize(u=rng.standard_normal(n) * 1e-3, v=rng.standard_normal(n) * 0.1)
        return s
    seed_state = rng.bit_generator.state
    free_step = make()
    rng.bit_generator.state = seed_state
    hit = make()
    rng.bit_generator.state = seed_state
    forced = make()
    f = rng.standard_normal(n)
    j = rng.standard_normal(n)
    u0 = hit.u.copy()
    free_step.step(dt, f)
    hit.step(dt, f)
    work = hit.end_impulse(np.arange(n), j)
    jf = np.where(np.arange(n) < n - 1, j, 0.0)
    forced.step(dt, f + 2.0 * jf / dt)
    a_mat = (1.0 + 0.5 * alpha * dt) * np.diag(m) + (0.5 * beta * dt + 0.25 * dt * dt) * k
    response = np.zeros(n)
    response[:-1] = np.linalg.solve(a_mat[:-1, :-1], j[:-1])
    np.testing.assert_allclose(hit.u - free_step.u, 0.5 * dt * response, rtol=1e-10,
                               atol=1e-14)
    np.testing.assert_allclose(hit.v - free_step.v, response, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(hit.u, forced.u, rtol=1e-12, atol=1e-16)
    c = alpha * np.diag(m) + beta * k
    resid = m * hit.a + c @ hit.v + k @ hit.u - f
    assert np.abs(resid[:-1]).max() < 1e-9 * np.abs(f).max()
    assert work == pytest.approx(float(jf @ (hit.u - u0)) / dt, rel=1e-12)


def test_energy_of_a_newmark_structure_hit_by_contact_impulses_closes(beam_mesh):
    """A damped cantilever with a moving root and a load ramp, stepped at 30 times the
    explicit limit, takes contact impulses on its tip nodes that amend some of its steps
    (twice on one step): kinetic + strain + damping loss = work of loads, supports and the
    impulses' returned work, to 1e-9 of the energy put in; the loads' work does not hold the
    contact's."""
    s, dt = _damped_cantilever(beam_mesh)
    dofs = s.dofmap.dofs_of(s.group_nodes("tip"), (1, 2))
    contact, worst = 0.0, 0.0
    for n in range(300):
        s.step(dt)
        if n % 20 == 3:
            contact += s.solver.end_impulse(dofs, np.full(len(dofs), -0.05))
            if n % 40 == 3:
                contact += s.solver.end_impulse(dofs[::2], np.full(len(dofs[::2]), 0.03))
        worst = max(worst, abs(_balance(s, 0.0, contact)))
    put_in = abs(s.solver.work_external) + abs(s.solver.work_supports) + abs(contact)
    print(f"put in {put_in:.4e} J, contact work {contact:.3e} J, worst residual {worst:.2e} J")
    assert abs(contact) > 0.01 * put_in
    assert worst < 1e-9 * put_in


def test_probed_compliance_blocks_match_the_exact_ones(tmp_path, gmsh_box):
    """The (3, 3) blocks of A^-1 between nearby nodes of a plate's contact face by probing
    against one solve per column: the diagonal blocks within 1e-3 (Frobenius, relative to the
    block), the couplings within 1e-3 of the diagonal block; symmetric (C_ik = C_ki^T),
    positive definite on the diagonal, zero rows and columns on held DOFs; the response to a
    uniform share equals the exact one to 2 % (the couplings reach 5 decay lengths)."""
    path = gmsh_box(tmp_path / "plate.msh", (0.4, 0.3, 0.02), volume_groups=["plate"],
                    face_groups={"contact": ["z1"], "fixed": ["x0"]}, divisions=(10, 8, 1))
    s = ElasticStructure(load_mesh(path), STEEL, fixed_groups=["fixed"], contact_group="contact",
                         integrator="implicit")
    dt = 20.0 * ElasticStructure(load_mesh(path), STEEL, fixed_groups=["fixed"]
                                 ).critical_time_step()
    s.step(dt)
    compliance = s.surface_compliance()
    c = compliance.coupling
    sol = s.solver
    table = s._surface_dofs.reshape(-1, 3)
    columns = np.zeros((sol.n, len(table), 3))       # response everywhere to each node's load
    for i, dofs in enumerate(table):
        for d in range(3):
            if sol.free[dofs[d]]:
                rhs = np.zeros(sol.n)
                rhs[dofs[d]] = 1.0
                columns[sol.free, i, d] = 0.5 * sol._lu.solve(rhs[sol.free])
    rows = np.repeat(np.arange(len(table)), np.diff(c.start))
    exact = columns[table[rows][:, :, None], c.index[:, None, None], np.arange(3)]
    diag = compliance.diagonal()
    scale = np.linalg.norm(diag, axis=(1, 2))
    held = ~sol.free[table].all(axis=1)
    free_rows = ~held[rows] & ~held[c.index]
    err = np.linalg.norm(c.blocks - exact, axis=(1, 2)) / np.maximum(scale[rows], 1e-300)
    assert held.any() and np.all(diag[held][~sol.free[table][held]] == 0.0)
    assert np.max(err[free_rows & (rows == c.index)]) < 1e-3
    assert np.max(err[free_rows]) < 1e-3
    assert np.mean(rows != c.index) > 0.8                  # neighbours were kept
    twin = np.lexsort((rows, c.index))
    np.testing.assert_array_equal(c.blocks, c.blocks[twin].transpose(0, 2, 1))
    assert np.linalg.eigvalsh(diag[~held]).min() > 0.0
    uniform = compliance.response(np.ones(len(table)))
    full = columns[table].sum(axis=2)                      # sum_k C_ik, (Ns, 3, 3)
    np.testing.assert_allclose(np.diagonal(uniform[~held], axis1=1, axis2=2),
                               np.diagonal(full[~held], axis1=1, axis2=2), rtol=0.02)


def test_restart_from_a_checkpoint_continues_bit_for_bit(beam_mesh):
    """A state saved mid-run and restored into a new structure continues with the same bits
    (the factorisation is made again for the step; reference: the uninterrupted run)."""
    def make():
        s = ElasticStructure(beam_mesh, STEEL, fixed_groups=["root"], integrator="implicit",
                             rayleigh_alpha=20.0)
        s.add_surface_load("tip", traction=(0.0, 0.0, -1e5))
        return s
    a = make()
    dt = 2e-5
    for _ in range(40):
        a.step(dt)
    state = a.checkpoint_state()
    for _ in range(40):
        a.step(dt)
    b = make()
    b.restore_state(state)
    for _ in range(40):
        b.step(dt)
    assert np.array_equal(a.solver.u, b.solver.u) and np.array_equal(a.solver.v, b.solver.v)
    assert a.solver.damping_dissipated == b.solver.damping_dissipated
