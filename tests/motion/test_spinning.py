"""Elastic structures in a moving frame (:mod:`pdfem.motion.frame_structure`, :mod:`pdfem.motion.moving_frame`).

References: the radial stress of a bar spinning about its root, rho omega^2 (R^2 - r^2) / 2,
from equilibrium d sigma / dr = -rho omega^2 r with a free tip (Timoshenko & Goodier 1970,
rotating bodies); rigid-body kinematics x = c + R (X - c0 + u_e) with R the rotation by
theta = omega (t - T/2) about the fixed axis after a linear ramp of duration T.
"""

from __future__ import annotations

import math
from importlib.resources import files

import numpy as np
import pytest

from pdfem.fem.elasticity import ElasticMaterial
from pdfem.motion.moving_frame import MovingFrame
from pdfem.motion.frame_structure import FrameStructure
from pdfem.fem.structure import ElasticStructure
from pdfem.meshing.runner import mesh_model
from pdfem.validation.case import Outcome, load_validation_case, run_and_read
from pdfem.validation.cases import spinning

STEEL = ElasticMaterial(7850.0, 210e9, 0.3)


@pytest.fixture(scope="module")
def bar_mesh(tmp_path_factory):
    """A 0.5 m x 0.1 m x 0.1 m bar of 5 x 1 x 1 hexahedra, root face x0 "fixed", tip "contact"."""
    path = tmp_path_factory.mktemp("bar") / "bar.msh"
    mesh_model(str(files("pdfem.models").joinpath("validation/box.py")), {
        "length_x": 0.5, "divisions_x": 5, "divisions_y": 1, "divisions_z": 1,
        "fixed_faces": "x0", "loaded_faces": "", "contact_faces": "x1"}, path)
    return path


def _bar(path, frame=None, **kwargs):
    extra = {} if frame is None else {"frame": frame}
    cls = ElasticStructure if frame is None else FrameStructure
    return cls.from_file(path, STEEL, fixed_groups=["fixed"], contact_group="contact", **kwargs,
                         **extra)


@pytest.mark.slow
def test_spinning_bar_radial_stress(tmp_path):
    """The quick validation case: mean sigma_xx at the element centres of 0.2 R..0.8 R within
    3 % of rho omega^2 (R^2 - r^2) / 2."""
    case = spinning.quick(load_validation_case("spinning_bar.toml"))
    outcome = Outcome(case, run_and_read(case, tmp_path), tmp_path, 0.0)
    r, sigma, theory = spinning.stress_profile(outcome)
    keep = (r >= 0.1) & (r <= 0.4)
    assert keep.sum() >= 3
    np.testing.assert_allclose(sigma[keep], theory[keep], rtol=0.03)
    assert abs(spinning.measure(outcome) - 1.0) < 0.03
    fields = outcome.data["structure"]["bar"]
    assert set(fields) >= {"u", "u_elastic", "v", "von_mises"}


def test_translation_only_reproduces_the_still_structure_bit_for_bit(bar_mesh):
    """A frame moving at a constant velocity brings no inertial load: the elastic displacement
    equals the still structure's exactly, and u is u_elastic plus V t."""
    still = _bar(bar_mesh)
    moving = _bar(bar_mesh, MovingFrame(velocity=(3.0, -1.0, 0.5), center=(0.0, 0.05, 0.05)))
    for s in (still, moving):
        s.add_surface_load("contact", traction=(1e5, 0.0, -2e5))
        s.set_state()
    dt = still.stable_time_step()
    for _ in range(200):
        still.step(dt)
        moving.step(dt)
    assert np.array_equal(still.displacement(), moving.displacement())
    assert np.array_equal(still.velocity(), moving.velocity())
    out = moving.output_fields()
    shift = np.array([3.0, -1.0, 0.5]) * moving.time
    np.testing.assert_allclose(out["u"], out["u_elastic"] + shift, rtol=0, atol=1e-12)


