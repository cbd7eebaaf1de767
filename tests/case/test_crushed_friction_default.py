"""The default friction of the "ice" law's crushed ice is tan(friction_angle): the internal
friction coefficient of Coulombic faulting equals the static friction across the fault in
biaxial tests on columnar S2 ice (Acta Materialia 2006; docs/ice_failure.md)."""

from __future__ import annotations

import math

import pytest

from pdfem.case.ice import IceMaterialSection
from pdfem.run.build_ice import ice_material


@pytest.mark.parametrize("angle", [30.0, 40.0])
def test_crushed_friction_defaults_to_tan_of_the_friction_angle(angle):
    m = IceMaterialSection(failure="ice", compressive_strength=2.0e6, friction_angle=angle)
    assert m.crushed_friction == pytest.approx(math.tan(math.radians(angle)), rel=1e-15)
    assert ice_material(m).crushed_friction == m.crushed_friction
    assert "crushed_friction" not in m.model_fields_set


def test_crushed_friction_zero_turns_it_off():
    m = IceMaterialSection(failure="ice", compressive_strength=2.0e6, crushed_friction=0.0)
    assert ice_material(m).crushed_friction == 0.0
