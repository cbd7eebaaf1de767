"""The case-file schema: the README's table is generated from it, its JSON Schema accepts every
case of models/, and ``pdfem schema`` prints it.

Reference: the README holds the output of ``pdfem schema --markdown`` between the
``case-table`` markers (regenerate with ``python -c "from pathlib import Path; from
pdfem.case.doc import replace_table; p = Path('README.md'); p.write_text(replace_table(p.read_text()))"``).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from pdfem.case.casefile import CaseFile
from pdfem.case.doc import END, START, markdown_table, replace_table
from pdfem.case.schema import json_schema
from pdfem.cli.main import main

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[2]
CASES = sorted([*(ROOT / "models").glob("*.toml"), *(ROOT / "models" / "validation").glob("*.toml")])


def test_readme_case_table_is_generated_from_the_schema():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert START in readme and END in readme
    table = readme[readme.index(START) + len(START):readme.index(END)].strip("\n")
    assert table == markdown_table().strip("\n"), (
        "README.md's case-file table differs from the schema; regenerate it (see this module's "
        "docstring)")
    assert replace_table(readme) == readme


def _refs(schema: dict, node: dict) -> dict:
    while "$ref" in node:
        extra = {k: v for k, v in node.items() if k != "$ref"}
        node = {**schema["$defs"][node["$ref"].split("/")[-1]], **extra}
    return node


def _check_keys(schema: dict, node: dict, value, path: str) -> None:
    """Every key of ``value`` is declared in ``node`` (following $ref, properties, items) and
    every required key is given: what an editor with the JSON Schema checks."""
    node = _refs(schema, node)
    if isinstance(value, dict) and node.get("type") == "object" and "properties" in node:
        assert node.get("additionalProperties") is False, path
        for key in node.get("required", []):
            assert key in value, f"{path}.{key} is required by the schema"
        for key, item in value.items():
            assert key in node["properties"], f"{path}.{key} is not in the schema"
            _check_keys(schema, node["properties"][key], item, f"{path}.{key}")
    elif isinstance(value, list) and "items" in node:
        for k, item in enumerate(value):
            _check_keys(schema, node["items"], item, f"{path}[{k}]")


@pytest.mark.parametrize("case", CASES, ids=[c.stem for c in CASES])
def test_every_model_case_matches_the_schema(case):
    data = tomllib.loads(case.read_text(encoding="utf-8"))
    CaseFile.model_validate(data, context={"directory": case.parent})
    schema = json_schema()
    _check_keys(schema, schema, data, case.name)
    jsonschema = pytest.importorskip("jsonschema")  # part of the test extra
    jsonschema.validate(data, schema)


def test_schema_top_level_and_descriptions():
    schema = json_schema()
    assert schema["title"] == "pdfem case file"
    assert schema["required"] == ["run"]
    assert set(schema["properties"]) == {"run", "ice", "structure", "contact", "monitor", "water"}
    assert schema["additionalProperties"] is False
    for name, section in schema["$defs"].items():
        assert section["additionalProperties"] is False, name
        for key, prop in section["properties"].items():
            text = prop.get("description", "")
            assert "Default:" in text or "Required" in text, f"{name}.{key}: {text!r}"


def test_pdfem_schema_command(capsys):
    assert main(["schema"]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed == json.loads(json.dumps(json_schema()))
    assert "end_time" in printed["$defs"]["RunSection"]["properties"]
    assert main(["schema", "--markdown"]) == 0
    assert capsys.readouterr().out == markdown_table()


def test_model_parameters_use_the_same_validator():
    """Each model script's PARAMETERS table becomes a pydantic model: defaults filled in,
    unknown and mistyped keys named (ModelParameterError, exit 2)."""
    from pdfem.meshing import ModelParameterError, check_parameters, parameter_model
    from pdfem.meshing.runner import available_models, resolve_model

    for name in available_models():
        table = resolve_model(name).PARAMETERS
        model = parameter_model(table, name)
        assert model.model_validate({}).model_dump() == {k: v[0] for k, v in table.items()}
        assert set(model.model_json_schema()["properties"]) == set(table)
        with pytest.raises(ModelParameterError) as err:
            check_parameters(table, {"no_such_key": 1})
        assert err.value.param == "no_such_key" and "valid parameters are" in str(err.value)
    with pytest.raises(ModelParameterError) as err:
        check_parameters({"n": (3, "-", "count")}, {"n": 2.5})
    assert err.value.param == "n" and "integer" in str(err.value)
