"""The extension interfaces: structures, failure laws, particle forces, ice bodies, output.

Each interface is checked for what the driver relies on: both structure kinds answer every
question of :class:`pdfem.fem.base.Structure` (rigid: no step limit, no energy, work supplied
from outside), a failure law sets the threshold the kernels break bonds at, gravity acts as the
kick's acceleration and reports its potential, a whole ice body has the distributed body's
interface (all particles owned), and the writer of ranks other than 0 takes every call of the
real writer explicitly.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from support.meshes import write_box
from pdfem.fem.base import Structure
from pdfem.fem.elasticity import ElasticMaterial
from pdfem.motion.rigid import RigidBody
from pdfem.fem.structure import ElasticStructure
from pdfem.forces.base import ParticleForce
from pdfem.forces.gravity import Gravity
from pdfem.forces.short_range import ShortRangeContact
from pdfem.geometry.shapes import Box
from pdfem.output import ResultsWriter
from pdfem.output.source import OutputSource
from pdfem.pd.body import IceBody
from pdfem.pd.failure import FAILURE_LAWS, CriticalStretch, FailureLaw, failure_law
from pdfem.pd.ice_interface import IceParticles
from pdfem.pd.materials.lps import IceMaterial
from pdfem.run.build_forces import PARTICLE_FORCES, potential_energies
from pdfem.run.build_structures import STRUCTURE_KINDS
from pdfem.run.outputs import NoOutput, StructureSource

ICE = IceMaterial(density=900.0, youngs_modulus=4.0e9, poisson_ratio=0.3, fracture_energy=1.0)


def _ice(**kwargs) -> IceBody:
    dx = 0.01
    return IceBody.from_shape("ice", Box((0, 0, 0), (0.04, 0.04, 0.04)), ICE, dx, 3.015 * dx,
                              **kwargs)


@pytest.fixture(scope="module")
def block(tmp_path_factory):
    path = tmp_path_factory.mktemp("block") / "block.msh"
    write_box(path, (0.1, 0.1, 0.1), divisions=(2, 2, 2),
              face_groups={"contact": ("x1",), "fixed": ("x0",)})
    return ElasticStructure.from_file(path, ElasticMaterial(7850.0, 210e9, 0.3),
                                      fixed_groups=["fixed"], contact_group="contact",
                                      name="block")


def _plate() -> RigidBody:
    return RigidBody(np.array([[0, 0, 1.0], [1, 0, 1], [1, 1, 1], [0, 1, 1]]),
                     np.array([[0, 1, 2], [0, 2, 3]]), velocity=(0, 0, -1.0), name="plate")


def test_structure_kinds_are_registered_structures(block):
    assert set(STRUCTURE_KINDS) == {"elastic", "rigid", "ship"}
    for s in (block, _plate()):
        assert isinstance(s, Structure)
        points, cells, cell_type = s.output_mesh()
        fields = s.output_fields()
        assert fields["u"].shape == (len(points), 3)
        assert s.describe().endswith(("s", "nodes")) and s.name in s.describe()
        assert s.is_finite()
        s.check_mesh()


def test_rigid_body_has_no_step_limit_no_energy_and_supplies_its_work():
    p = _plate()
    assert p.critical_time_step() == math.inf and p.stable_time_step() == math.inf
    assert p.kinetic_energy() == 0.0 and p.strain_energy() == 0.0
    assert p.prescribed_motion and p.frame_history() == {}
    assert set(p.output_fields()) == {"u", "v"}
    p.step(0.5)
    np.testing.assert_allclose(p.output_fields()["u"][:, 2], -0.5)


def test_elastic_structure_reports_its_fields_energies_and_reactions(block):
    assert not block.prescribed_motion
    assert block.critical_time_step() == block.solver.critical_time_step()
    assert set(block.output_fields()) == {"u", "v", "von_mises"}
    assert set(block.frame_history()) == {"kinetic", "strain", "reaction_fixed"}
    rows = StructureSource(block).frame_rows()
    assert list(rows) == ["structures/block"]


def test_failure_law_registry_and_threshold():
    assert "critical_stretch" in FAILURE_LAWS
    law = failure_law("critical_stretch", ICE, 0.03)
    assert isinstance(law, FailureLaw)
    assert law.stretch_limit() == ICE.s0(0.03)
    with pytest.raises(ValueError, match="critical_stretch"):
        failure_law("no such law", ICE, 0.03)
    body = _ice()
    assert body.s0 == ICE.s0(body.delta) and body.failure.name == "critical_stretch"


def test_the_law_decides_which_bonds_break():
    """The same stretched body: a tiny stretch limit breaks bonds, an infinite one none."""
    broken = {}
    for s0 in (1e-9, math.inf):
        body = _ice(failure=CriticalStretch(s0))
        body.y *= 1.001  # 0.1 % uniform stretch
        broken[s0] = body.compute_forces()
    assert broken[1e-9] == _ice().n_bonds and broken[math.inf] == 0


def test_gravity_acts_in_the_kick_and_has_a_potential():
    body = _ice()
    g = Gravity([body], (0.0, 0.0, -9.81))
    assert isinstance(g, ParticleForce) and g.energy_key == "gravity_potential"
    np.testing.assert_array_equal(body.gravity, [0.0, 0.0, -9.81])
    f0 = body.f.copy()
    g.add_forces()
    np.testing.assert_array_equal(body.f, f0)
    body.y[:, 2] -= 0.01
    expect = -ICE.density * body.vol.sum() * 0.01 * 9.81
    assert g.potential_energy() == pytest.approx(expect, rel=1e-12)
    assert Gravity([_ice()], (0, 0, 0)).potential_energy() == 0.0


def test_every_particle_force_kind_has_an_energy_column():
    assert Gravity in PARTICLE_FORCES and ShortRangeContact in PARTICLE_FORCES
    assert set(potential_energies([])) == {"gravity_potential", "short_range_potential",
                                           "water_potential"}
    assert issubclass(ShortRangeContact, ParticleForce)


def test_whole_ice_body_has_the_distributed_interface():
    body = _ice()
    assert isinstance(body, IceParticles) and body.n_global == body.n
    assert body.owned.all() and len(body.owned) == body.n
    index, x0, vol = body.owned_reference()
    np.testing.assert_array_equal(index, np.arange(body.n))
    assert np.array_equal(x0, body.x0) and np.array_equal(vol, body.vol)
    assert set(body.frame_fields()) == {"u", "v", "damage"}
    assert body.owned_sum(body.vol) == math.fsum(body.vol)  # correctly rounded


def test_broken_flags_kept_as_signed_weights():
    body = _ice()
    flags = np.zeros(body.n_bonds, dtype=np.uint8)
    flags[:3] = 1
    body.broken = flags
    assert body.broken.sum() == 3 and (body.weight < 0).sum() == 3
    body.broken = np.zeros_like(flags)
    assert body.broken.sum() == 0 and (body.weight > 0).all()


def test_no_output_takes_every_writer_call_explicitly(tmp_path):
    calls = ("add_ice_body", "add_structure", "write_frame", "append_history", "resume",
             "history_rows", "flush", "close")
    for name in calls:
        assert callable(getattr(ResultsWriter, name))
        assert name in vars(NoOutput), name
    assert "__getattr__" not in vars(NoOutput)
    w = NoOutput(tmp_path / "results.h5")
    w.write_frame(0.0, {})
    w.append_history("energy", 0.0, {"kinetic": 1.0})
    assert w.n_frames == 0 and w.history_rows() == {}
    assert not (tmp_path / "results.h5").exists()


def test_structure_source_is_an_output_source(block):
    src = StructureSource(block)
    assert isinstance(src, OutputSource) and src.mesh_kind == "structure"
    assert src.step_rows() == {}
