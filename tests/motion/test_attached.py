"""An elastic plate riding on the free tiny icebreaker (pdfem/motion/attached_frame.py,
pdfem/motion/attached_step.py, docs/ship.md): the ship and the plate advance as one system.

References: hydrostatic equilibrium (a ship at rest at its equilibrium stays there, whatever
share of its mass rides on it); Newton's second law for the combined rigid body (pulled by F
with no water force on a surge, ship and plate accelerate at F / m, m the whole ship's mass) and
the conservation of momentum (the total changes by exactly the pull's impulse) and energy
(kinetic + potential + strain + damping loss = work in); the rigid-body mass matrix of point
masses (Goldstein, Classical Mechanics, ch. 5). The case is models/validation/ship_attached_plate.toml,
its meshes made once here.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from pdfem.case.config import Pulse, SurfaceLoad
from pdfem.case.schema import load_case
from pdfem.errors import InputError
from pdfem.motion.rigid_inertia import dof_inertia
from pdfem.run.build_structures import build_all, structure_mesh
from pdfem.validation.cases.attached import meshed_case

from support.cli import run_main

CASES = Path(__file__).resolve().parents[2] / "models" / "validation"
VOLUME = 0.6 * 0.2 * 0.02   # m^3, the case's plate


@pytest.fixture(scope="module")
def meshed(tmp_path_factory):
    """The rest case with its hull and plate meshed once, the ship's mass (kg) and the
    directory."""
    d = tmp_path_factory.mktemp("attached")
    case, mass = meshed_case(load_case(CASES / "ship_attached_plate.toml"), d)
    return case, mass, d


def _build(meshed, mass: float, **plate):
    """Ship and plate of the case, the plate weighing ``mass`` (kg), other plate fields
    replaced."""
    case, _, d = meshed
    hull, cfg = case.structures
    return build_all((hull, dataclasses.replace(cfg, density=mass / VOLUME, **plate)), d,
                     case.file)


def _energy(ship, plate) -> float:
    """Stored energy + damping loss - work in (J): constant when the balance closes."""
    ts, tp = ship.energy_terms(), plate.energy_terms()
    stored = (ship.kinetic_energy() + ts["kinetic_correction"] + ship.potential_energy()
              + plate.kinetic_energy() + tp["kinetic_correction"] + plate.strain_energy())
    return (stored + tp["damping_dissipated"] - tp["load_work"] - ts["load_work"]
            - ts["support_work"])


def test_dof_inertia_of_point_masses():
    """Two point masses m at r: mass m1 + m2, the momentum of a turn w about the reference
    point w x (m1 r1 + m2 r2), inertia
    m (|r|^2 I - r r^T) summed (Goldstein ch. 5); a node held in z only adds m to the z
    translation and m (r x e_z) to its coupling, nothing to x and y."""
    r = np.array([[0.3, -0.2, 0.1], [-0.1, 0.4, 0.2]])
    m = np.array([2.0, 3.0])
    M = dof_inertia(r, m, np.ones((2, 3), dtype=bool))
    np.testing.assert_allclose(M[:3, :3], 5.0 * np.eye(3))
    s = (m[:, None] * r).sum(axis=0)
    np.testing.assert_allclose(M[:3, 3:] @ [1.0, 0.0, 0.0], np.cross([1.0, 0.0, 0.0], s))
    inertia = sum(mk * (rk @ rk * np.eye(3) - np.outer(rk, rk)) for mk, rk in zip(m, r))
    np.testing.assert_allclose(M[3:, 3:], inertia, atol=1e-15)
    held = dof_inertia(r[:1], m[:1], np.array([[False, False, True]]))
    np.testing.assert_allclose(np.diag(held)[:3], [0.0, 0.0, 2.0])
    np.testing.assert_allclose(held[2, 3:], 2.0 * np.cross(r[0], [0.0, 0.0, 1.0]))


def test_plate_at_rest_keeps_the_ship_at_rest(meshed):
    """The plate at 1, 2.5 and 5 kg and at the ship's whole mass (100 %: the hull a massless
    shell), at the automatic step and one ten times smaller, 5 ms: G stays where it is to
    round-off (1e-9 m asked; the validation entry ship_attached_rest_drift runs 1 s, 1 mm asked),
    the plate unstrained. The hull's weight is the whole ship's: at 100 % the integrated body
    is the plate's supports alone (4.5 kg), and the weight of the body alone would lift it
    0.6 mm in that time."""
    ship_mass = meshed[1]
    for mass in (1.0, 2.5, 5.0, ship_mass):
        ship, plate = _build(meshed, mass)
        start = ship.checkpoint_state(), plate.checkpoint_state()
        for factor in (1.0, 0.1):
            ship.restore_state(start[0])
            plate.restore_state(start[1])
            h = 0.8 * factor * plate.critical_time_step()
            c0 = ship.c.copy()
            for _ in range(math.ceil(0.005 / h)):
                ship.step(h)
            assert np.linalg.norm(ship.c - c0) < 1e-9, (mass, factor)
            assert np.abs(plate.displacement()).max() < 1e-12


def test_pulled_plate_accelerates_the_whole_ship(meshed):
    """The plate carrying the ship's whole mass pulled by F = 10 N along x (ramped over
    0.3 s, as models/validation/ship_attached_plate_pull.toml), 1 s: the total momentum (the
    ship's body and the plate's free nodes, world) changes by the pull's impulse to round-off,
    G accelerates at F / m within 0.1 % over the last half (Newton's second law for the
    combined body: the plate's mass counted once), and the energy balance closes to 1e-9 of the
    pull's work."""
    ship_mass = meshed[1]
    load = SurfaceLoad("loaded", 0.0, (10.0 / 0.024, 0.0, 0.0), Pulse(0.0, 0.3, math.inf, 0.0))
    ship, plate = _build(meshed, ship_mass, loads=(load,))
    h = 0.8 * plate.critical_time_step()
    e0, impulse, v = _energy(ship, plate), 0.0, []
    for n in range(math.ceil(1.0 / h)):
        ship.step(h)
        impulse += 0.5 * h * 10.0 * (load.pulse(n * h) + load.pulse((n + 1) * h))
        v.append(ship.v[0])
    r, u = plate.relative_motion()
    _, w = plate.frame.to_world(plate.time, r, u)
    free = plate.dofmap.to_nodal(plate.solver.free.astype(float))
    momentum = ship.p + (plate.node_mass[:, None] * free * (w @ ship.R) @ ship.R.T).sum(axis=0)
    np.testing.assert_allclose(momentum, [impulse, 0.0, 0.0], rtol=0, atol=1e-12 * impulse)
    k = len(v) // 2
    a = (v[-1] - v[k]) / ((len(v) - 1 - k) * h)
    assert a == pytest.approx(10.0 / ship_mass, rel=1e-3)
    assert abs(_energy(ship, plate) - e0) < 1e-9 * plate.energy_terms()["load_work"]


def test_heavy_plate_off_the_axis_rolls_with_the_ship_and_keeps_the_energy(meshed):
    """A stiff plate (E = 4.2 GPa) of 13 kg, half the ship's mass, on the port deck (its roll
    inertia about G close to all the ship's: the hull's own is nearly singular), the ship
    released 1 mrad in roll: over 600 steps the energy stays constant to 1e-6 of the roll's
    potential energy and nothing is supplied. The lagged hand-over of the support impulses
    blew this case up at step 2,430 (energy NaN, exit 3)."""
    case = meshed[0]
    hull, cfg = case.structures
    d = meshed[2] / "port_plate"
    params = {"length_x": 0.3, "length_y": 0.15, "length_z": 0.01,
              "origin_x": 0.0327369804716353 - 0.15, "origin_y": 0.0, "origin_z": 0.08,
              "divisions_x": 6, "divisions_y": 3, "divisions_z": 1, "fixed_faces": "x0, x1",
              "contact_faces": "z1"}
    plate_cfg = dataclasses.replace(load_case(CASES / "ship_attached_plate.toml").structures[1],
                                    params=params)
    plate_cfg = dataclasses.replace(plate_cfg, mesh=str(structure_mesh(plate_cfg, d)), params={},
                                    density=13.0 / (0.3 * 0.15 * 0.01), youngs_modulus=4.2e9)
    section = hull.ship.section.model_copy(update={"initial_rotation": (1e-3, 0.0, 0.0)})
    hull = dataclasses.replace(hull, ship=dataclasses.replace(hull.ship, section=section))
    ship, plate = build_all((hull, plate_cfg), d, case.file)
    upright = build_all((case.structures[0], plate_cfg), d, case.file)[0]
    swing = ship.potential_energy() - upright.potential_energy()
    h = 0.8 * plate.critical_time_step()
    e0 = _energy(ship, plate)
    for _ in range(600):
        ship.step(h)
    assert abs(_energy(ship, plate) - e0) < 1e-6 * swing
    assert abs(ship.omega[0]) > 0.0 and plate.strain_energy() > 0.0   # it does roll
    assert plate.energy_terms()["load_work"] == ship.energy_terms()["support_work"] == 0.0


def test_plate_heavier_than_the_ship_is_refused(meshed, tmp_path):
    """A plate of 50 kg on the 26.9 kg ship (whose mass includes what rides on it) is bad
    input: exit 2, one paragraph naming the ship's mass and the plate's density, no traceback;
    one of 5 kg far off the ship's side (more roll inertia than the whole ship's) names the
    radii of gyration."""
    text = (CASES / "ship_attached_plate.toml").read_text()
    text = text.replace('mesh = "box.py"', f'mesh = "{CASES / "box.py"}"')
    heavy = tmp_path / "heavy.toml"
    heavy.write_text(text.replace("density = 1041.6666666666667", "density = 20833.333333333332"))
    r = run_main("run", heavy, "--out", tmp_path / "out")
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert "structure[0].ship.mass" in r.stderr and "material.density" in r.stderr
    assert "50 kg" in r.stderr
    case = meshed[0]
    cfg = dataclasses.replace(load_case(CASES / "ship_attached_plate.toml").structures[1],
                              params={**load_case(CASES / "ship_attached_plate.toml")
                                      .structures[1].params, "origin_y": 0.5})
    with pytest.raises(InputError) as err:
        build_all((case.structures[0], dataclasses.replace(cfg, density=5.0 / VOLUME)),
                  tmp_path / "side", case.file)
    assert err.value.field == "structure[0].ship.radii_of_gyration"


def test_ship_and_plate_restart_bit_for_bit(meshed):
    """Ship and plate restored from their checkpoint states continue bit for bit (the plate
    pulled, so that both move)."""
    load = SurfaceLoad("loaded", 0.0, (400.0, 0.0, 100.0), Pulse(0.0, 0.01, math.inf, 0.0))
    a = _build(meshed, 5.0, loads=(load,))
    h = 0.8 * a[1].critical_time_step()
    for _ in range(20):
        a[0].step(h)
    b = _build(meshed, 5.0, loads=(load,))
    for x, y in zip(a, b):
        y.restore_state(x.checkpoint_state())
    for _ in range(20):
        a[0].step(h)
        b[0].step(h)
    np.testing.assert_array_equal(a[0].surface_points(), b[0].surface_points())
    np.testing.assert_array_equal(a[1].surface_points(), b[1].surface_points())
    assert a[0].energy_terms() == b[0].energy_terms()
    assert a[1].energy_terms() == b[1].energy_terms()
