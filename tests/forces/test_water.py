"""Water on ice particles: buoyancy, drag, the [water] section and the floating validation cases.

References: Archimedes' principle (the buoyancy of a floating body equals the weight of the
water it displaces: for a lattice slab with the water line inside it, rho_w g A times the
submerged depth, exactly, since the particles' cells tile the slab); the force is minus the
gradient of its potential (checked by central differences); a neutrally buoyant body moving
through water with linear drag only slows as v0 exp(-c t) (the ODE dv/dt = -c v); the energy
balance of pdfem/run/energy.py closes with the drag's dissipation; the floating validation
cases (Archimedes' draught, the hydrostatic heave period 2 pi sqrt(rho_i h / (rho_w g)), with
added mass 2 pi sqrt((1 + Ca) rho_i h / (rho_w g))); the serial run of the same case (for 2 MPI
ranks). SI units.
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest

from pdfem.case import parse_case
from pdfem.errors import InputError
from pdfem.forces.water import Water
from pdfem.geometry.shapes import Box
from pdfem.output import read_results
from pdfem.pd.body import IceBody
from pdfem.pd.materials.lps import IceMaterial
from pdfem.run.build_forces import PARTICLE_FORCES, build_forces, dissipated_energies
from pdfem.run.driver import run_case
from pdfem.validation.case import load_validation_case
from pdfem.validation.cases import floating
from pdfem.validation.runner import run_validation

from support.cli import run_ok

RHO_W, G = 1025.0, 9.81
ICE = IceMaterial(density=900.0, youngs_modulus=1e7, poisson_ratio=0.3, fracture_energy=1e6)


def _slab(bottom: float = -0.1, h: float = 0.1, dx: float = 0.025) -> IceBody:
    """A 0.1 m x 0.1 m slab of thickness h with its bottom at z = bottom (m)."""
    return IceBody.from_shape("slab", Box((0.0, 0.0, bottom), (0.1, 0.1, bottom + h)), ICE, dx,
                              3.015 * dx)


def _water(body: IceBody, **kw) -> Water:
    return Water([body], density=RHO_W, level=0.0, g=G, **kw)


@pytest.mark.parametrize("depth", [0.0, 0.013, 0.05, 0.0878, 0.1])
def test_buoyancy_of_a_slab_is_archimedes(depth):
    """Submerged depth s of a 0.1 m slab: total buoyancy rho_w g A s (N), to round-off."""
    body = _slab(bottom=-depth)
    body.f[:] = 0.0
    _water(body).add_forces()
    lift = float((body.f[:, 2] * body.vol).sum())
    assert lift == pytest.approx(RHO_W * G * 0.01 * depth, rel=1e-12, abs=1e-12)
    np.testing.assert_array_equal(body.f[:, :2], 0.0)


def test_buoyancy_is_minus_the_gradient_of_its_potential():
    """Lift the slab through the water line: dU/dz = -F (central differences, quadratic U)."""
    body = _slab(bottom=-0.06)
    water = _water(body)
    for z in (-0.03, -0.0125, 0.0, 0.004, 0.02):  # across cells' smooth zones and kinks
        body.y[:] = body.x0
        body.y[:, 2] += z
        body.f[:] = 0.0
        water.add_forces()
        force = float((body.f[:, 2] * body.vol).sum())
        h = 1e-6
        body.y[:, 2] += h
        up = water.potential_energy()
        body.y[:, 2] -= 2 * h
        down = water.potential_energy()
        assert -(up - down) / (2 * h) == pytest.approx(force, rel=1e-6)


def test_linear_drag_slows_a_neutral_body_exponentially_and_closes_the_balance(tmp_path):
    """Neutrally buoyant (rho_ice = rho_w) fully submerged block at 0.2 m/s, linear drag 5 /s:
    v(t) = v0 exp(-5 t); the drag's dissipation is the kinetic energy lost."""
    case = parse_case("""
[run]
end_time = 0.2
output_interval = 0.05
[water]
linear_drag = 5.0
[[ice]]
name = "b"
dx = 0.05
shape = { box = { min = [0, 0, -0.5], max = [0.2, 0.2, -0.3] } }
initial_velocity = [0.2, 0.0, 0.0]
material = { density = 1025.0, youngs_modulus = 1e7, poisson_ratio = 0.3, fracture_energy = 1e6 }
""")
    res = read_results(run_case(case, tmp_path, quiet=True).results)
    v = res["ice"]["b"]["v"][-1]
    assert v[:, 0].mean() == pytest.approx(0.2 * math.exp(-5.0 * 0.2), rel=1e-3)
    e = res["histories"]["energy"]
    lost = 0.5 * 1025.0 * 0.2 * 0.2 * 0.2 * (0.2 ** 2 - v[:, 0].mean() ** 2)
    assert e["water_drag_dissipated"][-1] == pytest.approx(lost, rel=1e-3)
    assert abs(e["residual"][-1]) < 1e-4 * lost


