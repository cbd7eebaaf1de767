"""Bad inputs of issue 18 (names, paths, overlaps, output directories, model scripts, group
fields, numeric ranges) and issue 31 (:data:`CORPUS_31`: water, ships, moving frames, supports,
element order, the ice law and crushing, paths, NaN and inf in physical fields, keys that would
have no effect, model scripts that exit, keys given twice and deeply nested TOML, and extreme
but valid numbers: sizes, steps and frames no run could hold or finish): each makes
``pdfem run`` exit 2 with a one-paragraph message naming the field, no traceback, and nothing
written outside ``--out``.

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


# -- keys and sections added since (issue 31): water, ships, moving frames, supports, element
#    order, the ice law and crushing, paths, NaN and inf (valid TOML floats) in physical fields,
#    keys that would have no effect, and the TOML text itself

SHIP = f"""
[[structure]]
name = "hull"
kind = "ship"
mesh = "{BOX.as_posix()}"
params = {{ surface_only = true, origin_x = 1.0, origin_y = 1.0, origin_z = -0.05, length_x = 0.3, length_y = 0.2, length_z = 0.1, element_size = 0.05 }}
"""
"""A ship (a closed box hull of 0.3 x 0.2 x 0.1 m, half under water) beside the wall."""

RIGID = f"""
[[structure]]
name = "ram"
kind = "rigid"
mesh = "{BOX.as_posix()}"
params = {{ surface_only = true, origin_x = 1.0, origin_y = 1.0, origin_z = 0.0, length_x = 0.1, length_y = 0.1, length_z = 0.1, element_size = 0.05 }}
"""
"""A rigid box beside the wall."""


def _run(extra: str):
    return _sub("end_time = 1e-5", "end_time = 1e-5\n" + extra)


def _floe(extra: str):
    return _sub("dx = 0.05\n", "dx = 0.05\n" + extra + "\n")


def _wall(extra: str):
    return _sub("element_order = 1", "element_order = 1\n" + extra)


def _water(extra: str = ""):
    return _add("\n[water]\n" + extra + "\n")


def _ship(keys: str = "", water: str = "\n[water]\n"):
    return _add(SHIP + keys + "\n" + water)


def _rigid(keys: str):
    return _add(RIGID + keys + "\n")


def _then(*edits):
    def edit(text: str) -> str:
        for e in edits:
            text = e(text)
        return text
    return edit


def _no_ice(text: str) -> str:
    """The case without its ice body (the wall and its monitor stay)."""
    head, _, rest = text.partition("[[ice]]")
    return head + "[[structure]]" + rest.partition("[[structure]]")[2]


DEEP = 2000
"""Nesting depth of the deep TOML entries (the TOML reader recurses once per level)."""

CORPUS_31 = [
    # the TOML text: a key given twice is named by its path; deep nesting is bad input
    ("toml_key_twice", _run("end_time = 2e-5"), {}, ["run.end_time", "given twice", "line 3"]),
    ("toml_key_twice_in_body", _floe("dx = 0.1"), {}, ["ice[0].dx", "given twice"]),
    ("toml_table_twice", _add("\n[run]\n"), {}, ["field 'run'", "declared twice"]),
    ("toml_deep_arrays", _wall("foo = " + "[" * DEEP + "]" * DEEP), {}, ["nested too deeply"]),
    ("toml_deep_tables", _wall("foo = " + "{ a = " * DEEP + "1" + " }" * DEEP), {},
     ["nested too deeply"]),
    ("nested_value_shown_short", _run("title = " + "[" * 300 + "]" * 300), {},
     ["run.title", " ... "]),
    # model scripts that exit
    ("script_exits_on_import", _script("ex.py"), {"ex.py": "import sys\nsys.exit(0)\n"},
     ["structure[0].mesh", "ex.py, line 2", "called sys.exit(0)"]),
    ("script_build_exits", _script("ex.py"),
     {"ex.py": "import sys\n\n\ndef build(path):\n    sys.exit('no mesh')\n"},
     ["structure[0].mesh", "ex.py, line 5", "called sys.exit('no mesh')"]),
    ("script_raises_system_exit", _script("ex.py"), {"ex.py": "raise SystemExit\n"},
     ["structure[0].mesh", "ex.py, line 1", "called sys.exit()"]),
    # NaN and inf in physical fields
    ("run_time_step_inf", _run("time_step = inf"), {}, ["run.time_step", "finite"]),
    ("run_safety_factor_nan", _run("safety_factor = nan"), {}, ["run.safety_factor", "finite"]),
    ("run_gravity_nan", _run("gravity = [0, 0, nan]"), {}, ["run.gravity", "finite"]),
    ("run_output_interval_inf", _run("output_interval = inf"), {}, ["run.output_interval"]),
    ("run_rebalance_imbalance_half", _run("rebalance_imbalance = 0.5"), {},
     ["run.rebalance_imbalance", "> 1"]),
    ("run_output_per_rank_rebalancing", _run("output_per_rank = true\nrebalance_every = 10"), {},
     ["run.output_per_rank", "rebalance_every"]),
    ("ice_dx_nan", _sub("dx = 0.05", "dx = nan"), {}, ["ice[0].dx", "finite"]),
    ("ice_horizon_inf", _floe("horizon = inf"), {}, ["ice[0].horizon", "finite"]),
    ("ice_horizon_factor_one", _floe("horizon_factor = 1.0"), {}, ["ice[0].horizon_factor", "> 1"]),
    ("ice_youngs_modulus_nan", _floe("material = { youngs_modulus = nan }"), {},
     ["ice[0].material.youngs_modulus", "finite"]),
    ("ice_fracture_energy_negative_inf", _floe("material = { fracture_energy = -inf }"), {},
     ["ice[0].material.fracture_energy", "finite"]),
    ("ice_initial_velocity_inf", _floe("initial_velocity = [inf, 0, 0]"), {},
     ["ice[0].initial_velocity", "finite"]),
    ("ice_box_min_nan", _sub("min = [0.0, 0.0, 0.01]", "min = [nan, 0.0, 0.01]"), {},
     ["ice[0].shape", "finite"]),
    ("ice_sphere_radius_inf",
     _sub("box = { min = [0.0, 0.0, 0.01], max = [0.2, 0.2, 0.21] }",
          "sphere = { center = [0.1, 0.1, 0.11], radius = inf }"), {},
     ["ice[0].shape.sphere.radius", "finite"]),
    ("ice_cylinder_radius_zero",
     _sub("box = { min = [0.0, 0.0, 0.01], max = [0.2, 0.2, 0.21] }",
          "cylinder = { base = [0.1, 0.1, 0.01], axis = [0, 0, 1], radius = 0, length = 0.2 }"),
     {}, ["ice[0].shape.cylinder.radius", "> 0"]),
    ("ice_cylinder_axis_zero",
     _sub("box = { min = [0.0, 0.0, 0.01], max = [0.2, 0.2, 0.21] }",
          "cylinder = { base = [0.1, 0.1, 0.01], axis = [0, 0, 0], radius = 0.1, length = 0.2 }"),
     {}, ["ice[0].shape.cylinder"]),
    ("steel_density_inf", _wall("material = { density = inf }"), {},
     ["structure[0].material.density", "finite"]),
    ("steel_youngs_modulus_zero", _wall("material = { youngs_modulus = 0 }"), {},
     ["structure[0].material.youngs_modulus", "> 0"]),
    ("steel_youngs_modulus_nan", _wall("material = { youngs_modulus = nan }"), {},
     ["structure[0].material.youngs_modulus", "finite"]),
    ("damping_beta_nan", _wall("damping = { beta = nan }"), {},
     ["structure[0].damping.beta", "finite"]),
    ("load_pressure_nan", _wall('loads = [{ group = "contact", pressure = nan }]'), {},
     ["structure[0].loads[0].pressure", "finite"]),
    ("load_traction_inf", _wall('loads = [{ group = "contact", traction = [0, 0, -inf] }]'), {},
     ["structure[0].loads[0].traction", "finite"]),
    ("pulse_rise_negative",
     _wall('loads = [{ group = "contact", pressure = 1e5, pulse = { rise = -1e-3 } }]'), {},
     ["structure[0].loads[0].pulse.rise", ">= 0"]),
    ("pulse_hold_inf",
     _wall('loads = [{ group = "contact", pressure = 1e5, pulse = { hold = inf } }]'), {},
     ["structure[0].loads[0].pulse.hold", "finite"]),
    ("contact_friction_nan", _add('\n[[contact]]\nice = "floe"\nstructure = "wall"\n'
                                  'friction = nan\n'), {}, ["contact[0].friction", "finite"]),
    ("contact_search_radius_inf", _add('\n[[contact]]\nice = "floe"\nstructure = "wall"\n'
                                       'search_radius = inf\n'), {},
     ["contact[0].search_radius", "finite"]),
    ("monitor_point_nan", _sub("point = [0.1, 0.1, 0.0]", "point = [0.1, nan, 0.0]"), {},
     ["monitor[0].point", "finite"]),
    ("short_range_contact_text", _run('short_range_contact = "yes"'), {},
     ["run.short_range_contact", "true or false"]),
    ("region_missing", _floe("prescribed_velocity = [{ velocity = [0, 0, -1] }]"), {},
     ["ice[0].prescribed_velocity[0].region", "required"]),
    ("no_fail_two_shapes",
     _floe("no_fail = [{ box = { min = [0, 0, 0], max = [1, 1, 1] }, sphere = { center = [0, 0, "
           "0], radius = 1 } }]"), {}, ["ice[0].no_fail[0]", "exactly one"]),
    ("crack_box_inverted",
     _floe("cracks = [{ point = [0.1, 0.1, 0.1], normal = [1, 0, 0], box = { min = [0.2, 0, 0], "
           "max = [0.0, 0.2, 0.2] } }]"), {}, ["ice[0].cracks[0].box"]),
    ("pulse_fall_without_hold",
     _wall('loads = [{ group = "contact", pressure = 1e5, pulse = { rise = 1e-3, fall = 1e-3 } }]'),
     {}, ["structure[0].loads[0].pulse.fall", "hold"]),
    # the ice law and crushing
    ("failure_unknown", _floe('material = { failure = "plastic" }'), {},
     ["ice[0].material.failure", "critical_stretch"]),
    ("ice_law_without_strength", _floe('material = { failure = "ice" }'), {},
     ["ice[0].material.compressive_strength", "needs"]),
    ("compressive_strength_without_ice_law", _floe("material = { compressive_strength = 3e6 }"),
     {}, ["ice[0].material.compressive_strength", 'failure = "ice"']),
    ("compressive_strength_inf",
     _floe('material = { failure = "ice", compressive_strength = inf }'), {},
     ["ice[0].material.compressive_strength", "finite"]),
    ("friction_angle_sixty",
     _floe('material = { failure = "ice", compressive_strength = 3e6, friction_angle = 60 }'), {},
     ["ice[0].material.friction_angle", "< 60"]),
    ("friction_angle_nan",
     _floe('material = { failure = "ice", compressive_strength = 3e6, friction_angle = nan }'),
     {}, ["ice[0].material.friction_angle", "finite"]),
    ("crushed_friction_above_two",
     _floe('material = { failure = "ice", compressive_strength = 3e6, crushed_friction = 2.5 }'),
     {}, ["ice[0].material.crushed_friction", "<= 2"]),
    ("transition_rate_zero",
     _floe('material = { failure = "ice", compressive_strength = 3e6, transition_rate = 0 }'),
     {}, ["ice[0].material.transition_rate", "> 0"]),
    ("rate_exponent_above_one",
     _floe('material = { failure = "ice", compressive_strength = 3e6, transition_rate = 1e-3, '
           'rate_exponent = 1.5 }'), {}, ["ice[0].material.rate_exponent", "<= 1"]),
    ("rate_exponent_without_transition_rate",
     _floe('material = { failure = "ice", compressive_strength = 3e6, rate_exponent = 0.5 }'),
     {}, ["ice[0].material.rate_exponent", "transition_rate"]),
    ("tensile_and_flexural_strength",
     _floe("material = { tensile_strength = 5e5, flexural_strength = 7e5 }"), {},
     ["ice[0].material.flexural_strength", "not both"]),
    ("tensile_strength_nan", _floe("material = { tensile_strength = nan }"), {},
     ["ice[0].material.tensile_strength", "finite"]),
    ("strength_and_fracture_energy",
     _floe("material = { tensile_strength = 5e5, fracture_energy = 10 }"), {},
     ["ice[0].material.fracture_energy", "not both"]),
    # paths
    ("region_path_times_decrease",
     _floe('prescribed_velocity = [{ region = { box = { min = [0, 0, 0.15], max = [0.2, 0.2, '
           '0.21] } }, path = [[0, 0, 0, 0], [1e-3, 0, 0, 1e-4], [5e-4, 0, 0, 2e-4]] }]'), {},
     ["ice[0].prescribed_velocity[0].path", "increase strictly"]),
    ("region_path_and_velocity",
     _floe('prescribed_velocity = [{ region = { box = { min = [0, 0, 0.15], max = [0.2, 0.2, '
           '0.21] } }, velocity = [0, 0, -1], path = [[0, 0, 0, 0], [1, 0, 0, 1]] }]'), {},
     ["ice[0].prescribed_velocity[0].path", "not both"]),
    ("region_path_row_of_three",
     _floe('prescribed_velocity = [{ region = { box = { min = [0, 0, 0.15], max = [0.2, 0.2, '
           '0.21] } }, path = [[0, 0, 0], [1, 0, 0, 1]] }]'), {},
     ["ice[0].prescribed_velocity[0].path", "row 0"]),
    ("region_path_nan",
     _floe('prescribed_velocity = [{ region = { box = { min = [0, 0, 0.15], max = [0.2, 0.2, '
           '0.21] } }, path = [[0, 0, 0, 0], [1, 0, nan, 1]] }]'), {},
     ["ice[0].prescribed_velocity[0].path", "finite"]),
    ("region_path_with_ramp",
     _floe('prescribed_velocity = [{ region = { box = { min = [0, 0, 0.15], max = [0.2, 0.2, '
           '0.21] } }, path = [[0, 0, 0, 0], [1, 0, 0, 1]], ramp_time = 1e-3 }]'), {},
     ["ice[0].prescribed_velocity[0].ramp_time", "path"]),
    ("region_velocity_ramp_nan",
     _floe('prescribed_velocity = [{ region = { box = { min = [0, 0, 0.15], max = [0.2, 0.2, '
           '0.21] } }, velocity = [0, 0, -1], ramp_time = nan }]'), {},
     ["ice[0].prescribed_velocity[0].ramp_time", "finite"]),
    ("rigid_path_starts_before_zero",
     _rigid("motion = { path = [[-1, 0, 0, 0], [1, 0, 0, 1]] }"), {},
     ["structure[1].motion.path", ">= 0"]),
    ("rigid_path_and_velocity",
     _rigid("motion = { velocity = [1, 0, 0], path = [[0, 0, 0, 0], [1, 1, 0, 0]] }"), {},
     ["structure[1].motion.path", "not both"]),
    # moving frames (an elastic structure's motion)
    ("frame_angular_velocity_nan", _wall("motion = { angular_velocity = [0, 0, nan] }"), {},
     ["structure[0].motion.angular_velocity", "finite"]),
    ("frame_center_inf", _wall("motion = { center = [inf, 0, 0] }"), {},
     ["structure[0].motion.center", "finite"]),
    ("frame_ramp_negative", _wall("motion = { velocity = [1, 0, 0], ramp_time = -1 }"), {},
     ["structure[0].motion.ramp_time", ">= 0"]),
    ("rigid_ramp_time", _rigid("motion = { velocity = [1, 0, 0], ramp_time = 1e-3 }"), {},
     ["structure[1].motion.ramp_time", "elastic structures only"]),
    # supports and element order
    ("support_component_w", _wall('supports = [{ group = "contact", components = ["w"] }]'), {},
     ["structure[0].supports[0].components", '"x", "y", "z"']),
    ("support_components_empty", _wall('supports = [{ group = "contact", components = [] }]'),
     {}, ["structure[0].supports[0].components"]),
    ("support_without_components", _wall('supports = [{ group = "contact" }]'), {},
     ["structure[0].supports[0].components", "required"]),
    ("element_order_zero", _sub("element_order = 1", "element_order = 0"), {},
     ["structure[0].element_order", ">= 1"]),
    ("element_order_not_whole", _sub("element_order = 1", "element_order = 1.5"), {},
     ["structure[0].element_order", "whole number"]),
    ("integrator_unknown", _wall('integrator = "leapfrog"'), {},
     ["structure[0].integrator", "explicit"]),
    # keys that would have no effect on the structure's kind
    ("rigid_element_order", _rigid("element_order = 1"), {},
     ["structure[1].element_order", "no effect", "rigid"]),
    ("rigid_material", _rigid("material = { density = 7850 }"), {},
     ["structure[1].material", "no effect"]),
    ("rigid_damping", _rigid("damping = { alpha = 1.0 }"), {},
     ["structure[1].damping", "no effect"]),
    ("rigid_integrator", _rigid('integrator = "explicit"'), {},
     ["structure[1].integrator", "no effect"]),
    ("rigid_supports", _rigid('supports = [{ group = "contact", components = ["z"] }]'), {},
     ["structure[1].supports", "no effect"]),
    ("rigid_loads", _rigid('loads = [{ group = "contact", pressure = 1e5 }]'), {},
     ["structure[1].loads", "no effect"]),
    ("rigid_ship_table", _rigid("ship = { mass = 10.0 }"), {},
     ["structure[1].ship", "no effect"]),
    ("elastic_ship_table", _wall("ship = { mass = 10.0 }"), {},
     ["structure[0].ship", "only a ship"]),
    ("ship_element_order", _ship("element_order = 2"), {},
     ["structure[1].element_order", "no effect", "ship"]),
    ("ship_motion", _ship("motion = { velocity = [1, 0, 0] }"), {},
     ["structure[1].motion", "no effect"]),
    ("ship_fixed_groups", _ship('fixed_groups = ["contact"]'), {},
     ["structure[1].fixed_groups", "no effect"]),
    ("ship_attached_to_ship", _ship('attached_to = "wall"'), {},
     ["structure[1].attached_to", "no effect"]),
    # ships
    ("ship_radius_of_gyration_zero", _ship("ship = { radii_of_gyration = [0.0, 0.1, 0.1] }"), {},
     ["structure[1].ship.radii_of_gyration", "> 0"]),
    ("ship_radius_of_gyration_negative",
     _ship("ship = { radii_of_gyration = [0.1, -0.1, 0.1] }"), {},
     ["structure[1].ship.radii_of_gyration", "> 0"]),
    ("ship_radius_of_gyration_nan", _ship("ship = { radii_of_gyration = [0.1, 0.1, nan] }"), {},
     ["structure[1].ship.radii_of_gyration", "finite"]),
    ("ship_mass_zero", _ship("ship = { mass = 0.0 }"), {}, ["structure[1].ship.mass", "> 0"]),
    ("ship_mass_nan", _ship("ship = { mass = nan }"), {}, ["structure[1].ship.mass", "finite"]),
    ("ship_thrust_inf", _ship("ship = { thrust = inf }"), {},
     ["structure[1].ship.thrust", "finite"]),
    ("ship_surge_speed_nan", _ship("ship = { surge_speed = nan }"), {},
     ["structure[1].ship.surge_speed", "finite"]),
    ("ship_initial_displacement_nan", _ship("ship = { initial_displacement = [0, 0, nan] }"), {},
     ["structure[1].ship.initial_displacement", "finite"]),
    ("ship_initial_rotation_inf", _ship("ship = { initial_rotation = [inf, 0, 0] }"), {},
     ["structure[1].ship.initial_rotation", "finite"]),
    ("ship_initial_velocity_two", _ship("ship = { initial_velocity = [1, 0] }"), {},
     ["structure[1].ship.initial_velocity", "three"]),
    ("ship_initial_angular_velocity_nan",
     _ship("ship = { initial_angular_velocity = [0, nan, 0] }"), {},
     ["structure[1].ship.initial_angular_velocity", "finite"]),
    ("ship_cog_inf", _ship("ship = { center_of_gravity = [1.15, 1.1, inf] }"), {},
     ["structure[1].ship.center_of_gravity", "finite"]),
    ("ship_ramp_without_surge_speed", _ship("ship = { ramp_time = 1.0 }"), {},
     ["structure[1].ship.ramp_time", "surge_speed"]),
    ("ship_unknown_key", _ship("ship = { draught = 0.05 }"), {},
     ["structure[1].ship.draught", "unknown key"]),
    ("ship_without_water", _ship(water=""), {}, ["structure[1].kind", "[water]"]),
    ("attached_to_not_a_ship", _wall('attached_to = "floe"'), {},
     ["structure[0].attached_to", "no ship (kind = \"ship\") of that name"]),
    ("attached_with_motion", _then(_ship(), _wall('attached_to = "hull"\n'
                                                  'motion = { velocity = [1, 0, 0] }')), {},
     ["structure[0].attached_to", "without a motion"]),
    ("attached_implicit", _then(_ship(), _wall('attached_to = "hull"\nintegrator = "implicit"')),
     {}, ["structure[0].integrator", "explicit"]),
    # water
    ("water_density_zero", _water("density = 0"), {}, ["water.density", "> 0"]),
    ("water_density_nan", _water("density = nan"), {}, ["water.density", "finite"]),
    ("water_level_inf", _water("level = inf"), {}, ["water.level", "finite"]),
    ("water_current_nan", _water("current = [nan, 0, 0]"), {}, ["water.current", "finite"]),
    ("water_linear_drag_negative", _water("linear_drag = -1"), {},
     ["water.linear_drag", ">= 0"]),
    ("water_drag_coefficient_inf", _water("drag_coefficient = inf"), {},
     ["water.drag_coefficient", "finite"]),
    ("water_added_mass_negative", _water("added_mass = -0.5"), {}, ["water.added_mass", ">= 0"]),
    ("water_unknown_key", _water("salinity = 35"), {}, ["water.salinity", "unknown key"]),
    ("water_gravity_sideways", _then(_water(), _run("gravity = [9.81, 0, 0]")), {},
     ["run.gravity", "down z"]),
    ("water_without_ice_or_ship", _then(_no_ice, _water()), {}, ["field 'water'", "neither"]),
    ("water_current_without_ice", _then(_no_ice, _ship(water="\n[water]\ncurrent = [1, 0, 0]\n")),
     {}, ["water.current", "ice bodies only"]),
    # extreme but valid numbers: sizes, steps and frames no run could hold or finish
    ("ice_dx_tiny", _sub("dx = 0.05", "dx = 1e-300"), {}, ["ice[0].dx", "1e+13 particles"]),
    ("ice_box_huge", _sub("max = [0.2, 0.2, 0.21]", "max = [1e300, 0.2, 0.21]"), {},
     ["ice[0].dx", "ice[0].shape", "1e+300 x 0.2", "1e+13 particles"]),
    ("ice_horizon_factor_huge", _floe("horizon_factor = 1e10"), {},
     ["ice[0].horizon_factor", "at most 20 dx"]),
    ("ice_horizon_huge", _floe("horizon = 1e9"), {}, ["ice[0].horizon", "at most 20 dx"]),
    ("run_time_step_tiny", _run("time_step = 1e-300"), {},
     ["run.time_step", "1e+09", "time_step >= end_time / 1e+09 = 1e-14 s"]),
    ("run_safety_factor_tiny", _run("safety_factor = 1e-300"), {},
     ["run.safety_factor", "1e+09"]),
    ("run_end_time_huge", _sub("end_time = 1e-5", "end_time = 1e300"), {},
     ["run.end_time", "1e+09", "choose end_time <="]),
    ("run_output_interval_tiny", _run("output_interval = 1e-300"), {},
     ["run.output_interval", "1,000,000", ">= 1e-11 s"]),
    ("run_substeps_huge", _run("substeps = 1000000000000"), {},
     ["run.substeps", "1e+09", "substeps <= 1,000,000,000"]),
    ("ice_youngs_modulus_huge", _floe("material = { youngs_modulus = 1e300 }"), {},
     ["ice[0].material", "youngs_modulus = 1e+300 Pa", "wave speed", "1e+09"]),
    ("ice_density_tiny", _floe("material = { density = 1e-300 }"), {},
     ["ice[0].material", "density = 1e-300", "infinitely many steps"]),
    ("steel_youngs_modulus_huge", _wall("material = { youngs_modulus = 1e300 }"), {},
     ["structure[0].material", "youngs_modulus = 1e+300 Pa", "1e+09"]),
    ("steel_youngs_modulus_max_float", _wall("material = { youngs_modulus = 1.7e308 }"), {},
     ["structure[0].material", "infinitely many steps"]),
    ("steel_density_tiny", _wall("material = { density = 1e-300 }"), {},
     ["structure[0].material", "density = 1e-300"]),
    ("damping_beta_huge", _wall("damping = { beta = 1e300 }"), {},
     ["structure[0].damping.beta", "1e+09"]),
]
"""Issue 31's entries: each is bad input (exit 2) naming the field."""

