"""Bad inputs of issue 18 (names, paths, overlaps, output directories, model scripts, group
fields, numeric ranges): each makes ``pdfem run`` exit 2 with a message naming the field, no
traceback, and nothing written outside ``--out``.

Reference: the contract of the command line (DESIGN.md, "Command line": exit 2 for bad input,
the message names file and field) and issue 18's list of inputs that escaped it. The cases run
in-process (:func:`pdfem.cli.main.main` with an argv list), each a small valid case with one
thing wrong; tests/cli/test_bad_inputs.py holds the earlier corpus (console script, subprocesses).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from pdfem.cli.main import main
from pdfem.run.outdir import LOCK_NAME, OutDirLock

BOX = Path(__file__).resolve().parents[2] / "models" / "validation" / "box.py"

BASE = f"""[run]
end_time = 1e-5

[[ice]]
name = "floe"
dx = 0.05
shape = {{ box = {{ min = [0.0, 0.0, 0.01], max = [0.2, 0.2, 0.21] }} }}

[[structure]]
name = "wall"
mesh = "{BOX.as_posix()}"
params = {{ divisions_x = 2, divisions_y = 2, divisions_z = 1, length_x = 0.3, length_y = 0.3, length_z = 0.05, origin_x = -0.05, origin_y = -0.05, origin_z = -0.05, fixed_faces = "z0", contact_faces = "z1" }}
fixed_groups = ["fixed"]
element_order = 1