def test_quadratic_drag_of_one_cell():
    """Cd = 1 on a fully submerged particle at 1 m/s: -0.5 rho_w Cd |u| u / dx (N/m^3)."""
    body = _slab(bottom=-1.0)
    body.v[:] = (1.0, 0.0, 0.0)
    body.f[:] = 0.0
    _water(body, drag_coefficient=1.0, current=(0.0, 0.0, 0.0)).add_forces()
    np.testing.assert_allclose(body.f[:, 0], -0.5 * RHO_W / 0.025, rtol=1e-12)
    np.testing.assert_allclose(body.f[:, 2], RHO_W * G, rtol=1e-12)


def test_water_section_defaults_and_gravity():
    def text(gravity: str, water: str) -> str:
        return TEXT.replace("GRAVITY", gravity).replace("WATER", water)

    TEXT = """
[run]
end_time = 0.1
GRAVITY
WATER
[[ice]]
name = "s"
dx = 0.05
shape = { box = { min = [0, 0, -0.1], max = [0.2, 0.2, 0.0] } }
"""
    case = parse_case(text(gravity="", water="[water]"))
    assert case.water.density == 1025.0 and case.water.level == 0.0
    assert case.run.gravity == (0.0, 0.0, -9.81)
    assert parse_case(text(gravity="", water="")).run.gravity == (0.0, 0.0, 0.0)
    given = parse_case(text(gravity="gravity = [0, 0, -9.8]", water="[water]"))
    assert given.run.gravity == (0.0, 0.0, -9.8)
    sideways = parse_case(text(gravity="gravity = [1, 0, -9.8]", water="[water]"))
    body = _slab()
    with pytest.raises(InputError, match="run.gravity"):
        build_forces(sideways, [body])
    with pytest.raises(InputError, match="water.density"):
        parse_case(text(gravity="", water="[water]\ndensity = -1"))
    with warnings.catch_warnings(record=True) as caught:  # fully submerged: out of equilibrium
        warnings.simplefilter("always")
        forces = build_forces(case, [body])
    assert any("hydrostatic equilibrium" in str(w.message) for w in caught)
    assert Water in PARTICLE_FORCES and any(isinstance(f, Water) for f in forces)
    assert dissipated_energies([]) == {"water_drag_dissipated": 0.0}


@pytest.mark.parametrize("name", ["floating_draught", "floating_heave_period"])
def test_floating_validation_cases_pass_quick(name, tmp_path):
    """The quick variants: draught within 1 % of Archimedes, heave period within 5 %."""
    case = next(c for c in floating.CASES if c.name == name)
    assert load_validation_case(case.case_file).water is not None
    results = run_validation([case], tmp_path, quick=True)
    assert results[0].passed, results[0]


def test_added_mass_lengthens_the_heave_period_by_sqrt_1_plus_ca(tmp_path):
    """Ca = 0.5 on the quick heave block: the submerged volume carries Ca rho_w d A =
    Ca rho_i h A of water, so T = 2 pi sqrt((1 + Ca) rho_i h / (rho_w g)), 1 %; the water's
    kinetic energy (in water_potential) keeps the energy balance closed."""
    case = floating.heave_quick(load_validation_case("floating_heave.toml"))
    case = dataclasses.replace(case, water=case.water.model_copy(update={"added_mass": 0.5}))
    res = read_results(run_case(case, tmp_path, quiet=True).results)
    period = floating.heave_period(floating.Outcome(case, res, tmp_path, 0.0))
    expect = 2 * math.pi * math.sqrt(1.5 * 900.0 * 0.25 / (1025.0 * 9.81))
    assert floating.heave_reference(case) == pytest.approx(expect, rel=1e-12)
    assert period == pytest.approx(expect, rel=0.01)
    e = res["histories"]["energy"]
    assert np.abs(e["residual"]).max() < 1e-5 * np.abs(e["gravity_potential"]).max()


MPI_CASE = """
[run]
end_time = 0.2
output_interval = 0.05
[water]
linear_drag = 5.0
drag_coefficient = 1.0
current = [0.05, 0.0, 0.0]
[[ice]]
name = "block"
dx = 0.05
shape = { box = { min = [0.0, 0.0, -0.199512], max = [0.3, 0.3, 0.050488] } }
material = { density = 900.0, youngs_modulus = 1.0e7, poisson_ratio = 0.3, fracture_energy = 1.0e6 }
"""


@pytest.mark.slow
def test_water_on_two_mpi_ranks_gives_the_serial_run(tmp_path):
    """Buoyancy, drag and the current on a block split over 2 ranks: the serial positions
    bit for bit, the water's energy terms to round-off (summed in another order)."""
    case = tmp_path / "block.toml"
    case.write_text(MPI_CASE)
    runs = {}
    for ranks in (1, 2):
        out = tmp_path / f"r{ranks}"
        run_ok("run", case, "--out", out, "--quiet", ranks=ranks, timeout=300)
        runs[ranks] = read_results(out / "results.h5")
    np.testing.assert_array_equal(runs[1]["ice"]["block"]["u"], runs[2]["ice"]["block"]["u"])
    e1, e2 = runs[1]["histories"]["energy"], runs[2]["histories"]["energy"]
    for key in ("water_potential", "water_drag_dissipated", "residual"):
        np.testing.assert_allclose(e2[key], e1[key], rtol=1e-12, atol=1e-12)
    assert e1["water_drag_dissipated"][-1] > 0