def test_total_displacement_is_elastic_plus_rigid_motion(bar_mesh):
    """u = c(t) - c0 + R(theta) (X - c0 + u_e) - (X - c0), theta = omega (t - T / 2) about z."""
    omega, ramp, c0, vel = 50.0, 1e-3, np.array([0.0, 0.05, 0.05]), np.array([0.0, 0.0, 2.0])
    s = _bar(bar_mesh, MovingFrame((0.0, 0.0, omega), tuple(c0), tuple(vel), ramp),
             rayleigh_alpha=2000.0)
    dt = s.stable_time_step()
    while s.time < 1.5 * ramp:
        s.step(dt)
    t, out = s.time, s.output_fields()
    theta = omega * (t - 0.5 * ramp)
    rot = np.array([[math.cos(theta), -math.sin(theta), 0.0],
                    [math.sin(theta), math.cos(theta), 0.0], [0.0, 0.0, 1.0]])
    r = s.points - c0
    expected = vel * (t - 0.5 * ramp) + (r + out["u_elastic"]) @ rot.T - r
    assert np.abs(out["u_elastic"]).max() > 0.0
    np.testing.assert_allclose(out["u"], expected, rtol=0, atol=1e-12)
    # the contact surface is the same moving, deformed surface
    np.testing.assert_allclose(s.surface_points(), (s.points + out["u"])[s.surface_nodes],
                               rtol=0, atol=1e-12)


def test_world_impulse_changes_the_world_velocity_by_impulse_over_mass(bar_mesh):
    """An impulse J (world axes) on a free surface node changes its true velocity by J / m,
    whatever the frame's angle (the impulse is turned into frame axes)."""
    s = _bar(bar_mesh, MovingFrame((0.0, 0.0, 80.0), (0.0, 0.05, 0.05)))
    dt = s.stable_time_step()
    for _ in range(100):
        s.step(dt)
    j = np.zeros((len(s.surface_nodes), 3))
    j[0] = (0.3, -0.2, 0.1)
    v0 = s.surface_velocities()
    s.apply_surface_impulse(j)
    dv = s.surface_velocities() - v0
    np.testing.assert_allclose(dv[0], j[0] * s.surface_inverse_mass()[0], rtol=1e-12)
    np.testing.assert_allclose(dv[1:], 0.0, atol=1e-15)


def test_flapwise_frequency_follows_southwell(tmp_path):
    """The validation case: first flapwise frequency of a slender bar spinning at about its own
    rest frequency within 5 % of Southwell's sqrt(omega_0^2 + 1.193 omega^2) (Euler-Bernoulli
    omega_0), and the rise with speed at every speed of the sweep."""
    case = load_validation_case("spinning_bar_southwell.toml")
    data = spinning.solve_flapwise(case, tmp_path)
    np.testing.assert_allclose(data["frequency"], spinning.southwell(case, data["speed"]),
                               rtol=0.05)
    assert np.all(np.diff(data["frequency"]) > 0.0)


def test_time_stepping_uses_the_rotating_stiffness(bar_mesh):
    """At full speed, the acceleration the integrator gives a displacement phi (less that of the
    undeformed spinning bar) is -M^-1 (K + K_sigma - spin softening) phi on the free DOFs."""
    s = _bar(bar_mesh, MovingFrame((0.0, 0.0, 300.0), (0.0, 0.05, 0.05)))
    phi = np.zeros((s.n_nodes, 3))
    phi[:, 2] = 1e-5 * (s.points[:, 0] / 0.5) ** 2       # a flapwise shape, zero at the root
    phi[:, 1] = -3e-6 * (s.points[:, 0] / 0.5) ** 2
    s.set_state()
    a0 = s.solver.a.copy()
    s.set_state(displacement=phi)
    u = s.solver.u
    expected = -(s.rotating_stiffness() @ u) / s.solver.m
    free = s.solver.free
    np.testing.assert_allclose((s.solver.a - a0)[free], expected[free],
                               rtol=1e-9, atol=1e-9 * np.abs(expected).max())
    assert s.K_sigma is not None and abs(s.K_sigma @ u).max() > 0.0


def test_energy_balance_in_the_frame_and_checkpoint_restart(bar_mesh):
    """With the drive's work in support_work, kinetic + correction + strain - (load work +
    support work - damping) stays at its value after the first step (the integrator's start-up
    term -(dt^2/8) a0.M a0 of the initial centrifugal/Euler acceleration) to round-off; and a
    restored checkpoint continues bit for bit."""
    s = _bar(bar_mesh, MovingFrame((0.0, 0.0, 200.0), (0.0, 0.05, 0.05), (1.0, 0.0, 0.0), 2e-3),
             rayleigh_alpha=1000.0)
    dt = s.stable_time_step()

    def residual():
        e = s.energy_terms()
        return (s.kinetic_energy() + e["kinetic_correction"] + s.strain_energy()
                - e["load_work"] - e["support_work"] + e["damping_dissipated"])

    s.step(dt)
    first = residual()
    for _ in range(600):
        s.step(dt)
    assert s.energy_terms()["support_work"] > 0.0
    assert abs(residual() - first) < 1e-9 * s.energy_terms()["support_work"]
    state = s.checkpoint_state()
    for _ in range(20):
        s.step(dt)
    after = s.displacement()
    s.restore_state(state)
    for _ in range(20):
        s.step(dt)
    assert np.array_equal(s.displacement(), after)


