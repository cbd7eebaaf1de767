"""Ice contact on a structure advanced by implicit Newmark steps (:mod:`pdfem.fem.implicit`,
:mod:`pdfem.fem.step_compliance`, :class:`pdfem.fem.surface_motion.SteppedSurface`).

References: conservation of linear momentum (a free ice block hitting a free implicit block,
nothing else acting: the impulse leaving the ice reaches the structure, and the Newmark step
conserves the momentum it is given, to round-off); conservation of energy (the run's terms,
kinetic + strain of both bodies + the contact loss = the ice's initial kinetic energy, to
round-off: the structure's contact work is the trapezoidal work of the force that amends its
step); and the plastic contact's loss, never negative when the ice side has no forces of its
own (free particles: the work of the impulses on them is exactly ``P . v + P^2 / (2 m)``), for
particles of any mass on 10-node tetrahedra whose corner nodes are lighter than the particles,
hitting one by one or all at once.
"""

from __future__ import annotations

import numpy as np
import pytest

from support.meshes import write_box
from pdfem.coupling.contact import SurfaceContact
from pdfem.coupling.coupler import ContactPair, Coupler
from pdfem.fem.elasticity import ElasticMaterial
from pdfem.fem.structure import ElasticStructure
from pdfem.geometry.shapes import Box
from pdfem.pd.body import IceBody
from pdfem.pd.materials.lps import IceMaterial

STEEL = ElasticMaterial(7850.0, 210e9, 0.3)


@pytest.fixture(scope="module")
def block_msh(tmp_path_factory):
    path = tmp_path_factory.mktemp("block") / "block.msh"
    return write_box(path, (0.1, 0.1, 0.1), divisions=(4, 4, 4),
                     face_groups={"contact": ("x0", "x1", "y0", "y1", "z0", "z1")})


def test_free_blocks_conserve_momentum_and_energy_with_an_implicit_block(block_msh):
    """An unbreakable ice block (2 m/s) hits a free steel block advanced by implicit steps at
    the ice's step (2.5 times the block's explicit limit) and rebounds: the total momentum
    is conserved to round-off at every step, the ice's initial kinetic energy is found again
    in the two bodies and the contact loss within 1 % (0.5 %: the bonded ice's own O(dt^2)
    Verlet error, as with an explicit block; the structure's side is exact, next test), and
    the contact loses 5-30 % of it (12 %)."""
    st = ElasticStructure.from_file(block_msh, STEEL, contact_group="contact", name="block",
                                    integrator="implicit")
    dx = 0.01
    ice = IceBody.from_shape("ice", Box((0.1 + 1e-5 - dx / 2, 0.01, 0.01),
                                        (0.18 + 1e-5 - dx / 2, 0.09, 0.09)),
                             IceMaterial(density=900.0, youngs_modulus=4.0e9,
                                         poisson_ratio=0.3), dx, 3.015 * dx)
    ice.v[:, 0] = -2.0
    pair = ContactPair("ice-block", ice, st, SurfaceContact(st, 0.5 * dx))
    dt = 0.8 * ice.stable_time_step()
    explicit = ElasticStructure.from_file(block_msh, STEEL, contact_group="contact")
    assert dt > 2.0 * explicit.critical_time_step()
    c = Coupler([ice], [st], [pair], dt)
    c.start()
    p0 = ice.momentum() + st.momentum()
    e0 = ice.kinetic_energy() + ice.strain_energy()
    drift = 0.0
    for _ in range(int(round(4e-4 / dt))):
        c.step()
        drift = max(drift, np.abs(ice.momentum() + st.momentum() - p0).max())
    assert drift < 1e-10 * abs(p0[0])
    assert st.momentum()[0] < -0.3 * abs(p0[0])
    stored = ice.kinetic_energy() + ice.strain_energy() + st.kinetic_energy() + st.strain_energy()
    lost = c.contact_dissipated
    assert 0.05 * e0 < lost < 0.3 * e0
    assert abs(stored + lost - e0) < 0.01 * e0


@pytest.fixture(scope="module")
def plate_msh(tmp_path_factory):
    """A 0.3 m x 0.3 m x 0.02 m plate of tetrahedra 0.03 m, clamped on x = 0 and x = 0.3."""
    path = tmp_path_factory.mktemp("plate") / "plate.msh"
    return write_box(path, (0.3, 0.3, 0.02), face_groups={"contact": ["z1"], "fixed": ["x0", "x1"]},
                     size=0.03)