[[monitor]]
name = "m"
structure = "wall"
point = [0.1, 0.1, 0.0]
"""
"""A valid case (a 0.2 m ice cube over a 0.3 m steel block of 2 x 2 x 1 hexahedra), whose
variants below each break one thing."""

SECOND_ICE = """
[[ice]]
name = "{name}"
dx = 0.05
shape = {shape}
"""

RAISING_IMPORT = "import math\nraise RuntimeError('bad geometry')\n"
RAISING_BUILD = ("PARAMETERS = {'size': (1.0, 'm', 'edge')}\n\n\ndef build(path, size=1.0):\n"
                 "    x = 1\n    return size / (x - 1)\n")
SYNTAX_ERROR = "def build(path:\n    pass\n"
NO_BUILD = "PARAMETERS = {}\n"


def _sub(old: str, new: str):
    def edit(text: str) -> str:
        assert old in text, old
        return text.replace(old, new, 1)
    return edit


def _add(extra: str):
    return lambda text: text + extra


def _script(name: str):
    return _sub(f'mesh = "{BOX.as_posix()}"\nparams = {BASE.split("params = ")[1].splitlines()[0]}',
                f'mesh = "{name}"')


# (id, edit of BASE, extra files {name: text}, fragments the message must contain)
CORPUS = [
    # names that would become file or HDF5 group names
    ("ice_name_slash", _sub('name = "floe"', 'name = "a/b"'), {}, ["ice[0].name", "letters"]),
    ("ice_name_dotdot", _sub('name = "floe"', 'name = ".."'), {}, ["ice[0].name"]),
    ("ice_name_leading_dot", _sub('name = "floe"', 'name = ".floe"'), {}, ["ice[0].name"]),
    ("ice_name_space", _sub('name = "floe"', 'name = "my floe"'), {}, ["ice[0].name"]),
    ("ice_name_empty", _sub('name = "floe"', 'name = ""'), {}, ["ice[0].name"]),
    ("ice_name_backslash", _sub('name = "floe"', 'name = "a\\\\b"'), {}, ["ice[0].name"]),
    ("structure_name_parent", _sub('name = "wall"', 'name = "../evil"'), {},
     ["structure[0].name"]),
    ("structure_name_absolute", _sub('name = "wall"', 'name = "/tmp/evil"'), {},
     ["structure[0].name"]),
    ("structure_name_colon", _sub('name = "wall"', 'name = "c:wall"'), {}, ["structure[0].name"]),
    ("monitor_name_dotdot", _sub('name = "m"', 'name = ".."'), {}, ["monitor[0].name"]),
    ("monitor_name_slash", _sub('name = "m"', 'name = "m/x"'), {}, ["monitor[0].name"]),
    ("contact_name_slash", _add('\n[[contact]]\nice = "floe"\nstructure = "wall"\nname = "c/d"\n'),
     {}, ["contact[0].name"]),
    ("contact_name_leading_dot",
     _add('\n[[contact]]\nice = "floe"\nstructure = "wall"\nname = ".c"\n'), {},
     ["contact[0].name"]),
    ("region_name_slash",
     _sub('dx = 0.05\n', 'dx = 0.05\nfixed = [{ name = "a/b", box = { min = [0, 0, 0.15], '
                         'max = [0.2, 0.2, 0.21] } }]\n'), {}, ["ice[0].fixed[0].name"]),
    ("duplicate_monitor", _add('\n[[monitor]]\nname = "m"\nstructure = "wall"\n'
                               'point = [0.0, 0.0, 0.0]\n'), {}, ["monitor[1].name", "unique"]),
    ("structure_named_like_ice", _sub('name = "wall"', 'name = "floe"'), {},
     ["structure[0].name", "unique"]),
    ("duplicate_contact_name",
     _add('\n[[contact]]\nice = "floe"\nstructure = "wall"\nname = "c"\n'
          '\n[[ice]]\nname = "floe2"\ndx = 0.05\n'
          'shape = { box = { min = [1, 1, 1], max = [1.2, 1.2, 1.2] } }\n'
          '\n[[contact]]\nice = "floe2"\nstructure = "wall"\nname = "c"\n'), {},
     ["contact[1].name", "unique"]),
    # paths
    ("structure_msh_missing", _script("nowhere.msh"), {}, ["structure[0].mesh", "no such file"]),
    ("structure_script_missing", _script("nowhere.py"), {}, ["structure[0].mesh", "no such file"]),
    ("structure_model_unknown", _script("no_such_model"), {}, ["structure[0].mesh", "hull_panel"]),
    ("structure_msh_is_text", _script("fake.msh"), {"fake.msh": "hello\n"},
     ["structure[0].mesh", "not a gmsh mesh"]),
    ("ice_shape_mesh_missing",
     _sub('shape = { box = { min = [0.0, 0.0, 0.01], max = [0.2, 0.2, 0.21] } }',
          'shape = { mesh = { file = "nowhere.msh", group = "ice" } }'), {},
     ["ice[0].shape.mesh"]),
    # overlapping ice bodies, monitors off their structure
    ("ice_boxes_overlap",
     _add(SECOND_ICE.format(name="floe2", shape="{ box = { min = [0.1, 0.1, 0.11], "
                                                "max = [0.3, 0.3, 0.31] } }")),
     {}, ["ice[1].shape", "'floe'", "'floe2'", "overlap", "min = [0.1, 0.1, 0.11]"]),
    ("ice_sphere_inside_box",
     _add(SECOND_ICE.format(name="ball", shape="{ sphere = { center = [0.1, 0.1, 0.11], "
                                               "radius = 0.06 } }")),
     {}, ["ice[1].shape", "'ball'", "overlap"]),
    ("ice_same_box_twice",
     _add(SECOND_ICE.format(name="twin", shape="{ box = { min = [0.0, 0.0, 0.01], "
                                               "max = [0.2, 0.2, 0.21] } }")),
     {}, ["ice[1].shape", "'twin'", "overlap"]),
    ("monitor_far_away", _sub("point = [0.1, 0.1, 0.0]", "point = [5.0, 5.0, 5.0]"), {},
     ["monitor[0].point", "element size"]),
    ("monitor_just_off", _sub("point = [0.1, 0.1, 0.0]", "point = [0.1, 0.1, 0.6]"), {},
     ["monitor[0].point"]),
    # model scripts
    ("script_raises_on_import", _script("bad.py"), {"bad.py": RAISING_IMPORT},
     ["structure[0].mesh", "bad.py, line 2", "RuntimeError", "bad geometry"]),
    ("script_build_raises", _script("div.py"), {"div.py": RAISING_BUILD},
     ["structure[0].mesh", "div.py, line 6", "ZeroDivisionError"]),
    ("script_syntax_error", _script("syn.py"), {"syn.py": SYNTAX_ERROR},
     ["structure[0].mesh", "syn.py, line 1", "SyntaxError"]),
    ("script_without_build", _script("nob.py"), {"nob.py": NO_BUILD},
     ["structure[0].mesh", "build"]),
    ("model_parameter_unknown", _sub("divisions_x = 2,", "divisions_x = 2, divisons_z = 1,"), {},
     ["structure[0].params.divisons_z", "divisions_z", "length_x"]),
    ("model_parameter_wrong_type", _sub("divisions_x = 2,", 'divisions_x = "two",'), {},
     ["structure[0].params.divisions_x"]),
    ("model_parameter_bad_face", _sub('fixed_faces = "z0"', 'fixed_faces = "q9"'), {},
     ["structure[0].params.fixed_faces"]),
    # mesh groups reported against their own field
    ("fixed_group_missing", _sub('fixed_groups = ["fixed"]', 'fixed_groups = ["fixed", "nope"]'),
     {}, ["structure[0].fixed_groups[1]", "nope", "contact, fixed, solid"]),
    ("contact_group_missing", _sub("element_order = 1", 'element_order = 1\ncontact_group = "x"'),
     {}, ["structure[0].contact_group", "contact, fixed, solid"]),
    ("support_group_missing",
     _sub("element_order = 1", 'element_order = 1\nsupports = [{ group = "nope", '
                               'components = ["x"] }]'), {}, ["structure[0].supports[0].group"]),
    ("load_group_missing",
     _sub("element_order = 1", 'element_order = 1\nloads = [{ group = "nope", '
                               'pressure = 1e5 }]'), {}, ["structure[0].loads[0].group"]),
    # numeric ranges
    ("energy_tolerance_zero", _sub("end_time = 1e-5", "end_time = 1e-5\nenergy_tolerance = 0"), {},
     ["run.energy_tolerance", "> 0"]),
    ("energy_tolerance_above_one",
     _sub("end_time = 1e-5", "end_time = 1e-5\nenergy_tolerance = 2.0"), {},
     ["run.energy_tolerance", "<= 1"]),
    ("check_interval_zero",
     _sub("end_time = 1e-5", "end_time = 1e-5\nstability_check_interval_steps = 0"), {},
     ["run.stability_check_interval_steps"]),
    ("end_time_nan", _sub("end_time = 1e-5", "end_time = nan"), {}, ["run.end_time", "finite"]),
    ("dx_zero", _sub("dx = 0.05", "dx = 0.0"), {}, ["ice[0].dx", "> 0"]),
    ("ice_density_infinite", _sub("dx = 0.05\n", "dx = 0.05\nmaterial = { density = inf }\n"), {},
     ["ice[0].material.density", "finite"]),
    ("steel_poisson_half",
     _sub("element_order = 1", "element_order = 1\nmaterial = { poisson_ratio = 0.5 }"), {},
     ["structure[0].material.poisson_ratio", "< 0.5"]),
    ("friction_negative",
     _add('\n[[contact]]\nice = "floe"\nstructure = "wall"\nfriction = -0.1\n'), {},
     ["contact[0].friction", ">= 0"]),
    ("element_order_three", _sub("element_order = 1", "element_order = 3"), {},
     ["structure[0].element_order"]),
    ("damping_negative",
     _sub("element_order = 1", "element_order = 1\ndamping = { alpha = -1.0 }"), {},
     ["structure[0].damping.alpha", ">= 0"]),
]


def _files(root: Path, out: Path) -> set[Path]:
    """Every file under ``root`` except those in ``out`` (the run may write there)."""
    return {p for p in root.rglob("*") if p.is_file() and out not in p.parents}


def _run_bad(tmp_path: Path, capsys, argv: list[str], out: Path) -> str:
    """Run ``pdfem`` with ``argv``; assert exit 2, no traceback, nothing new outside ``out``;
    the message."""
    before = _files(tmp_path, out)
    status = main(argv)
    err = capsys.readouterr().err
    assert status == 2, err
    assert "Traceback" not in err, err
    assert _files(tmp_path, out) == before, "a file was written outside --out"
    return err


@pytest.mark.parametrize("edit, files, fragments",
                         [pytest.param(*c[1:], id=c[0]) for c in CORPUS])
def test_bad_case_exits_2(tmp_path, capsys, monkeypatch, edit, files, fragments):
    """The case exits 2 naming the field (and what is valid)."""
    monkeypatch.chdir(tmp_path)
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    case = tmp_path / "case.toml"
    case.write_text(edit(BASE))
    out = tmp_path / "out"
    err = _run_bad(tmp_path, capsys, ["run", str(case), "--out", str(out), "--quiet"], out)
    assert "case.toml" in err
    for fragment in fragments:
        assert fragment in err, (fragment, err)


def _case(tmp_path: Path) -> Path:
    case = tmp_path / "case.toml"
    case.write_text(BASE)
    return case


def test_out_is_a_file(tmp_path, capsys, monkeypatch):
    """``--out`` naming a file: exit 2 naming --out."""
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "results"
    out.write_text("not a directory")
    err = _run_bad(tmp_path, capsys, ["run", str(_case(tmp_path)), "--out", str(out)], out)
    assert "--out" in err and "is a file" in err


def test_out_below_a_file(tmp_path, capsys, monkeypatch):
    """``--out`` that cannot be created (its parent is a file): exit 2 naming --out."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "f").write_text("x")
    out = tmp_path / "f" / "sub"
    err = _run_bad(tmp_path, capsys, ["run", str(_case(tmp_path)), "--out", str(out)], out)
    assert "--out" in err and "cannot create" in err


