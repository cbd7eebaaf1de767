"""The icebreaker hull model, the hydrostatics of a clipped hull and the free 6-DOF ship.

References: Archimedes' principle (the buoyancy of a cube half under water in any attitude is
rho g a^3 / 2, through the centroid of the submerged half); the hull's own parametric
surface integrated independently of the mesh (models/icebreaker.py hydrostatic_properties:
volume, waterplane area and moments); the hydrostatic heave period T = 2 pi sqrt(m / (rho g
A_wp)) (Newman, Marine Hydrodynamics, 1977, sec. 6.16, added mass zero); conservation of
momentum, angular momentum and energy of a rigid body (Goldstein, Classical Mechanics, ch. 5).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from pdfem.case.schema import load_case
from pdfem.errors import InputError
from pdfem.motion.hydrostatics import hydrostatics
from pdfem.motion.rigid import read_msh_groups, read_surface, rotation_matrix
from pdfem.motion.ship import Ship
from pdfem.fem.surface import orient_outward
from pdfem.models import icebreaker
from pdfem.output import read_results
from pdfem.run.driver import run_case

SYMMETRIC = dict(length=2.4, entrance_angle=math.atan(0.5), stem_angle=math.pi / 2,
                 flare_angle=0.0, element_size=0.05)
"""Fore-and-aft symmetric, wall-sided hull (uncoupled heave and pitch, linear heave)."""


@pytest.fixture(scope="module")
def hull(tmp_path_factory):
    path = tmp_path_factory.mktemp("hull") / "hull.msh"
    icebreaker.build(path)
    return path


@pytest.fixture(scope="module")
def symmetric_hull(tmp_path_factory):
    path = tmp_path_factory.mktemp("hull") / "symmetric.msh"
    icebreaker.build(path, **SYMMETRIC)
    return path


def _cube(a: float = 1.0):
    v = np.array([[x, y, z] for x in (-a / 2, a / 2) for y in (-a / 2, a / 2)
                  for z in (-a / 2, a / 2)])
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tri = [t for a_, b, c, d in quads for t in ((a_, b, c), (a_, c, d))]
    return v, orient_outward(v, np.array(tri))


@pytest.mark.parametrize("axis", [(1.0, 0.0, 0.0), (0.3, 1.0, 0.2), (1.0, -2.0, 0.5)])
def test_cube_centred_on_the_surface_floats_half(axis):
    """A unit cube centred on the water surface, in any attitude, displaces half its volume
    (the surface through its centre halves it): F = (0, 0, rho g / 2), V = 1/2, the centre
    of buoyancy below the centre, at z_B from the potential U = rho g V (level - z_B)."""
    v, tri = _cube()
    R = rotation_matrix(0.37 * np.asarray(axis) / np.linalg.norm(axis))
    h = hydrostatics(v @ R.T, tri, 0.0, 1000.0, 9.81, (0.0, 0.0, 0.0))
    assert h.volume == pytest.approx(0.5, rel=1e-12)
    np.testing.assert_allclose(h.force, [0.0, 0.0, 1000.0 * 9.81 * 0.5], atol=1e-9)
    assert h.centre_of_buoyancy[2] < 0.0
    assert h.potential == pytest.approx(1000 * 9.81 * 0.5 * -h.centre_of_buoyancy[2], rel=1e-12)


@pytest.mark.parametrize("apex_down", [True, False])
def test_tetrahedron_clipped_by_the_water_plane(apex_down):
    """A tetrahedron of base height H: with its apex down, immersed to depth d above the apex,
    the wet part is the similar tetrahedron, V (d / H)^3 (every side face one wet corner);
    apex up, the dry part is, V (1 - ((H - d) / H)^3) (side faces two wet corners, the base
    wholly wet). Reference: volumes of similar solids scale with the cube of the length."""
    H = 1.2
    base = np.array([[1.0, 0.0, 0.0], [-0.5, 0.8, 0.0], [-0.4, -0.9, 0.0]])
    apex = np.array([[0.1, 0.05, -H if apex_down else H]])
    v = np.vstack([base, apex])
    tri = orient_outward(v, np.array([(0, 1, 2), (0, 1, 3), (1, 2, 3), (2, 0, 3)]))
    volume = abs(np.linalg.det(base - apex)) / 6.0
    for d in (0.1, 0.55, 1.0):
        level = (-H + d) if apex_down else d
        h = hydrostatics(v, tri, level, 1000.0, 9.81, (0.0, 0.0, 0.0))
        expected = volume * ((d / H) ** 3 if apex_down else 1.0 - ((H - d) / H) ** 3)
        assert h.volume == pytest.approx(expected, rel=1e-12)
        np.testing.assert_allclose(h.force, [0.0, 0.0, 1000.0 * 9.81 * expected],
                                   atol=1e-9 * 1000.0 * 9.81)


def test_upright_cube_buoyancy_centre_and_moment():
    """Upright cube a = 1 immersed to 0.3 m: V = 0.3, B at z = -0.15 below the surface
    (bottom at -0.3); about a point 0.2 m off in x the moment of the buoyancy is r x F."""
    v, tri = _cube()
    h = hydrostatics(v + [0.2, 0.0, 0.2], tri, 0.0, 1025.0, 9.81, (0.0, 0.0, 0.0))
    assert h.volume == pytest.approx(0.3, rel=1e-12)
    np.testing.assert_allclose(h.centre_of_buoyancy, [0.2, 0.0, -0.15], atol=1e-12)
    np.testing.assert_allclose(h.moment, [0.0, -0.2 * 1025 * 9.81 * 0.3, 0.0], atol=1e-9)


def test_hull_is_closed_with_its_groups_and_volume(hull):
    """The hull mesh is closed (finish_mesh checks every edge is in two triangles), has the
    named groups, and its enclosed and submerged volumes, centre of buoyancy and waterplane
    agree with the parametric surface (within 0.1 %: the sides between levels are bilinear)."""
    groups = read_msh_groups(hull).groups
    for name in ("bow", "shoulder", "midship", "stern", "bow_panel", "contact"):
        assert groups[name][0] == 2, name
    pts, tri = read_surface(hull)
    ref = icebreaker.hydrostatic_properties()
    whole = hydrostatics(pts, tri, 10.0, 1000.0, 9.81, (0.0, 0.0, 0.0))
    wet = hydrostatics(pts, tri, 0.0, 1000.0, 9.81, (0.0, 0.0, 0.0))
    assert whole.volume == pytest.approx(ref["enclosed_volume"], rel=1e-3)
    assert wet.volume == pytest.approx(ref["volume"], rel=1e-3)
    assert wet.centre_of_buoyancy[0] == pytest.approx(ref["x_b"], abs=1e-3)
    assert wet.centre_of_buoyancy[2] == pytest.approx(ref["z_b"], abs=1e-3)
    # waterplane area: dV/dlevel at the design waterline (central difference)
    up = hydrostatics(pts, tri, 1e-4, 1000.0, 9.81, (0.0, 0.0, 0.0)).volume
    down = hydrostatics(pts, tri, -1e-4, 1000.0, 9.81, (0.0, 0.0, 0.0)).volume
    assert (up - down) / 2e-4 == pytest.approx(ref["waterplane_area"], rel=2e-3)
    bow_panel = read_surface(hull, "bow_panel")[0]
    assert (bow_panel[:, 1] >= 0).all() and np.abs(bow_panel[:, 2]).max() < 0.12  # port, waterline


def test_bad_hull_parameter_is_named():
    """A run longer than the hull is refused naming the parameter."""
    from pdfem.meshing import ModelParameterError
    with pytest.raises(ModelParameterError, match="parallel_middle_body"):
        icebreaker.build("/nonexistent/x.msh", parallel_middle_body=3.0)


def _ship(path, **kw) -> Ship:
    pts, tri = read_surface(path)
    return Ship(pts, tri, density=1000.0, level=0.0, gravity=(0.0, 0.0, -9.81),
                radii_of_gyration=(0.24, 0.6, 0.6), **kw)


def test_heave_period_and_energy(symmetric_hull):
    """Released 5 mm high, the symmetric hull heaves with T = 2 pi sqrt(m / (rho g A_wp))
    within 0.5 %, does not pitch, and keeps its energy (kinetic + potential) to 1e-4 of the
    energy of the swing (velocity Verlet, second order)."""
    s = _ship(symmetric_hull, initial_displacement=(0.0, 0.0, 0.005))
    ref = icebreaker.hydrostatic_properties(**SYMMETRIC)
    period = 2 * math.pi * math.sqrt(s.mass / (1000.0 * 9.81 * ref["waterplane_area"]))
    e0 = s.kinetic_energy() + s.potential_energy()
    t, z, worst = [], [], 0.0
    for k in range(650):
        s.step(2e-3)
        t.append(s.time)
        z.append(s.c[2])
        worst = max(worst, abs(s.kinetic_energy() + s.potential_energy() - e0))
    z = np.array(z) - 0.5 * (max(z) + min(z))
    up = [t[i] for i in range(1, len(z)) if z[i - 1] < 0 <= z[i]]
    assert len(up) >= 1
    down = [t[i] for i in range(1, len(z)) if z[i - 1] > 0 >= z[i]]
    measured = 2 * (up[0] - down[0]) if up[0] > down[0] else 2 * (down[1] - up[0])
    assert measured == pytest.approx(period, rel=5e-3)
    assert abs(s.omega).max() < 1e-9
    swing = 0.5 * 1000 * 9.81 * ref["waterplane_area"] * 0.005 ** 2
    assert worst < 1e-4 * swing  # velocity Verlet: (omega h)^2 / 8 = 2.4e-5


def test_impulse_momentum_and_work(hull):
    """A surface impulse J at a node changes the momentum by J and the angular momentum by
    r x J; its returned work is the kinetic-energy change."""
    s = _ship(hull)
    node = int(np.argmax(s.surface_points()[:, 0]))
    J = np.zeros((s.n_surface_nodes, 3))
    J[node] = (-3.0, 1.0, 0.5)
    r = s.surface_points()[node] - s.c
    p0, L0, e0 = s.mass * s.v.copy(), s.L.copy(), s.kinetic_energy()
    work = s.apply_surface_impulse(J)
    np.testing.assert_allclose(s.mass * s.v - p0, J[node], atol=1e-12)
    np.testing.assert_allclose(s.L - L0, np.cross(r, J[node]), atol=1e-12)
    assert work == pytest.approx(s.kinetic_energy() - e0, rel=1e-12)
    assert work > 0


def test_checkpoint_restores_exactly(hull):
    """A ship restored from its checkpoint state continues bit for bit."""
    a = _ship(hull, initial_rotation=(0.02, 0.01, 0.0), thrust=5.0)
    for _ in range(20):
        a.step(2e-3)
    b = _ship(hull, initial_rotation=(0.02, 0.01, 0.0), thrust=5.0)
    b.restore_state(a.checkpoint_state())
    for _ in range(20):
        a.step(2e-3)
        b.step(2e-3)
    np.testing.assert_array_equal(a.surface_points(), b.surface_points())
    assert a.energy_terms() == b.energy_terms()


def test_surge_speed_is_held_after_the_ramp(hull):
    """With surge_speed and ramp_time the x velocity follows the ramp, then holds."""
    s = _ship(hull, surge_speed=0.5, ramp_time=0.1)
    for _ in range(25):
        s.step(4e-3)
    assert s.v[0] == pytest.approx(0.5)
    assert s.energy_terms()["support_work"] == pytest.approx(0.5 * s.mass * 0.25)


CASE = """
[run]
end_time = 0.6
output_interval = 0.1
time_step = 2.0e-3
{water}
[[structure]]
name = "hull"
kind = "ship"
mesh = "icebreaker"
params = {{ element_size = 0.05 }}
ship = {{ initial_rotation = [0.0, 0.005, 0.0] }}
"""


def test_run_writes_motions_and_closes_the_energy_balance(tmp_path):
    """A free hull released off equilibrium in a run: ``motions/hull`` every coupling step, and
    the energy balance (ship kinetic + potential) closes to 2e-4 of the pitching energy."""
    (tmp_path / "case.toml").write_text(CASE.format(water="[water]\ndensity = 1025.0\n"))
    res = run_case(load_case(tmp_path / "case.toml"), tmp_path / "out", quiet=True)
    r = read_results(res.results)
    m = r["histories"]["motions/hull"]
    assert len(m["time"]) == res.steps + 1
    assert m["rotation"][0][1] == pytest.approx(0.005)
    e = r["histories"]["energy"]
    swing = np.ptp(e["structure_kinetic"])
    assert swing > 0
    assert np.abs(e["residual"]).max() < 2e-4 * swing  # 4.6e-5 measured at this step
    # pdfem post: the largest pitch is the release angle (the free swing returns to it, no
    # damping) and the motion plot is written
    from pdfem.post import load_results, summarize, write_plots
    post = load_results(res.results)
    pitch = summarize(post)["motions"]["hull"]["rotation"][1]
    assert pitch == pytest.approx(math.degrees(0.005), rel=1e-3)
    assert tmp_path / "plots" / "ship_motions.png" in write_plots(post, tmp_path / "plots")


def test_ship_needs_water(tmp_path):
    """A ship in a case without [water] is refused naming the field."""
    (tmp_path / "case.toml").write_text(CASE.format(water=""))
    with pytest.raises(InputError, match="water"):
        run_case(load_case(tmp_path / "case.toml"), tmp_path / "out", quiet=True)


ICE_CASE = """
[run]
end_time = 0.08
output_interval = 0.01

