"""Case-file validation: every bad field is named, with its file and what would be valid."""

from __future__ import annotations

import pytest

from pdfem.case.schema import parse_case
from pdfem.errors import InputError

GOOD = """
[run]
end_time = 1e-4
output_interval = 2e-5

[[ice]]
name = "block"
dx = 0.01
shape = { box = { min = [0, 0, 0], max = [0.1, 0.05, 0.05] } }
material = { density = 900, youngs_modulus = 4e9, poisson_ratio = 0.3, fracture_energy = 10 }
fixed = [ { box = { min = [0, 0, 0], max = [0.01, 0.05, 0.05] } } ]
"""


def test_good_case_parses_with_si_values():
    case = parse_case(GOOD, "good.toml")
    ice = case.ice[0]
    assert ice.dx == 0.01
    assert ice.horizon == pytest.approx(3.015 * 0.01)
    assert ice.material.youngs_modulus == 4e9
    assert case.run.pd_loop == "pairs"
    assert case.run.time_step is None


@pytest.mark.parametrize("old,new,field", [
    ("end_time = 1e-4", "end_time = -1e-4", "run.end_time"),
    ("end_time = 1e-4", "end_time = 'soon'", "run.end_time"),
    ("output_interval = 2e-5", "output_interval = 1.0", "run.output_interval"),
    ("output_interval = 2e-5", "output_interval = 2e-5\nendtime = 3", "run.endtime"),
    ("dx = 0.01", "dx = 0", "ice[0].dx"),
    ("dx = 0.01", "dx = 0.01\nhorizon = 0.005", "ice[0].horizon"),
    ("dx = 0.01", "dx = 0.2", "ice[0].dx"),
    ("poisson_ratio = 0.3", "poisson_ratio = 0.5", "ice[0].material.poisson_ratio"),
    ("density = 900", "density = -900", "ice[0].material.density"),
    ("density = 900", "densty = 900", "ice[0].material.densty"),
    ("max = [0.1, 0.05, 0.05] } }", "max = [0.1, 0.05] } }", "ice[0].shape.box.max"),
    ("shape = { box", "shape = { cube", "ice[0].shape"),
    ("name = \"block\"", "name = \"\"", "ice[0].name"),
    ("[run]", "[run]\npd_loop = 'fast'", "run.pd_loop"),
    ("fracture_energy = 10 }", "fracture_energy = 10, critical_stretch = 1e-3 }", "ice[0].material.critical_stretch"),
])
def test_bad_field_is_named(old, new, field):
    text = GOOD.replace(old, new, 1)
    assert text != GOOD
    with pytest.raises(InputError) as err:
        parse_case(text, "bad.toml")
    assert err.value.field == field
    msg = err.value.text()
    assert "bad.toml" in msg and field in msg


def test_invalid_toml_names_file():
    with pytest.raises(InputError) as err:
        parse_case("[run\nend_time = 1", "broken.toml")
    assert "broken.toml" in err.value.text() and "TOML" in err.value.text()


def test_missing_ice_and_duplicate_names():
    with pytest.raises(InputError) as err:
        parse_case("[run]\nend_time = 1e-3\n", "x.toml")
    assert err.value.field == "ice"
    body = GOOD[GOOD.index("[[ice]]"):]
    with pytest.raises(InputError) as err:
        parse_case(GOOD + body, "x.toml")
    assert err.value.field == "ice[1].name"


def test_missing_mesh_file_is_reported(tmp_path):
    text = GOOD.replace('box = { min = [0, 0, 0], max = [0.1, 0.05, 0.05] }',
                        'mesh = { file = "nowhere.msh" }', 1)
    with pytest.raises(InputError) as err:
        parse_case(text, "m.toml", tmp_path)
    assert err.value.field == "ice[0].shape.mesh.file"
