"""A corpus of bad inputs: each makes ``pdfem run`` exit 2 with one message naming the file, the
field and what is valid, and no traceback; and (:data:`COMMANDS`, issue 31) bad options of
``pdfem post``, ``modes``, ``validate`` and ``mesh``, which exit 2 writing nothing, and a
closed standard output, which ends ``pdfem post --json`` quietly.

Reference: the contract of the command line (DESIGN.md, "Command line": exit 2 for bad input,
the message names file and field). Each case is a small valid case with one thing wrong. The
inputs of :data:`CONSOLE` (one per stage: the case file, the structure's mesh, the time step of
the built body) run the installed console script as a user would; the others run its code in
this process (:func:`support.cli.run_main`: the same ``main``, without an interpreter start of
about a second each).
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

from support.cli import pdfem_command, run_main, run_pdfem
from support.results import write_swinging_monitor

RUN = "[run]\nend_time = 1e-4\noutput_interval = 5e-5\n"
ICE = ("[[ice]]\nname = 'cube'\ndx = 0.01\n"
       "shape = { box = { min = [0, 0, 0.0005], max = [0.04, 0.04, 0.0405] } }\n")
STRUCT = ("[[structure]]\nname = 'block'\nmesh = 'block.msh'\nfixed_groups = ['fixed']\n"
          "contact_group = 'contact'\n")

DEGENERATE_MSH = """$MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
2
2 1 "contact"
3 2 "solid"
$EndPhysicalNames
$Nodes
4
1 0 0 -1
2 1 0 -1
3 0 1 -1
4 1 1 -1
$EndNodes
$Elements
2
1 2 2 1 1 1 3 2
2 4 2 2 1 1 3 2 4
$EndElements
"""

# (id, case text, extra files {name: text}, fragments the message must contain)
CORPUS = [
    ("not_toml", "[run\nend_time = 1", {}, ["not valid TOML"]),
    ("no_run_table", ICE, {}, ["'run'", "required"]),
    ("unknown_run_key", RUN + "end_tme = 1\n" + ICE, {}, ["run.end_tme", "unknown key"]),
    ("negative_end_time", RUN.replace("1e-4", "-1e-4") + ICE, {}, ["run.end_time", "> 0"]),
    ("output_interval_longer_than_run", RUN.replace("5e-5", "1e-3") + ICE, {},
     ["run.output_interval", "longer than the run"]),
    ("safety_factor_above_one", RUN + "safety_factor = 1.5\n" + ICE, {},
     ["run.safety_factor", "<= 1"]),
    ("unknown_pd_loop", RUN + "pd_loop = 'fast'\n" + ICE, {}, ["run.pd_loop", "pairs"]),
    ("gravity_two_components", RUN + "gravity = [0, -9.81]\n" + ICE, {},
     ["run.gravity", "three finite numbers"]),
    ("negative_substeps", RUN + "substeps = -1\n" + ICE, {}, ["run.substeps", "whole number"]),
    ("checkpoint_steps_not_whole", RUN + "checkpoint_interval_steps = 2.5\n" + ICE, {},
     ["run.checkpoint_interval_steps", "whole number"]),
    ("checkpoint_minutes_negative", RUN + "checkpoint_interval_minutes = -1\n" + ICE, {},
     ["run.checkpoint_interval_minutes", ">= 0"]),
    ("allow_unstable_not_boolean", RUN + "allow_unstable_time_step = 'yes'\n" + ICE, {},
     ["run.allow_unstable_time_step", "true or false"]),
    ("time_step_above_stable", RUN + "time_step = 1e-4\n" + ICE, {},
     ["run.time_step", "stable step", "allow_unstable_time_step"]),
    ("no_bodies", RUN, {}, ["at least one"]),
    ("negative_dx", RUN + ICE.replace("dx = 0.01", "dx = -0.01"), {}, ["ice[0].dx", "> 0"]),
    ("horizon_not_above_spacing", RUN + ICE + "horizon = 0.005\n", {},
     ["ice[0].horizon", "larger than the spacing"]),
    ("poisson_ratio_half", RUN + ICE + "material = { poisson_ratio = 0.5 }\n", {},
     ["ice[0].material.poisson_ratio", "< 0.5"]),
    ("density_as_text", RUN + ICE + "material = { density = '900 kg/m3' }\n", {},
     ["ice[0].material.density", "finite number"]),
    ("fracture_energy_and_critical_stretch",
     RUN + ICE + "material = { fracture_energy = 10, critical_stretch = 1e-3 }\n", {},
     ["ice[0].material.critical_stretch", "not both"]),
    ("two_shapes", RUN + ICE.replace("shape = { box", "shape = { sphere = { center = [0,0,0], "
                                     "radius = 1 }, box"), {}, ["ice[0].shape", "exactly one"]),
    ("fixed_region_selects_nothing",
     RUN + ICE + "fixed = [ { box = { min = [1, 1, 1], max = [2, 2, 2] } } ]\n", {},
     ["ice[0].fixed[0]", "contains no particle"]),
    ("crack_normal_zero",
     RUN + ICE + "cracks = [ { point = [0.02, 0.02, 0.02], normal = [0, 0, 0], "
     "box = { min = [0, 0, 0], max = [0.04, 0.04, 0.04] } } ]\n", {},
     ["ice[0].cracks[0].normal", "must not be zero"]),
    ("ice_shape_mesh_missing", RUN + ICE.replace(
        "shape = { box = { min = [0, 0, 0.0005], max = [0.04, 0.04, 0.0405] } }",
        "shape = { mesh = { file = 'floe.stl' } }"), {}, ["ice[0].shape.mesh.file", "no such"]),
    ("ice_shape_mesh_open", RUN + ICE.replace(
        "shape = { box = { min = [0, 0, 0.0005], max = [0.04, 0.04, 0.0405] } }",
        "shape = { mesh = { file = 'open.stl' } }"),
     {"open.stl": "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                  "vertex 0 1 0\nendloop\nendfacet\nendsolid s\n"},
     ["ice[0].shape", "closed"]),
    ("duplicate_names", RUN + ICE + ICE.replace("[0, 0, 0.0005]", "[1, 1, 1]").replace(
        "[0.04, 0.04, 0.0405]", "[1.04, 1.04, 1.04]"), {}, ["ice[1].name", "unique"]),
    ("too_large_for_memory", RUN + ICE.replace("max = [0.04, 0.04, 0.0405]",
                                               "max = [10, 10, 10.0005]").replace(
        "dx = 0.01", "dx = 0.001"), {}, ["ice[0].dx", "of memory", "particles"]),
    ("structure_mesh_missing", RUN + ICE + STRUCT, {}, ["structure[0].mesh", "no such file"]),
    ("structure_mesh_not_a_mesh", RUN + ICE + STRUCT, {"block.msh": "this is not a mesh\n"},
     ["structure[0].mesh", "not a gmsh"]),
    ("structure_group_missing", RUN + ICE + STRUCT.replace("['fixed']", "['clamped']"),
     {"block.msh": None}, ["structure[0].fixed_groups[0]", "clamped", "fixed"]),
    ("structure_degenerate_element", RUN + ICE + STRUCT.replace("fixed_groups = ['fixed']\n", ""),
     {"block.msh": DEGENERATE_MSH}, ["structure[0].mesh", "degenerate"]),
    ("structure_kind_unknown", RUN + ICE + STRUCT + "kind = 'plastic'\n", {"block.msh": None},
     ["structure[0].kind", "elastic"]),
    ("structure_poisson_negative_two", RUN + ICE + STRUCT
     + "material = { poisson_ratio = -2 }\n", {"block.msh": None},
     ["structure[0].material.poisson_ratio", "> -1"]),
    ("contact_unknown_ice", RUN + ICE + STRUCT + "[[contact]]\nice = 'floe'\nstructure = 'block'\n",
     {"block.msh": None}, ["contact[0].ice", "no ice body of that name", "cube"]),
    ("contact_unknown_structure",
     RUN + ICE + STRUCT + "[[contact]]\nice = 'cube'\nstructure = 'hull'\n", {"block.msh": None},
     ["contact[0].structure", "no structure of that name", "block"]),
    ("monitor_unknown_structure",
     RUN + ICE + STRUCT + "[[monitor]]\nname = 'm'\nstructure = 'hull'\npoint = [0, 0, 0]\n",
     {"block.msh": None}, ["monitor[0].structure", "no structure of that name"]),
    ("ice_starts_inside_structure", RUN + ICE + STRUCT,
     {"block.msh": None}, ["contact", "start inside structure"]),
]


CONSOLE = {"not_toml", "structure_group_missing", "time_step_above_stable"}
"""Inputs run through the installed console script (a new process each)."""


@pytest.fixture(scope="module")
def block_msh(tmp_path_factory, gmsh_box) -> str:
    """A hexahedral block [0, 0.1] x [0, 0.1] x [0, 0.02] m, groups "fixed" (z = 0) and
    "contact" (z = 0.02): the cube of ICE overlaps it (only the case that says so gets that far)."""
    d = tmp_path_factory.mktemp("mesh")
    path = gmsh_box(d / "block.msh", (0.1, 0.1, 0.02), face_groups={"fixed": ["z0"],
                                                                   "contact": ["z1"]},
                    divisions=(2, 2, 1))
    return path.read_text()


@pytest.mark.parametrize("name,text,files,fragments", CORPUS, ids=[c[0] for c in CORPUS])
def test_bad_input_exits_2_with_a_clear_message(name, text, files, fragments, tmp_path,
                                                 block_msh):
    """Exit status 2, no traceback, a one-paragraph message naming the case file and the
    fragments listed for this input (field, value or what is valid)."""
    case = tmp_path / f"{name}.toml"
    case.write_text(text)
    for fname, content in files.items():
        (tmp_path / fname).write_text(block_msh if content is None else content)
    run = run_pdfem if name in CONSOLE else run_main
    r = run("run", str(case), "--out", str(tmp_path / "out"), "--quiet")
    assert r.returncode == 2, r.stderr
    assert "Traceback" not in r.stderr
    message = r.stderr.strip().splitlines()[-1]
    assert len(r.stderr.strip().splitlines()) <= 2, r.stderr
    assert str(tmp_path) in r.stderr
    for fragment in fragments:
        assert fragment in message, (fragment, message)


def test_corpus_is_large_and_distinct():
    """The issue asks for at least 25 distinct bad inputs."""
    assert len(CORPUS) >= 25 and len({c[0] for c in CORPUS}) == len(CORPUS)
    assert len({c[1] + str(c[2]) for c in CORPUS}) == len(CORPUS)
    assert CONSOLE <= {c[0] for c in CORPUS}


# -- the other commands' options (issue 31): post, modes, validate, mesh ----------------------

BOX = Path(__file__).resolve().parents[2] / "models" / "validation" / "box.py"
D_CURVE = "m=3,stress=90e6,cycles=2e6"
WALL = (f"[[structure]]\nname = 'wall'\nmesh = '{BOX.as_posix()}'\nfixed_groups = ['fixed']\n"
        "params = { divisions_x = 2, divisions_y = 2, divisions_z = 1, length_x = 0.3, "
        "length_y = 0.3, length_z = 0.05, fixed_faces = 'z0', contact_faces = 'z1' }\n")
RAM = (f"[[structure]]\nname = 'ram'\nkind = 'rigid'\nmesh = '{BOX.as_posix()}'\n"
       "params = { surface_only = true, origin_x = 1.0, length_x = 0.1, length_y = 0.1, "
       "length_z = 0.1, element_size = 0.05 }\n")
CASES = {"rigid.toml": RUN + RAM, "ice.toml": RUN + ICE, "both.toml": RUN + WALL + RAM}
"""Case files of the ``modes`` entries: a rigid structure only, ice only, an elastic wall and a
rigid ram."""

# (id, argv with {results} {tmp} {file} placeholders, fragments of the last line of stderr)
COMMANDS = [
    ("post_lowpass_zero", ["post", "{results}", "--lowpass", "0"], ["'--lowpass'", "> 0"]),
    ("post_lowpass_nan", ["post", "{results}", "--lowpass", "nan"], ["'--lowpass'", "finite"]),
    ("post_lowpass_inf", ["post", "{results}", "--lowpass", "inf"], ["'--lowpass'", "finite"]),
    ("post_lowpass_text", ["post", "{results}", "--lowpass", "fast"], ["--lowpass", "float"]),
    ("post_events_inf", ["post", "{results}", "--sn", D_CURVE, "--events", "inf"],
     ["'--events'", "finite"]),
    ("post_sn_bins_zero", ["post", "{results}", "--sn", D_CURVE, "--sn-bins", "0"],
     ["'--sn-bins'", "at least 1"]),
    ("post_sn_slope_nan", ["post", "{results}", "--sn", "m=nan,stress=90e6,cycles=2e6"],
     ["'--sn'", "m must be a positive number"]),
    ("post_sn_stress_inf", ["post", "{results}", "--sn", "m=3,stress=inf,cycles=2e6"],
     ["'--sn'", "stress must be a positive number"]),
    ("post_sn_stress_without_curve", ["post", "{results}", "--sn-stress", "xx"],
     ["'--sn-stress'", "needs an S-N curve"]),
    ("post_csv_in_missing_dir", ["post", "{results}", "--csv", "{tmp}/nowhere/h.csv"],
     ["'--csv'", "cannot write"]),
    ("post_plots_on_a_file", ["post", "{results}", "--plots", "{file}"],
     ["'--plots'", "cannot write"]),
    ("post_csv_empty", ["post", "{results}", "--csv", ""], ["--csv", "not an empty string"]),
    ("post_plots_blank", ["post", "{results}", "--plots", " "], ["--plots", "not an empty"]),
    ("run_out_empty", ["run", "{tmp}/both.toml", "--out", ""], ["--out", "not an empty"]),
    ("modes_out_empty", ["modes", "{tmp}/both.toml", "--out", ""], ["--out", "not an empty"]),
    ("validate_report_empty", ["validate", "--report", ""], ["--report", "not an empty"]),
    ("mesh_output_empty", ["mesh", str(BOX), "-o", ""], ["--output", "not an empty"]),
    ("post_results_missing", ["post", "{tmp}/none.h5"], ["none.h5", "no such results file"]),
    ("post_results_not_hdf5", ["post", "{file}"], ["notes.txt", "not an HDF5 file"]),
    ("modes_rigid_only", ["modes", "{tmp}/rigid.toml", "--out", "{tmp}/out"],
     ["rigid.toml", "no elastic structure", "'ram' (rigid)"]),
    ("modes_ice_only", ["modes", "{tmp}/ice.toml", "--out", "{tmp}/out"],
     ["ice.toml", "no elastic structure", "structures: none"]),
    ("modes_structure_rigid", ["modes", "{tmp}/both.toml", "--structure", "ram", "--out",
                               "{tmp}/out"], ["structure[1].kind", "only elastic structures"]),
    ("modes_structure_unknown", ["modes", "{tmp}/both.toml", "--structure", "hull", "--out",
                                 "{tmp}/out"], ["'--structure'", "no structure of that name"]),
    ("modes_n_zero", ["modes", "{tmp}/both.toml", "--n", "0", "--out", "{tmp}/out"],
     ["'--n'", "at least 1"]),
    ("modes_out_is_a_file", ["modes", "{tmp}/both.toml", "--out", "{file}"],
     ["'--out'", "is a file"]),
    ("validate_unknown_case", ["validate", "--case", "no_such_case"],
     ["'--case'", "unknown validation case"]),
    ("validate_report_is_a_file", ["validate", "--report", "{file}", "--case", "wave_speed"],
     ["'--report'", "is a file"]),
    ("mesh_output_below_a_file", ["mesh", str(BOX), "-o", "{file}/box.msh"],
     ["'--output'", "is a file"]),
    ("mesh_output_is_a_dir", ["mesh", str(BOX), "-o", "{tmp}"], ["'--output'", "directory"]),
    ("mesh_parameter_nan", ["mesh", str(BOX), "--set", "length_x=nan"],
     ["'length_x'", "finite"]),
    ("mesh_parameter_zero", ["mesh", str(BOX), "--set", "length_x=0"], ["'length_x'", "> 0"]),
    ("mesh_script_exits", ["mesh", "{tmp}/ex.py"], ["ex.py, line 2", "called sys.exit(3)"]),
]


@pytest.fixture(scope="module")
def results_file(tmp_path_factory) -> Path:
    """A hand-made results file: one elastic tetrahedron and a monitor 'root' whose xx stress
    swings 40 +- 50 MPa over 10 cycles."""
    return write_swinging_monitor(tmp_path_factory.mktemp("results") / "results.h5",
                                  "bad options")


@pytest.mark.parametrize("name,argv,fragments", COMMANDS, ids=[c[0] for c in COMMANDS])
def test_bad_option_exits_2_and_writes_nothing(name, argv, fragments, tmp_path, monkeypatch,
                                               results_file):
    """Exit status 2, no traceback, the last line of stderr names the option or file, and not
    a file is written (``pdfem modes`` refuses before meshing; ``mesh`` writes no .msh)."""
    monkeypatch.chdir(tmp_path)
    for fname, text in CASES.items():
        (tmp_path / fname).write_text(text)
    (tmp_path / "notes.txt").write_text("not a results file\n")
    (tmp_path / "ex.py").write_text("import sys\nsys.exit(3)\n")
    before = {p for p in tmp_path.rglob("*")}
    r = run_main(*[a.format(results=results_file, tmp=tmp_path, file=tmp_path / "notes.txt")
                   for a in argv])
    assert r.returncode == 2, r.stderr
    assert "Traceback" not in r.stderr
    message = r.stderr.strip().splitlines()[-1]
    for fragment in fragments:
        assert fragment in message, (fragment, message)
    assert {p for p in tmp_path.rglob("*")} == before, "a file or directory was written"


def test_closed_stdout_ends_quietly(results_file):
    """``pdfem post --json`` into a pipe nobody reads (``| head`` gone): exit 1, no
    BrokenPipeError traceback (the reader's end is closed before pdfem starts, so the first
    write fails: deterministic)."""
    read, write = os.pipe()
    os.close(read)
    try:
        r = subprocess.run([*pdfem_command(), "post", str(results_file), "--json"], stdout=write,
                           stderr=subprocess.PIPE, text=True, timeout=300)
    finally:
        os.close(write)
    assert r.returncode == 1, r.stderr
    assert "Traceback" not in r.stderr and "BrokenPipe" not in r.stderr, r.stderr
