"""Coupled ice-structure time stepping (pdfem.coupling.coupler): conservation and subcycling.

References: conservation of linear momentum (a free ice block hitting a free elastic block,
nothing else acting: the total momentum, counting the impulse in transit, is constant to
round-off), conservation of energy (unbreakable ice, no friction: kinetic + strain energy of
both bodies plus the energy lost in contact equal the ice's initial kinetic energy within
2 %; the loss itself is measured as minus the work of the contact impulses, each taken at the
velocity Verlet time it acts), and the
unsubcycled run at the small step as the reference for subcycling.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from support.meshes import write_box
from pdfem.coupling.contact import SurfaceContact
from pdfem.coupling.coupler import ContactPair, Coupler, substep_counts
from pdfem.fem.elasticity import ElasticMaterial
from pdfem.fem.structure import ElasticStructure
from pdfem.pd.body import IceBody
from pdfem.pd.materials.lps import IceMaterial
from pdfem.geometry.shapes import Box

ICE = IceMaterial(density=900.0, youngs_modulus=4.0e9, poisson_ratio=0.3)  # unbreakable
V0 = 2.0  # m/s, ice towards -x


@pytest.fixture(scope="module")
def block_msh(tmp_path_factory):
    path = tmp_path_factory.mktemp("block") / "block.msh"
    return write_box(path, (0.1, 0.1, 0.1), divisions=(4, 4, 4),
                     face_groups={"contact": ("x0", "x1", "y0", "y1", "z0", "z1")})


def _setup(block_msh, youngs_modulus, density=900.0):
    st = ElasticStructure.from_file(block_msh, ElasticMaterial(density, youngs_modulus, 0.3),
                                    contact_group="contact", name="block")
    dx = 0.01
    ice = IceBody.from_shape("ice", Box((0.0955, 0.01, 0.01), (0.1755, 0.09, 0.09)), ICE, dx,
                             3.015 * dx)
    ice.v[:, 0] = -V0
    pair = ContactPair("ice-block", ice, st, SurfaceContact(st, 0.5 * dx))
    return ice, st, pair


def _run(block_msh, youngs_modulus, density=900.0, end=6e-4, substeps=0, small_step=False):
    ice, st, pair = _setup(block_msh, youngs_modulus, density)
    dt_ice = 0.8 * ice.stable_time_step()
    dt_st = 0.8 * st.solver.critical_time_step()
    if small_step:
        dt, n_ice, n_st = min(dt_ice, dt_st), 1, 1
    else:
        dt, n_ice, n_st = substep_counts(dt_ice, dt_st, substeps)
    c = Coupler([ice], [st], [pair], dt, n_ice, n_st)
    c.start()
    p0 = ice.momentum() + st.momentum()
    e0 = ice.kinetic_energy() + ice.strain_energy()
    drift, umax = 0.0, 0.0
    forces = []
    for _ in range(int(round(end / dt))):
        c.step()
        p = ice.momentum() + st.momentum()
        drift = max(drift, np.abs(p - p0).max())
        forces.append(-pair.force[0])  # the ice pushes the block towards -x
        umax = max(umax, np.abs(st.displacement()).max())
    e1 = ice.kinetic_energy() + ice.strain_energy() + st.kinetic_energy() + st.strain_energy()
    return dict(p0=p0, drift=drift, e0=e0, e1=e1, lost=c.contact_dissipated,
                force=np.array(forces), dt=dt, umax=umax, n_ice=n_ice, n_st=n_st, ice=ice, st=st)


@pytest.mark.parametrize("youngs_modulus, density, subcycling", [
    (4.0e9, 900.0, "none"), (4.0e11, 900.0, "structure"), (4.0e10, 9.0e4, "ice")])
def test_free_blocks_conserve_momentum_and_energy(block_msh, youngs_modulus, density, subcycling):
    """A free ice block (2 m/s) hits a free elastic block and rebounds. Total linear momentum
    is conserved to round-off over the whole impact, with and without subcycling of either
    side; kinetic + strain energy of both after the impact plus the contact loss equals the
    initial kinetic energy within 1 % (nothing breaks, no friction). The contact of Eq. (5) is
    perfectly plastic particle by particle, so some energy is lost (9-27 % here, with 8 particle
    layers; it shrinks as the ice is refined), but never created."""
    r = _run(block_msh, youngs_modulus, density, substeps=1 if subcycling == "none" else 0)
    assert {"none": (1, 1), "structure": (1, r["n_st"]), "ice": (r["n_ice"], 1)}[subcycling] \
        == (r["n_ice"], r["n_st"])
    if subcycling != "none":
        assert max(r["n_ice"], r["n_st"]) >= 2
    p0 = abs(r["p0"][0])
    assert r["drift"] <= 1e-10 * p0  # round-off of the internal force sums
    assert r["st"].momentum()[0] < -0.3 * p0  # the block was really hit
    assert 0.0 < r["lost"] < 0.3 * r["e0"]
    assert r["e1"] + r["lost"] == pytest.approx(r["e0"], rel=0.01)


@pytest.fixture(scope="module")
def clamped_block_msh(tmp_path_factory):
    path = tmp_path_factory.mktemp("clamped") / "clamped.msh"
    return write_box(path, (0.1, 0.1, 0.1), divisions=(4, 4, 4),
                     face_groups={"contact": ("x1",), "fixed": ("x0",)})


def _push(msh, small_step):
    """An ice block resting on the face x = 0.1 of a block clamped at x = 0, pushed by its
    back layers (velocity ramped to 1 m/s over 0.1 ms); peak force on the block (N) and peak
    mean axial displacement of the block's nodes (m), the steps used, and the energy the
    contacts dissipated (J) after each coupling step."""
    st = ElasticStructure.from_file(msh, ElasticMaterial(900.0, 4.0e11, 0.3),
                                    fixed_groups=["fixed"], contact_group="contact", name="block")
    dx = 0.01
    ice = IceBody.from_shape("ice", Box((0.1 + 1e-9 - dx / 2, 0.01, 0.01),
                                        (0.18 + 1e-9 - dx / 2, 0.09, 0.09)), ICE, dx, 3.015 * dx)
    ice.add_velocity_constraint(ice.x0[:, 0] > ice.x0[:, 0].max() - 2.5 * dx, (-1.0, 0.0, 0.0),
                                ramp_time=1e-4)
    pair = ContactPair("ice-block", ice, st, SurfaceContact(st, 0.5 * dx))
    dt_ice, dt_st = 0.8 * ice.stable_time_step(), 0.8 * st.solver.critical_time_step()
    dt, n_ice, n_st = (min(dt_ice, dt_st), 1, 1) if small_step else substep_counts(dt_ice, dt_st)
    c = Coupler([ice], [st], [pair], dt, n_ice, n_st)
    c.start()
    force, umax, lost = [], 0.0, []
    for _ in range(int(round(3e-4 / dt))):
        c.step()
        force.append(-pair.force[0])
        umax = max(umax, np.abs(st.displacement()[:, 0]).mean())
        lost.append(c.contact_dissipated)
    return np.array(force), umax, dt, n_st, np.array(lost)


def test_subcycled_structure_matches_the_small_step(clamped_block_msh):
    """Ice pushed against a stiff clamped block (the FEM subcycles, 12 substeps) against the
    run with both sides at the FEM step (reference): peak contact force within 1 % (measured
    0.02 %; 6.8 % before the ice drifted with each substep's velocity) and the block's peak
    mean axial displacement within 1 % (measured 0.05 %). The force is compared as the
    impulse per coupling step of the subcycled run (the same windows in both runs). The
    energy the contacts dissipate (second law: plastic impulses only take energy) is never
    negative in either run, and the subcycled run's loss is within 15 % of the reference's
    (measured 9 %; 73 % below it when the ice met the substeps with its mid-step velocity)."""
    f_sub, u_sub, dt_sub, n, lost_sub = _push(clamped_block_msh, False)
    f_ref, u_ref, dt_ref, _, lost_ref = _push(clamped_block_msh, True)
    assert n >= 2 and dt_sub == pytest.approx(n * dt_ref, rel=1e-12)
    windows = f_ref[: len(f_ref) // n * n].reshape(-1, n).mean(axis=1)
    assert f_sub.max() > 1e3  # N: a real load
    assert f_sub.max() == pytest.approx(windows.max(), rel=0.01)
    assert u_sub == pytest.approx(u_ref, rel=0.01)
    assert lost_sub.min() >= 0.0 and lost_ref.min() >= 0.0
    assert lost_ref[-1] > 0.1  # J: the contacts did dissipate
    assert lost_sub[-1] == pytest.approx(lost_ref[-1], rel=0.15)


def test_substep_counts():
    """The faster side takes floor(slow / fast) steps (or the given count); the coupling step
    never exceeds the slower side's step."""
    assert substep_counts(1.0, float("inf")) == (1.0, 1, 1)
    assert substep_counts(1.0, 3.5) == (3.0, 3, 1)
    assert substep_counts(3.5, 1.0) == (3.0, 1, 3)
    assert substep_counts(3.5, 1.0, substeps=2) == (2.0, 1, 2)
    assert substep_counts(1.0, 3.5, substeps=5) == (3.5, 5, 1)


def test_cylinder_impact_same_with_pair_and_full_family_loops(tmp_path):
    """The seed paper's benchmark (Fig. 7: rigid cylinder striking an ice plate, no damage) run
    with the particle-pair loop and with the full-family loop gives the same plate
    displacement history and the same load on the cylinder (seed Fig. 8), to round-off;
    coarsened to dx = 0.02 m for speed."""
    import dataclasses
    from pathlib import Path

    from pdfem.case.schema import load_case
    from pdfem.run.driver import run_case
    from pdfem.output import read_results

    case = load_case(Path(__file__).resolve().parents[2] / "models" / "cylinder_ice_plate.toml")
    ice = dataclasses.replace(case.ice[0], dx=0.02, horizon=3.015 * 0.02)
    cyl = case.structures[0]  # moved to 0.5 mm from the coarser plate's edge particles
    cyl = dataclasses.replace(cyl, params=dict(cyl.params, center_y=0.5905))
    out = {}
    for loop in ("pairs", "full_family"):
        run = dataclasses.replace(case.run, pd_loop=loop, end_time=1.6e-3, output_interval=4e-4)
        c = dataclasses.replace(case, run=run, ice=(ice,), structures=(cyl,))
        out[loop] = read_results(run_case(c, tmp_path / loop, quiet=True).results)
    a, b = out["pairs"], out["full_family"]
    u_a, u_b = a["ice"]["plate"]["u"], b["ice"]["plate"]["u"]
    assert np.abs(u_a[-1, :, 1]).max() > 1e-3  # the plate was pushed (m)
    np.testing.assert_allclose(u_a, u_b, rtol=0, atol=1e-10 * np.abs(u_a).max())
    fa, fb = a["histories"]["loads/cylinder"]["force"], b["histories"]["loads/cylinder"]["force"]
    assert np.abs(fa[:, 1]).max() > 1e3  # N
    np.testing.assert_allclose(fa, fb, rtol=0, atol=1e-8 * np.abs(fa).max())


def test_two_ice_bodies_and_two_structures_in_one_case(tmp_path):
    """Two ice cubes, each struck by its own rigid sphere, in one case with two named contact
    pairs: each structure's load history is the sum of its pairs' (here exactly its one
    pair's), each pair sees only its own ice, and the impulse on each sphere equals the
    momentum its cube gained (momentum conservation, the spheres moving as prescribed)."""
    from pdfem.case.schema import parse_case
    from pdfem.run.driver import run_case
    from pdfem.output import read_results

    text = """
[run]
end_time = 1.0e-3
output_interval = 5.0e-4
[[ice]]
name = "a"
dx = 0.01
shape = { box = { min = [0.0, 0.0, 0.0], max = [0.06, 0.06, 0.06] } }
material = { critical_stretch = 1.0 }
[[ice]]
name = "b"
dx = 0.01
shape = { box = { min = [1.0, 0.0, 0.0], max = [1.06, 0.06, 0.06] } }
material = { critical_stretch = 1.0 }
[[structure]]
name = "ball_a"
kind = "rigid"
mesh = "indenters"
params = { shape = "sphere", radius = 0.03, center_x = 0.03, center_y = 0.03, center_z = 0.0845, element_size = 0.006 }
motion = { velocity = [0.0, 0.0, -1.0] }
[[structure]]
name = "ball_b"
kind = "rigid"
mesh = "indenters"
params = { shape = "sphere", radius = 0.03, center_x = 1.03, center_y = 0.03, center_z = 0.0845, element_size = 0.006 }
motion = { velocity = [0.0, 0.0, -2.0] }
[[contact]]
ice = "a"
structure = "ball_a"
[[contact]]
ice = "b"
structure = "ball_b"
"""
    case = parse_case(text, "two.toml", tmp_path)
    r = read_results(run_case(case, tmp_path / "out", quiet=True).results)
    h = r["histories"]
    for ice, ball in (("a", "ball_a"), ("b", "ball_b")):
        pair, load = h[f"contacts/{ice}-{ball}"], h[f"loads/{ball}"]
        np.testing.assert_array_equal(pair["force"], load["force"])
        dt = r["meta"]["time_step"]
        impulse = load["force"].sum(axis=0) * dt          # N s given to the sphere so far
        rho, vol = 900.0, r["ice"][ice]["volume"]
        # the last step's impulse is in transit: the ice already has it, the sphere's history too
        p_ice = rho * (vol[:, None] * r["ice"][ice]["v"][-1]).sum(axis=0)
        assert abs(p_ice[2]) > 1e-3
        np.testing.assert_allclose(p_ice, -impulse, rtol=1e-9, atol=1e-12)
    # the faster sphere pushes harder
    assert abs(h["loads/ball_b"]["force"][:, 2]).max() > abs(h["loads/ball_a"]["force"][:, 2]).max()


@pytest.mark.slow
def test_hull_panel_subcycling_matches_the_small_step(tmp_path):
    """Ice resting on the elastic hull panel (models/hull_panel.py, coarse) and pushed by its
    back layers (ramped to 1 m/s over 0.5 ms): the run with the structure subcycling against
    the run with both sides at the structure's step gives the same peak ice force within 1 %
    (measured 0.12 %; 5.1 % before the ice drifted with each substep's velocity) and the same
    peak panel displacement within 1 % (measured 0.005 %). The force is compared as ice loads
    are reported, averaged over windows of about 0.1 ms (8 coupling steps of the subcycled run,
    the same windows in both runs): step by step the two differ by the ice's own time-step
    error (its step is 21 times longer when the structure subcycles)."""
    import dataclasses

    from pdfem.case.schema import parse_case
    from pdfem.run.driver import run_case
    from pdfem.run.build_structures import build_structure
    from pdfem.output import read_results

    text = """
[run]
end_time = 2.0e-3
output_interval = 5.0e-4
substeps = {substeps}
[[ice]]
name = "floe"
dx = 0.04
shape = {{ box = {{ min = [0.8, 0.4, -0.019999], max = [1.2, 0.8, 0.140001] }} }}
material = {{ critical_stretch = 1.0 }}
prescribed_velocity = [ {{ region = {{ box = {{ min = [0.7, 0.3, 0.09], max = [1.3, 0.9, 0.2] }} }}, velocity = [0.0, 0.0, -1.0], ramp_time = 5.0e-4 }} ]
[[structure]]
name = "panel"
mesh = "hull_panel"
params = {{ element_size = 0.12 }}
fixed_groups = ["fixed"]
[[monitor]]
name = "centre"
structure = "panel"
point = [1.0, 0.6, 0.0]
"""
    runs = {}
    for sub in (0, 1):
        case = parse_case(text.format(substeps=sub), "panel.toml", tmp_path)
        if sub == 1:  # both sides at the structure's step: the ice steps with it
            st = build_structure(case.structures[0], tmp_path / "mesh", "panel.toml")
            step = case.run.safety_factor * st.solver.critical_time_step()
            case = dataclasses.replace(case, run=dataclasses.replace(case.run, time_step=step))
        r = read_results(run_case(case, tmp_path / f"run{sub}", quiet=True).results)
        runs[sub] = (r["meta"], r["histories"])
    (m_sub, h_sub), (m_ref, h_ref) = runs[0], runs[1]
    n = int(m_sub["structure_substeps"])
    assert n >= 2 and int(m_ref["structure_substeps"]) == 1
    f_sub = -h_sub["loads/panel"]["force"][1:, 2]
    f_ref = -h_ref["loads/panel"]["force"][1:, 2]
    m = 8
    w_sub = f_sub[: len(f_sub) // m * m].reshape(-1, m).mean(axis=1)
    w_ref = f_ref[: len(f_ref) // (n * m) * n * m].reshape(-1, n * m).mean(axis=1)
    assert w_sub.max() > 1e4  # N
    assert w_sub.max() == pytest.approx(w_ref.max(), rel=0.01)
    u_sub = np.abs(h_sub["monitors/centre"]["u"]).max()
    u_ref = np.abs(h_ref["monitors/centre"]["u"]).max()
    assert u_sub == pytest.approx(u_ref, rel=0.01)


def test_bar_impact_on_a_rigid_wall_follows_elastic_wave_theory():
    """A slender unbreakable ice bar hits a fixed rigid wall end-on at v = 1 m/s. One-dimensional
    elastic impact theory (e.g. Johnson, Impact Strength of Materials, ch. 1): the contact
    lasts 2 L / c with c = sqrt(E / rho), the wall force is rho c A v meanwhile, and the
    total impulse on the wall equals the bar's momentum change (momentum conservation, to
    round-off). Duration and mean force within 5 %."""
    from pdfem.motion.rigid import RigidBody

    dx, n_side, length, v0 = 0.005, 4, 0.3, 1.0
    side = n_side * dx
    wall = RigidBody(np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float),
                     np.array([[0, 1, 2], [0, 2, 3]]), name="wall")
    bar = IceBody.from_shape("bar", Box((0.0, 0.0, 1e-6 - dx / 2), (side, side, length + 1e-6 - dx / 2)),
                             ICE, dx, 3.015 * dx)
    bar.v[:, 2] = -v0
    pair = ContactPair("bar-wall", bar, wall, SurfaceContact(wall, 0.5 * dx))
    dt = 0.8 * bar.stable_time_step()
    c = Coupler([bar], [wall], [pair], dt)
    c.start()
    p0 = bar.momentum()[2]
    c_bar = math.sqrt(ICE.youngs_modulus / ICE.density)
    t_contact = 2 * length / c_bar
    forces = []
    for _ in range(int(1.6 * t_contact / dt)):
        c.step()
        forces.append(pair.force[2])
    forces = np.array(forces)
    on = np.flatnonzero(forces != 0.0)
    duration = (on[-1] - on[0] + 1) * dt
    assert duration == pytest.approx(t_contact, rel=0.05)
    impulse = forces.sum() * dt
    assert impulse == pytest.approx(-(bar.momentum()[2] - p0), rel=1e-10)
    plateau = -forces[on[0] + 2:on[-1] - 1].mean()   # the first-touch step left out
    assert plateau == pytest.approx(ICE.density * c_bar * side * side * v0, rel=0.05)
