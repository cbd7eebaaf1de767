"""The shear springs of crushed bonds (pdfem.pd.failure.crushed_shear): Coulomb friction between the
ends of a pushing crushed bond, as a tangential spring with slip (Cundall & Strack 1979,
"A discrete numerical model for granular assemblies", Geotechnique 29:47-65).

Checks: the spring sticks below the Coulomb limit and slides at mu times the normal force
above it; sliding at the limit dissipates mu F_n per metre slid (Coulomb's law of friction);
turning with the bond keeps its length; a crushed block squeezed hard keeps kinetic + stored +
dissipated equal to its initial energy, converging with the step; checkpoints carry the
springs, and a restart continues bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from pdfem.geometry.shapes import Box
from pdfem.pd.body import IceBody
from pdfem.pd.failure.crushed_shear import STIFFNESS_RATIO
from pdfem.pd.failure.ice import IceFailure
from pdfem.pd.bonds.lps_law import crushed_shear
from pdfem.pd.materials.lps import IceMaterial

from support.cli import run_ok

E, NU, ST, SC = 4.1e9, 0.3, 0.6e6, 3.0e6


def test_spring_sticks_then_slides_at_the_coulomb_limit():
    """A bond along x compressed by c: tangential increments of 1 um in y. The stretch grows
    by the increments until it reaches mu c / kappa, then stays there; once sliding, each step
    dissipates (per k_t) s_max times the increment, i.e. the friction force mu F_n times the
    distance slid (F_n = k c, k_t = kappa k)."""
    mu, c = 0.5, 1.0e-5
    smax = mu * c / STIFFNESS_RATIO   # 1e-5 m
    s = np.zeros(3)
    lost_total = 0.0
    history = []
    for _ in range(30):
        s0, s1, s2, lost = crushed_shear(s[0], s[1], s[2], 0.0, 1e-6, 0.0, 0.04, 0.0, 0.0,
                                         0.04, smax)
        s = np.array([s0, s1, s2])
        history.append(s1)
        lost_total += lost
    np.testing.assert_allclose(history[:10], 1e-6 * np.arange(1, 11), rtol=1e-12)  # sticks
    np.testing.assert_allclose(history[10:], smax, rtol=1e-12)                      # slides
    # 20 steps of 1 um slid at the limit: Coulomb's mu F_n x distance, per k_t = smax x 20 um
    assert lost_total == pytest.approx(smax * 20e-6, rel=1e-12)
    # a bond no longer pushing (smax = 0) lets its spring go: all its energy is released
    s0, s1, s2, lost = crushed_shear(s[0], s[1], s[2], 0.0, 0.0, 0.0, 0.04, 0.0, 0.0, 0.04,
                                     0.0)
    assert (s0, s1, s2) == (0.0, 0.0, 0.0) and lost == pytest.approx(0.5 * smax**2, rel=1e-12)


def test_spring_turns_with_the_bond():
    """A stretch normal to the old bond stays normal to the turned one, with its length."""
    s = (0.0, 2e-6, 0.0)
    a = math.radians(30.0)
    d = (0.04 * math.cos(a), 0.04 * math.sin(a), 0.0)
    s0, s1, s2, lost = crushed_shear(*s, 0.0, 0.0, 0.0, *d, 0.04, 1.0)
    assert s0 * d[0] + s1 * d[1] + s2 * d[2] == pytest.approx(0.0, abs=1e-20)
    assert math.hypot(s0, s1, s2) == pytest.approx(2e-6, rel=1e-12)
    assert lost == 0.0


def _material(mu):
    return IceMaterial(900.0, E, NU, tensile_strength=ST, compressive_strength=SC,
                       crushed_friction=mu)


def _crushed_block(speed, mu=0.58):
    """A block whose bonds are all crushed at their reference length, halves moving together
    at +-speed (m/s) and sliding past each other at speed / 2 across."""
    mat = _material(mu)
    body = IceBody.from_shape("b", Box((0, 0, 0), (0.09,) * 3), mat, 0.01, 0.03015,
                              failure=IceFailure.from_material(mat, 0.03015))
    body.weight[:] = -np.abs(body.weight)
    body.rest[:] = 0.0
    body.start()
    z = body.x0[:, 2]
    body.v[:, 2] = np.where(z < z.mean(), speed, -speed)
    body.v[:, 0] = np.where(z < z.mean(), 0.25 * speed, -0.25 * speed)
    return body


def test_friction_of_crushed_ice_dissipates_and_keeps_the_energy():
    """Crushed ice squeezed and sheared hard: the shear springs slide (dissipation > 0 beyond
    the normal springs' own yielding), and kinetic + stored + dissipated stays the initial
    energy, the error falling with the step (velocity Verlet, O(dt^2) for the elastic parts)."""
    drift = []
    for frac in (0.4, 0.1):
        body = _crushed_block(2.0)
        assert body.shear is not None
        assert body.shear.friction == 0.58
        e0 = body.kinetic_energy() + body.strain_energy()
        dt = frac * body.stable_time_step()
        e = []
        for _ in range(int(round(1e-4 / dt))):
            body.step(dt)
            e.append(body.kinetic_energy() + body.strain_energy() + body.fracture_dissipated)
        drift.append(np.abs(np.array(e) - e0).max() / e0)
        assert np.abs(body.shear.slip).max() > 0.0
    frictionless = _crushed_block(2.0, mu=0.0)
    assert frictionless.shear is None
    dt = 0.1 * frictionless.stable_time_step()
    for _ in range(int(round(1e-4 / dt))):
        frictionless.step(dt)
    # measured: 1.025 J dissipated against 0.882 J without friction; energy error 0.50 % at
    # 0.4 of the stable step and 0.031 % at 0.1 (0.42 % and 0.025 % without friction)
    assert body.fracture_dissipated > 1.1 * frictionless.fracture_dissipated
    assert drift[0] < 0.01 and drift[1] < 0.15 * drift[0], drift


def test_restart_carries_the_springs_bit_for_bit():
    """Checkpoint a sheared crushed block mid-run, restore it into a fresh body, and step both:
    positions, velocities and springs agree exactly."""
    body = _crushed_block(2.0)
    dt = 0.4 * body.stable_time_step()
    for _ in range(20):
        body.step(dt)
    state = body.checkpoint_state()
    assert "slip" in state
    other = _crushed_block(2.0)
    other.restore_state(state)
    for b in (body, other):
        for _ in range(20):
            b.step(dt)
    np.testing.assert_array_equal(other.y, body.y)
    np.testing.assert_array_equal(other.v, body.v)
    np.testing.assert_array_equal(other.shear.slip, body.shear.slip)


CRUSH = """
[run]
end_time = 1.2e-3
output_interval = 4.0e-4

[[ice]]
name = "plate"
dx = 0.02
shape = { box = { min = [0.0, 0.0, 0.0], max = [1.0, 0.5, 0.04] } }
material = { density = 900.0, youngs_modulus = 4.1e9, poisson_ratio = 0.3, failure = "ice", compressive_strength = 2.0e6, crushed_friction = MU }

[[structure]]
name = "cylinder"
kind = "rigid"
mesh = "indenters"
params = { shape = "cylinder", radius = 0.1, length = 0.1, axis = "z", center_x = 0.5, center_y = 0.5905, center_z = 0.02, element_size = 0.02 }
motion = { velocity = [0.0, -4.0, 0.0] }
"""


@pytest.mark.slow
def test_one_and_two_ranks_agree_with_friction(tmp_path):
    """A rigid cylinder crushing an ice plate's edge (the "ice" law, crushed_friction 0.58) on 1 and 2
    ranks: a bond between particles owned by two ranks is evaluated on both, and its shear
    spring advances alike there, so the runs agree to round-off (reference: the serial run);
    without friction the load differs, so the springs did act."""

    from pdfem.output import read_results

    results = {}
    for name, mu, ranks in (("r1", 0.58, 1), ("r2", 0.58, 2), ("f0", 0.0, 1)):
        case = tmp_path / f"{name}.toml"
        case.write_text(CRUSH.replace("MU", str(mu)))
        run_ok("run", case, "--out", tmp_path / name, "--quiet", ranks=ranks)
        results[name] = read_results(tmp_path / name / "results.h5")
    ref, two = results["r1"], results["r2"]
    u = ref["ice"]["plate"]["u"]
    force = ref["histories"]["loads/cylinder"]["force"]
    assert ref["ice"]["plate"]["damage"][-1].max() > 0.5   # crushed
    np.testing.assert_allclose(two["ice"]["plate"]["u"], u, rtol=0, atol=1e-10 * np.abs(u).max())
    np.testing.assert_allclose(two["histories"]["loads/cylinder"]["force"], force, rtol=0,
                               atol=1e-10 * np.abs(force).max())
    other = results["f0"]["histories"]["loads/cylinder"]["force"]
    assert np.abs(other - force).max() > 1e-3 * np.abs(force).max()