CORPUS += CORPUS_31


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
    assert len(err.strip().splitlines()) == 1, err  # one paragraph
    for fragment in fragments:
        assert fragment in err, (fragment, err)


@pytest.mark.parametrize("name", ["ice_dx_tiny", "ice_density_tiny", "run_time_step_tiny"])
def test_estimate_refuses_sizes_and_steps(tmp_path, capsys, monkeypatch, name):
    """``pdfem run --estimate`` refuses the sizes and step counts a run refuses (issue 31),
    naming the same field, before its calibration runs."""
    monkeypatch.chdir(tmp_path)
    edit, _, fragments = next(c[1:] for c in CORPUS_31 if c[0] == name)
    case = tmp_path / "case.toml"
    case.write_text(edit(BASE))
    err = _run_bad(tmp_path, capsys, ["run", str(case), "--estimate"], tmp_path / "out")
    assert fragments[0] in err and len(err.strip().splitlines()) == 1, err


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


def test_byte_order_mark_is_not_bad_input(tmp_path):
    """A case file saved with a UTF-8 byte-order mark (some Windows editors) reads as without."""
    from pdfem.case.schema import load_case
    case = tmp_path / "bom.toml"
    case.write_text(BASE, encoding="utf-8-sig")
    assert case.read_bytes()[:3] == b"\xef\xbb\xbf"
    assert load_case(case).run.end_time == 1e-5
