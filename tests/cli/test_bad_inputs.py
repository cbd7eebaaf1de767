"""A corpus of bad inputs: each makes ``pdfem run`` exit 2 with one message naming the file, the
field and what is valid, and no traceback.

Reference: the contract of the command line (DESIGN.md, "Command line": exit 2 for bad input,
the message names file and field). Each case is a small valid case with one thing wrong. The
inputs of :data:`CONSOLE` (one per stage: the case file, the structure's mesh, the time step of
the built body) run the installed console script as a user would; the others run its code in
this process (:func:`support.cli.run_main`: the same ``main``, without an interpreter start of
about a second each).
"""

from __future__ import annotations


import pytest

from support.cli import run_main, run_pdfem

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