CASE = """
[run]
title = "a spinning bar strikes an ice cube"
end_time = 2.0e-3
output_interval = 2.0e-4
safety_factor = 0.8

[[ice]]
name = "ice"
dx = 0.01
horizon_factor = 3.015
shape = {{ box = {{ min = [0.33, 0.105, 0.01], max = [0.41, 0.145, 0.09] }} }}
material = {{ density = 900.0, youngs_modulus = 4.0e9, poisson_ratio = 0.3, critical_stretch = 1.0 }}

[[structure]]
name = "bar"
kind = "elastic"
mesh = "{box}"
params = {{ length_x = 0.5, length_y = 0.1, length_z = 0.1, divisions_x = 10, divisions_y = 2, divisions_z = 2, fixed_faces = "x0", contact_faces = "y1" }}
fixed_groups = ["fixed"]
contact_group = "contact"
motion = {{ angular_velocity = [0.0, 0.0, 20.0], center = [0.0, 0.05, 0.05] }}

[[contact]]
ice = "ice"
structure = "bar"
"""


@pytest.mark.slow
def test_spinning_bar_strikes_ice_energy_closes_with_the_shaft_work(tmp_path):
    """A bar turning at 20 rad/s about its root sweeps into a free ice cube at r = 0.33..0.41 m:
    the contact sees the moving face (the cube is struck after the bar turns through its 5 mm
    gap, and leaves faster than the face's 6.6..8.2 m/s but slower than twice that, the limit
    of an elastic bounce off a driven wall), and the run's energy balance closes within 1 %
    with the shaft's work in support_work."""
    from pdfem.case import load_case
    from pdfem.output import read_results
    from pdfem.run.driver import run_case
    path = tmp_path / "spin_ice.toml"
    path.write_text(CASE.format(box=files("pdfem.models").joinpath("validation/box.py")))
    data = read_results(run_case(load_case(path), tmp_path / "out", quiet=True).results)
    e = data["histories"]["energy"]
    assert e["support_work"][-1] > 1.0
    assert abs(e["residual"][-1]) < 0.01 * e["supplied"][-1]
    h = data["histories"]["structures/bar"]
    np.testing.assert_allclose(h["frame_angle"], 20.0 * h["time"], rtol=1e-12)
    vy = data["ice"]["ice"]["v"][-1][:, 1].mean()
    assert 20.0 * 0.33 < vy < 2 * 20.0 * 0.41


def test_time_stepping_swings_at_the_southwell_frequency(tmp_path):
    """The slender bar of spinning_bar_southwell.toml at full speed, released from its first
    flapwise mode shape: after half a period of the spinning frequency omega_f (Southwell:
    sqrt(omega_0^2 + 1.193 omega^2), 1.48 omega_0 here) the tip's z displacement has reversed
    (within 2 % of its amplitude); with the rest frequency it would be far from it (cos(pi /
    1.48) = 0.22)."""
    from pdfem.fem.modes import generalized_modes
    case = load_validation_case("spinning_bar_southwell.toml")
    cfg = case.structures[0]
    mesh = tmp_path / "bar.msh"
    mesh_model(str(files("pdfem.models").joinpath("validation/box.py")), dict(cfg.params), mesh)
    s = FrameStructure.from_file(mesh, STEEL, fixed_groups=["fixed"], contact_group="contact",
                                 frame=MovingFrame(cfg.angular_velocity, cfg.center))
    free = s.solver.free
    lam, phi = generalized_modes(s.rotating_stiffness()[free][:, free], s.solver.m[free], 2)
    full = np.zeros(s.dofmap.n_dofs)
    for k in range(2):   # the flapwise one of the two lowest
        full[free] = phi[:, k]
        shape = s.dofmap.to_nodal(full)
        if np.abs(shape[:, 2]).sum() > np.abs(shape[:, 1]).sum():
            omega_f = math.sqrt(lam[k])
            break
    assert omega_f / (2 * math.pi) == pytest.approx(spinning.flapwise_reference(case), rel=0.05)
    s.set_state(displacement=1e-4 * shape / np.abs(shape[:, 2]).max())
    # the tip face's mean: the Poisson contraction of the axial vibration that the centrifugal
    # load starts cancels in it
    tip = np.isclose(s.points[:, 0], s.points[:, 0].max())
    z0 = s.displacement()[tip, 2].mean()
    n = int(math.ceil(math.pi / omega_f / s.stable_time_step()))
    dt = math.pi / omega_f / n
    for _ in range(n):
        s.step(dt)
    assert s.displacement()[tip, 2].mean() == pytest.approx(-z0, abs=0.02 * abs(z0))


