"""Changing a case's values by dotted paths (pdfem.case.overrides) and writing case data back as
TOML (pdfem.case.toml_text).

References: Python's own TOML parser (tomllib) reads every written text back to the data it was
written from; the schema's own messages for the changed values; the mesh files the original
case resolves to.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import pytest

from pdfem.case import json_schema, load_case, parse_case
from pdfem.case.overrides import anchor_paths, key_parts, override_case
from pdfem.case.toml_text import dumps, value_text
from pdfem.errors import InputError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[2]
CASES = sorted((ROOT / "models").glob("*.toml")) + sorted((ROOT / "models" / "validation").glob("*.toml"))


@pytest.mark.parametrize("path", CASES, ids=[p.stem for p in CASES])
def test_every_case_file_is_written_back_to_the_same_data(path):
    data = tomllib.loads(path.read_text())
    assert tomllib.loads(dumps(data)) == data


@pytest.mark.parametrize("x", [0.3, 4.1e9, 1e-5, 2.0e-4, 1e16, -0.0, 5e-324, 123456.789, 0.1 + 0.2])
def test_a_float_reads_back_as_the_same_number_and_short(x):
    text = value_text(x)
    assert tomllib.loads(f"v = {text}")["v"] == x and math.copysign(1, float(text)) == math.copysign(1, x)
    assert len(text) <= len(repr(x))


def test_key_parts_take_both_path_forms():
    assert key_parts("ice[0].material.dx") == key_parts("ice.0.material.dx") == ["ice", "0", "material", "dx"]


def test_overrides_reach_the_validated_case_and_its_text():
    base = load_case(ROOT / "models" / "ice_beam_bending.toml")
    case = override_case(base, {"ice.0.material.flexural_strength": 5e5,
                                "ice[0].prescribed_velocity.0.velocity": [0.0, 0.0, -0.04],
                                "run.end_time": 2e-4, "run.output_interval": 1e-4,
                                "run.title": None})
    assert case.ice[0].material.flexural_strength == 5e5
    assert case.ice[0].prescribed_velocity[0].velocity == (0.0, 0.0, -0.04)
    assert (case.run.end_time, case.run.output_interval, case.run.title) == (2e-4, 1e-4, "")
    assert base.ice[0].material.flexural_strength == 0.7e6  # the base case is unchanged
    again = parse_case(case.text, "again.toml")  # the text is the changed case file
    assert again.ice[0] == case.ice[0] and again.run == case.run
    assert case.text.startswith(f"# {base.file} with overrides:\n")


@pytest.mark.parametrize("overrides, field, words", [
    ({"ice.3.dx": 0.01}, "ice.3.dx", "ice has 1 entry"),
    ({"ice.sheet.dx": 0.01}, "ice.sheet.dx", "give the number of an entry"),
    ({"run.end_time.max": 1.0}, "run.end_time.max", "is a value (0.01), not a table"),
    ({"monitor.0.name": "a"}, "monitor.0.name", "no monitor entries"),
    ({"run..end_time": 1.0}, "run..end_time", "not a dotted path"),
    ({"run.title": object()}, "run.title", "not a value a case file can hold"),
    ({"run.no_such_key": 1}, "run.no_such_key", "unknown key"),            # the schema's message
    ({"ice.0.dx": -0.01}, "ice[0].dx", "must be > 0 m"),                    # the schema's message
    ({"ice.0.dx": None}, "ice[0].dx", "this field is required"),
])
def test_a_bad_override_is_bad_input_naming_the_key(overrides, field, words):
    base = load_case(ROOT / "models" / "ice_beam_bending.toml")
    with pytest.raises(InputError) as e:
        override_case(base, overrides)
    assert e.value.field == field and words in e.value.message
    assert e.value.file == base.file


def test_the_changed_case_runs_from_any_folder_with_its_mesh_files(tmp_path):
    """ice_edge_crushing.toml names a surface mesh (shape) and a .py model (structure) relative
    to its folder: the changed text names the same files from elsewhere."""
    base = load_case(ROOT / "models" / "ice_edge_crushing.toml")
    case = override_case(base, {"run.end_time": 0.02})
    moved = tmp_path / "runs" / "a" / "case.toml"
    moved.parent.mkdir(parents=True)
    moved.write_text(case.text)
    again = load_case(moved)
    assert again.structures[0].mesh == base.structures[0].mesh == str(ROOT / "models" / "validation" / "box.py")
    data = tomllib.loads(case.text)
    assert data["ice"][0]["shape"]["mesh"]["file"] == str(ROOT / "models" / "validation" / "ice_sheet_wedge.obj")


def _relative_paths(node, path=""):
    """The schema properties whose description says they are relative to the case file."""
    found = []
    if isinstance(node, dict):
        for key, value in node.items():
            if isinstance(value, dict) and "relative to the case" in str(value.get("description", "")):
                found.append(key)
            found += _relative_paths(value, key)
    elif isinstance(node, list):
        for value in node:
            found += _relative_paths(value, path)
    return found


def test_every_path_relative_to_the_case_file_is_one_anchor_paths_makes_absolute():
    """anchor_paths knows the schema's two kinds of file paths (a structure's mesh, a shape's
    mesh file); a new kind of path in the schema must be added there."""
    assert set(_relative_paths(json_schema())) <= {"mesh", "file", "shape"}
    data = {"structure": [{"mesh": "hull.msh"}, {"mesh": "hull_panel"}],
            "ice": [{"shape": {"mesh": {"file": "sheet.obj"}}}]}
    anchor_paths(data, Path("/cases"))
    assert data == {"structure": [{"mesh": "/cases/hull.msh"}, {"mesh": "hull_panel"}],
                    "ice": [{"shape": {"mesh": {"file": "/cases/sheet.obj"}}}]}