@pytest.mark.parametrize("density, together, friction", [
    (900.0, False, 0.0), (14000.0, True, 0.0), (14000.0, True, 0.3)])
def test_contact_loss_is_never_negative_with_light_nodes(plate_msh, density, together, friction):
    """Free particles (no bonds, 2 cm apart: 7.2 g of ice, or 112 g, the milling case's
    particle) hit a clamped steel plate of 10-node tetrahedra (nodes of 0.9-24 g) advanced by
    implicit steps at 1e-5 s, with random speeds of 1-8 m/s or all at 5 m/s at once (with the
    diagonal blocks alone this case gains 30 J of 728 J in one step), with and without
    friction: the contact loses energy in every step (the coupled compliance: each
    contact sees the step's response of its facet's nodes to all the step's contacts), the
    balance closes to round-off, and the plate takes the impulse."""
    st = ElasticStructure.from_file(plate_msh, STEEL, fixed_groups=["fixed"],
                                    contact_group="contact", integrator="implicit")
    assert st.solver.m.min() < 900.0 * 0.02 ** 3 < st.solver.m.max()
    dx = 0.02
    ice = IceBody.from_shape("ice", Box((0.02, 0.02, 0.0201), (0.28, 0.28, 0.0201 + 3 * dx)),
                             IceMaterial(density=density, youngs_modulus=4e9, poisson_ratio=0.3),
                             dx, 0.5 * dx, isotropic=False, surface_correction=False)
    assert ice.counts()[1] == 0   # no bonds: free particles
    rng = np.random.default_rng(0)
    ice.v[:, 2] = -5.0 if together else -rng.uniform(1.0, 8.0, ice.n)
    ice.v[:, :2] = rng.uniform(-1.0, 1.0, (ice.n, 2))
    pair = ContactPair("p", ice, st, SurfaceContact(st, 0.5 * dx, friction=friction))
    c = Coupler([ice], [st], [pair], 1e-5)
    c.start()
    e0 = ice.kinetic_energy()
    before, worst = 0.0, 0.0
    for _ in range(250):
        c.step()
        worst = min(worst, c.contact_dissipated - before)
        before = c.contact_dissipated
    stored = ice.kinetic_energy() + st.kinetic_energy() + st.strain_energy()
    assert worst > -1e-12 * e0
    assert 0.1 * e0 < before < 0.5 * e0
    assert abs(stored + before - e0) < 1e-12 * e0
    assert pair.contact.total_impulse[2] < -0.9 * ice.n * density * dx ** 3



@pytest.mark.slow
def test_restart_of_an_implicit_frame_in_contact_is_bit_identical(tmp_path):
    """A turning bar advanced by implicit steps strikes an ice block
    (shaft_energy_implicit.toml, with Rayleigh damping): the run restarted from its last
    checkpoint (after the strike began) ends with every frame and history of the uninterrupted
    run, bit for bit (the factorisation and the contact compliance are made again,
    identically)."""
    import shutil
    from pdfem.output import read_results
    from pdfem.run.driver import run_case
    from pdfem.validation.case import load_validation_case, replace_run
    case = replace_run(load_validation_case("shaft_energy_implicit.toml"),
                       checkpoint_interval_steps=200, output_interval=2.5e-4)
    ref = run_case(case, tmp_path / "ref", quiet=True)
    shutil.copytree(tmp_path / "ref", tmp_path / "again")
    run_case(case, tmp_path / "again", quiet=True, restart=tmp_path / "again" / "checkpoint.h5")
    a, b = read_results(ref.results), read_results(tmp_path / "again" / "results.h5")
    assert a["histories"]["shaft/bar"]["ice_work"][-1] < 0.0      # the bar struck the ice
    np.testing.assert_array_equal(a["time"], b["time"])
    np.testing.assert_array_equal(a["structure"]["bar"]["u"], b["structure"]["bar"]["u"])
    np.testing.assert_array_equal(a["ice"]["ice"]["v"], b["ice"]["ice"]["v"])
    for g, hist in a["histories"].items():
        for k, v in hist.items():
            np.testing.assert_array_equal(v, b["histories"][g][k], err_msg=f"{g}/{k}")