def test_implicit_frame_balances_energy_with_contact_impulses(bar_mesh):
    """The bar in a turning, translating frame (ramped over 2 ms), advanced by implicit steps
    20 times its explicit stable step with Rayleigh damping, takes contact impulses (world
    axes) on its tip face that amend some of its steps: kinetic + strain - (load work +
    support work - damping) equals the impulses' returned work to round-off (the drive's share
    of it in support_work), the shaft books the same work; without impulses the elastic motion
    (inertial loads explicit, at the step's start) follows an explicit run: the tip's swing
    (the ramp's Euler load, 19 mm, damped) within 2 % of its largest value at every step."""
    def make(**kwargs):
        return _bar(bar_mesh, MovingFrame((0.0, 0.0, 200.0), (0.0, 0.05, 0.05), (1.0, 0.0, 0.0),
                                          2e-3), rayleigh_alpha=1000.0, **kwargs)
    s, plain, still = make(integrator="implicit"), make(integrator="implicit"), make()
    n = 20
    dt = n * still.stable_time_step()
    rng = np.random.default_rng(2)
    returned, worst, swing = 0.0, 0.0, []

    def residual():
        e = s.energy_terms()
        return (s.kinetic_energy() + s.strain_energy() - e["load_work"] - e["support_work"]
                + e["damping_dissipated"] - returned)

    for k in range(150):
        s.step(dt)
        if k % 7 == 3:
            j = rng.normal(0.0, 0.02, (s.n_surface_nodes, 3))
            returned += s.apply_surface_impulse(j)
        worst = max(worst, abs(residual()))
        plain.step(dt)
        for _ in range(n):
            still.step(dt / n)
        swing.append((plain.displacement()[:, 1].min(), still.displacement()[:, 1].min()))
    assert s.energy_terms()["support_work"] > 0.0
    assert worst < 1e-9 * s.energy_terms()["support_work"]
    assert s.shaft.ice_work == pytest.approx(returned, rel=1e-12, abs=1e-15)
    swing = np.array(swing)
    assert np.abs(swing[:, 0] - swing[:, 1]).max() < 0.02 * np.abs(swing[:, 1]).max()


@pytest.mark.parametrize("integrator", ["explicit", "implicit"])
def test_a_structure_turning_from_t0_starts_and_stays_in_its_steady_state(bar_mesh, integrator):
    """The 5 x 1 x 1 bar turning at 100 rad/s about z from t = 0 (no ramp) starts in the static
    equilibrium of the rotating frame (FrameStructure.steady_displacement): its relative
    acceleration is zero to round-off (M a below 1e-9 of the centrifugal load); the supports
    hold the whole centrifugal force, sum m omega^2 x over the displaced nodes (a stiffness
    and its geometric part are balanced in themselves), which is the bar's m omega^2 r_c
    (mass x omega^2 x the centroid's radius 0.25 m: 98.1 kN) to the stretch, 4e-6; and five
    axial periods of steps leave its displacement within 1e-9 of the steady one (nothing rings,
    where a start from rest rings at twice the static stretch)."""
    omega = 100.0
    s = _bar(bar_mesh, MovingFrame((0.0, 0.0, omega), (0.0, 0.05, 0.05)), integrator=integrator)
    free = s.solver.free
    u0 = s.solver.u.copy()
    load = float(np.abs(s._f_inertial[free]).max())
    assert np.abs(u0).max() > 1e-6                                  # the bar has stretched
    assert np.abs(s.solver.m[free] * s.solver.a[free]).max() < 1e-9 * load
    held = s.shaft.held_reactions().sum(axis=0)                      # N, supports on the bar
    x = s.node_points[:, 0] + s.displacement()[:, 0]                 # m, from the axis (x = 0)
    assert held[0] == pytest.approx(-float(np.sum(s.node_mass * omega**2 * x)), rel=1e-9)
    assert -held[0] == pytest.approx(float(s.node_mass.sum()) * omega**2 * 0.25, rel=1e-4)
    period = 4 * 0.5 / math.sqrt(210e9 / 7850.0)                    # axial, 4 L / c
    dt = s.stable_time_step() if integrator == "explicit" else period / 20
    for _ in range(int(math.ceil(5 * period / dt))):
        s.step(dt)
    assert np.abs(s.solver.u - u0).max() < 1e-9 * np.abs(u0).max()