[water]
density = 1025.0

[[ice]]
name = "floe"
dx = 0.025
shape = { box = { min = [-0.1, -0.46, -0.0878], max = [0.1, -0.36, 0.0122] } }
material = { density = 900.0, youngs_modulus = 5.0e7, poisson_ratio = 0.3, fracture_energy = 1.0e6 }
initial_velocity = [0.0, 2.0, 0.0]

[[structure]]
name = "hull"
kind = "ship"
mesh = "icebreaker"
params = { element_size = 0.05 }
ship = { mass = 220.554 }
"""


@pytest.mark.slow
def test_floe_striking_the_side_pushes_the_ship(tmp_path):
    """A floating floe (1.8 kg at 2 m/s) strikes the hull's side amidships and bounces: the
    sway momentum the ship gains equals the floe's loss (nothing else acts along y: buoyancy is
    vertical, no drag), and the energy balance with the ship's kinetic and potential energy
    closes to 0.5 % of the floe's kinetic energy."""
    (tmp_path / "case.toml").write_text(ICE_CASE)
    res = run_case(load_case(tmp_path / "case.toml"), tmp_path / "out", quiet=True)
    r = read_results(res.results)
    ice = r["ice"]["floe"]
    p = (ice["v"][:, :, 1] * ice["volume"] * 900.0).sum(axis=1)
    ship = r["histories"]["motions/hull"]["velocity"][-1, 1] * 220.554
    assert p[0] - p[-1] > 2.0                       # the floe was stopped and turned back
    assert ship == pytest.approx(p[0] - p[-1], rel=1e-4)
    e = r["histories"]["energy"]
    assert np.abs(e["residual"]).max() < 5e-3 * e["kinetic"][0]


def test_hull_groups_are_load_patches_that_tile_the_hull(hull):
    """The hull's bow, shoulder, midship and stern groups are load patches that together cover
    every contact triangle exactly once, and the bow panel lies on the bow (the partition the
    model builds; patch forces then sum to the hull's total load)."""
    from pdfem.fem.surface_patches import surface_patches

    pts, tri = read_surface(hull, "contact")
    patches = surface_patches(hull, "contact", pts, tri)
    parts = ("bow", "shoulder", "midship", "stern")
    assert set(parts) <= set(patches)
    cover = sum(patches[p].astype(int) for p in parts)
    assert np.all(cover == 1)
    assert patches["bow_panel"].any()
    assert not np.any(patches["bow_panel"] & ~patches["bow"])
