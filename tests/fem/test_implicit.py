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


def test_energy_balance_closes_with_loads_damping_supports_and_impulses(beam_mesh):
    """A cantilever with Rayleigh damping (mass and stiffness), a pressure pulse on the tip, a
    root that moves (prescribed), impulses on the tip nodes; steps 30x the explicit critical
    step: the balance closes to 1e-9 of the energy put in, and the damping loss only grows."""
    s = ElasticStructure(beam_mesh, STEEL, fixed_groups=["root"], rayleigh_alpha=50.0,
                         rayleigh_beta=2e-6, integrator="implicit",
                         prescribed={"root": lambda t: (0.0, 0.0, 1e-5 * math.sin(2e3 * t))})
    s.add_surface_load("tip", traction=(0.0, 0.0, -1e5), history=lambda t: min(t / 1e-3, 1.0))
    explicit = ElasticStructure(beam_mesh, STEEL, fixed_groups=["root"])
    dt = 30.0 * explicit.critical_time_step()
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


def test_implicit_structure_refuses_ice_contact(tmp_path):
    """A case whose ice meets an implicit structure stops with one clear message (exit 2): the
    contact needs the surface's mobility over the step, which the nodal masses do not give."""
    src = tmp_path / "case.toml"
    src.write_text("""
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
""")
    with pytest.raises(InputError) as err:
        load_case(src)
    assert err.value.field == "structure[0].integrator"
    assert "contact" in err.value.message


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