def test_out_not_writable(tmp_path, capsys, monkeypatch):
    """``--out`` in a read-only place (/proc): exit 2 naming --out."""
    monkeypatch.chdir(tmp_path)
    out = Path("/proc/pdfem-out")
    err = _run_bad(tmp_path, capsys, ["run", str(_case(tmp_path)), "--out", str(out)], out)
    assert "--out" in err


def test_out_locked_by_a_living_run(tmp_path, capsys, monkeypatch):
    """A second run into an ``--out`` whose lock a living process holds: exit 2 naming its pid;
    the lock is left to its holder."""
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    holder = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        import socket
        (out / LOCK_NAME).write_text(f"{holder.pid}@{socket.gethostname()}\n")
        err = _run_bad(tmp_path, capsys, ["run", str(_case(tmp_path)), "--out", str(out)],
                       out)
        assert f"pid {holder.pid}" in err and "--out" in err
        assert (out / LOCK_NAME).read_text().startswith(str(holder.pid))
    finally:
        holder.kill()
        holder.wait()


def test_stale_lock_is_taken_over_and_released(tmp_path):
    """A lock left by a dead process is taken over; the lock is released at exit, also when the
    run raises."""
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    (tmp_path / LOCK_NAME).write_text(f"{dead.pid}\n")
    with pytest.raises(RuntimeError):
        with OutDirLock(tmp_path):
            assert (tmp_path / LOCK_NAME).read_text().startswith(str(os.getpid()))
            raise RuntimeError("a failing run")
    assert not (tmp_path / LOCK_NAME).exists()
