"""Named fixed and prescribed ice regions: their reaction forces, displacement paths of ice regions
and rigid bodies, the case-file checks, and the results and post-processing of the reactions.

References: Hooke's law for a bar in uniaxial stress, N = E A eps (e.g. Timoshenko & Goodier
1970, ch. 1); Newton's third law at static equilibrium (the two grips of a bar at rest carry equal
and opposite forces); linear interpolation of the path's points (the path's definition); the
energy balance (work of the drivers = kinetic + strain energy of an elastic bar); rigid-body
kinematics. MPI runs are ``mpiexec -n 2`` subprocesses with a timeout, as in
tests/pd/test_mpi_distributed.py.
"""

from __future__ import annotations

import shutil
import textwrap
from pathlib import Path

import h5py
import numpy as np
import pytest

from pdfem.case.loader import load_case
from pdfem.cli.main import main
from pdfem.motion.rigid import RigidBody, rotation_matrix
from pdfem.geometry.path import DisplacementPath
from pdfem.geometry.shapes import Box
from pdfem.output import read_results
from pdfem.pd.body import IceBody
from pdfem.pd.materials.lps import IceMaterial
from pdfem.post.summary import summarize
from pdfem.post.table import format_summary
from pdfem.run.driver import run_case

from support.mpi import run_script

E, RHO, NU, DX = 4.1e9, 900.0, 0.3, 0.01


def _bar(n: int, length: float, ramp: float, stretch: float) -> IceBody:
    """An n x n (particles) bar along x held at x < 2 dx ("left") and pulled at its other end
    along the path 0 -> ``stretch`` (m) over ``ramp`` (s), then held ("grip")."""
    mat = IceMaterial(density=RHO, youngs_modulus=E, poisson_ratio=NU, critical_stretch=1.0)
    b = IceBody.from_shape("bar", Box((0, 0, 0), (length, n * DX, n * DX)), mat, DX, 3.015 * DX)
    x = b.x0[:, 0]
    b.fix(x < 2 * DX, name="left")
    b.add_velocity_constraint(x > length - 2 * DX, name="grip",
                              path=DisplacementPath([[0, 0, 0, 0], [ramp, stretch, 0, 0]]))
    return b


def test_bar_reactions_are_EA_strain_and_equal_and_opposite():
    """A 10 x 10 particle bar, 0.4 m long, fixed at one end and pulled 10 um at the other over
    2 ms, then held 1 ms. Averaged over the hold: the fixed end's reaction is -E A eps (Hooke's
    law with the axial strain eps of the bar's middle half, where it is in uniaxial stress)
    within 5 %; the reactions of the two ends are equal and opposite within 1 %; the work of the
    grip equals the bar's kinetic plus strain energy within 1 %."""
    n, length, ramp, stretch = 10, 0.4, 2e-3, 1e-5
    b = _bar(n, length, ramp, stretch)
    x = b.x0[:, 0]
    mid = (x > 0.25 * length) & (x < 0.75 * length)
    b.start()
    dt = 0.8 * b.stable_time_step()
    left, grip, strain = [], [], []
    while b.time < ramp + 1e-3:
        b.step(dt)
        if b.time > ramp:
            r = b.reactions()
            left.append(r["left"])
            grip.append(r["grip"])
            strain.append(np.polyfit(x[mid], b.y[mid, 0] - x[mid], 1)[0])
    left, grip = np.mean(left, axis=0), np.mean(grip, axis=0)
    area = (n * DX) ** 2
    assert left[0] == pytest.approx(-E * area * np.mean(strain), rel=0.05)
    assert np.linalg.norm(left + grip) < 0.01 * abs(left[0])
    assert abs(left[1]) + abs(left[2]) < 1e-3 * abs(left[0])
    assert b.external_work == pytest.approx(b.kinetic_energy() + b.strain_energy(), rel=0.01)


def test_path_gives_its_displacement_exactly():
    """The path [[0, 0, 0, 0], [1e-3, 0, 0, 1e-5]]: the region is displaced 5e-6 m at 0.5 ms and
    1e-5 m at 1 ms (to the round-off of one position, 1e-17 m), and holds 1e-5 m after."""
    mat = IceMaterial(density=RHO, youngs_modulus=E, poisson_ratio=NU, critical_stretch=1.0)
    b = IceBody.from_shape("block", Box((0, 0, 0), (0.1, 0.04, 0.04)), mat, DX, 3.015 * DX)
    x = b.x0[:, 0]
    region = x > 0.08
    b.fix(x < 0.02)
    b.add_velocity_constraint(region, path=DisplacementPath([[0, 0, 0, 0], [1e-3, 0, 0, 1e-5]]))
    assert [c.name for c in b.constraints] == ["fixed1", "prescribed1"]
    b.start()
    dt = 1e-3 / 500
    assert dt < b.stable_time_step()
    for k in range(1, 601):
        b.step(dt)
        u = b.y[region] - b.x0[region]
        expected = 1e-5 * min(k, 500) / 500
        if k in (250, 500, 600):
            np.testing.assert_allclose(u[:, 2], expected, rtol=0, atol=1e-17)
            np.testing.assert_array_equal(u[:, :2], 0.0)


def test_energy_balance_closes_through_path_kinks():
    """A bar end pushed in and pulled back along a path with kinks (the velocity jumps at
    0.2 ms and 0.4 ms and stops at 0.6 ms): the initial kinetic energy plus the drivers' work
    equals the kinetic plus strain energy of the bar within 1 % of the largest energy, every
    step."""
    mat = IceMaterial(density=RHO, youngs_modulus=E, poisson_ratio=NU, critical_stretch=1.0)
    b = IceBody.from_shape("bar", Box((0, 0, 0), (0.2, 0.04, 0.04)), mat, DX, 3.015 * DX)
    x = b.x0[:, 0]
    b.fix(x < 0.02)
    path = DisplacementPath([[0, 0, 0, 0], [2e-4, -2e-6, 0, 0], [4e-4, 1e-6, 1e-6, 0],
                             [6e-4, 0, 0, 0]])
    b.add_velocity_constraint(x > 0.18, path=path)
    b.start()
    initial = b.kinetic_energy()  # the driven end starts at the first segment's velocity
    dt = 0.8 * b.stable_time_step()
    residual, peak = [], 0.0
    while b.time < 1e-3:
        b.step(dt)
        stored = b.kinetic_energy() + b.strain_energy()
        peak = max(peak, stored)
        residual.append(initial + b.external_work - stored)
    assert peak > 0
    assert np.abs(residual).max() < 0.01 * peak


def test_rigid_body_follows_its_path():
    """A rigid triangle translating along a path and spinning about its moving centre: its
    points are c0 + u(t) + R(w t)(X - c0) with u interpolated linearly between the path's points,
    its velocity the slope of the current segment plus w x r; a restored state gives the pose."""
    pts = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    rows = [[1e-3, 0.1, 0.0, 0.0], [3e-3, 0.1, 0.2, -0.1], [4e-3, 0.0, 0.0, 0.0]]
    w = np.array([0.0, 0.0, 5.0])
    c0 = np.array([0.2, 0.3, 0.0])
    body = RigidBody(pts, np.array([[0, 1, 2]]), angular_velocity=w, centre=c0,
                     translation=DisplacementPath(rows), orient=False)
    np.testing.assert_allclose(body.surface_points(), pts + [0.1, 0, 0], atol=1e-15)
    dt = 1e-5
    t = np.array([r[0] for r in rows])
    u = np.array([r[1:] for r in rows])
    for k in range(1, 501):
        body.step(dt)
        tk = k * dt
        uk = np.array([np.interp(tk, t, u[:, a]) for a in range(3)])
        c = c0 + uk
        expected = c + (pts - c0) @ rotation_matrix(w * tk).T
        np.testing.assert_allclose(body.surface_points(), expected, atol=1e-12)
        seg = np.searchsorted(t, tk, side="right")
        slope = np.zeros(3) if seg in (0, len(t)) else (u[seg] - u[seg - 1]) / (t[seg] - t[seg - 1])
        np.testing.assert_allclose(body.surface_velocities(),
                                   slope + np.cross(w, expected - c), atol=1e-9)
    state = body.checkpoint_state()
    again = RigidBody(pts, np.array([[0, 1, 2]]), angular_velocity=w, centre=c0,
                      translation=DisplacementPath(rows), orient=False)
    again.restore_state(state)
    np.testing.assert_array_equal(again.surface_points(), body.surface_points())


RUN = "[run]\nend_time = 1e-4\noutput_interval = 5e-5\n"
ICE = ("[[ice]]\nname = 'bar'\ndx = 0.01\n"
       "shape = { box = { min = [0, 0, 0], max = [0.1, 0.03, 0.03] } }\n")
LEFT = "{ box = { min = [0, 0, 0], max = [0.02, 0.03, 0.03] } }"
RIGHT = "{ box = { min = [0.08, 0, 0], max = [0.1, 0.03, 0.03] } }"


@pytest.mark.parametrize("text, field, fragment", [
    (f"fixed = [ {{ name = 'a b', box = {LEFT[8:-2]} }} ]\n", "ice[0].fixed[0].name", "letters"),
    (f"fixed = [ {{ name = 'a', box = {LEFT[8:-2]} }} ]\n"
     f"prescribed_velocity = [ {{ name = 'a', region = {RIGHT}, velocity = [1, 0, 0] }} ]\n",
     "ice[0].prescribed_velocity[0].name", "unique"),
    (f"fixed = [ {LEFT}, {{ name = 'fixed1', box = {RIGHT[8:-2]} }} ]\n",
     "ice[0].fixed[1].name", "used twice"),
    (f"prescribed_velocity = [ {{ region = {RIGHT}, path = [[0, 0, 0, 0], [0, 1e-6, 0, 0]] }} ]\n",
     "ice[0].prescribed_velocity[0].path", "increase strictly"),
    (f"prescribed_velocity = [ {{ region = {RIGHT}, path = [[0, 0, 0], [1, 1e-6, 0, 0]] }} ]\n",
     "ice[0].prescribed_velocity[0].path", "four finite numbers"),
    (f"prescribed_velocity = [ {{ region = {RIGHT}, path = [[-1, 0, 0, 0]] }} ]\n",
     "ice[0].prescribed_velocity[0].path", ">= 0"),
    (f"prescribed_velocity = [ {{ region = {RIGHT}, velocity = [1, 0, 0], "
     "path = [[0, 0, 0, 0]] } ]\n", "ice[0].prescribed_velocity[0].path", "not both"),
    (f"prescribed_velocity = [ {{ region = {RIGHT} }} ]\n",
     "ice[0].prescribed_velocity[0].velocity", "either velocity"),
    (f"prescribed_velocity = [ {{ region = {RIGHT}, ramp_time = 1e-4, "
     "path = [[0, 0, 0, 0]] } ]\n", "ice[0].prescribed_velocity[0].ramp_time", "velocity"),
])
def test_bad_names_and_paths_exit_2_naming_the_field(tmp_path, capsys, text, field, fragment):
    case = tmp_path / "bad.toml"
    case.write_text(RUN + ICE + text)
    assert main(["run", str(case), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "bad.toml" in err and field in err and fragment in err, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_rigid_path_with_velocity_exits_2(tmp_path, capsys):
    case = tmp_path / "bad.toml"
    case.write_text(RUN + ICE + "[[structure]]\nname = 'wall'\nkind = 'rigid'\nmesh = 'indenters'\n"
                    "motion = { velocity = [1, 0, 0], path = [[0, 0, 0, 0], [1, 1, 0, 0]] }\n")
    assert main(["run", str(case), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "structure[0].motion.path" in err and "not both" in err, err


CASE = (RUN.replace("1e-4", "3e-4").replace("5e-5", "1e-4") + "checkpoint_interval_steps = 50\n"
        + ICE + f"fixed = [ {{ name = 'left', box = {LEFT[8:-2]} }} ]\n"
        + f"prescribed_velocity = [ {{ region = {RIGHT}, "
        + "path = [[0, 0, 0, 0], [2e-4, 2e-6, 0, 0]] } ]\n")


def test_run_writes_region_reactions_and_post_shows_them(tmp_path):
    """``pdfem run``: ``/loads/bar.left/force`` and ``/loads/bar.prescribed1/force`` (N) every
    coupling step; a restart from the last checkpoint gives the same histories bit for bit;
    ``pdfem post`` reports them as reactions of ice regions with their peaks."""
    (tmp_path / "case.toml").write_text(CASE)
    case = load_case(tmp_path / "case.toml")
    ref = run_case(case, tmp_path / "ref", quiet=True)
    res = read_results(ref.results)
    left, driven = res["histories"]["loads/bar.left"], res["histories"]["loads/bar.prescribed1"]
    assert left["force"].shape == (ref.steps + 1, 3)  # t = 0 and every coupling step
    np.testing.assert_array_equal(left["time"], driven["time"])
    with h5py.File(ref.results, "r") as f:
        assert f["loads/bar.left/force"].attrs.get("unit", "N") == "N"
    assert np.abs(left["force"][:, 0]).max() > 0
    summary = summarize(res)
    assert set(summary["regions"]) == {"bar.left", "bar.prescribed1"}
    assert summary["loads"] == {}
    peak = np.linalg.norm(left["force"], axis=1).max()
    got = summary["regions"]["bar.left"]["magnitude"]
    assert got["per_step_peak"] == pytest.approx(peak, rel=1e-12)
    assert 0.0 < got["peak"] <= peak                  # averaged over 0.1 ms: at most the raw
    assert "Reaction of ice region (force on the ice) 'bar.left'" in format_summary(summary)
    again = tmp_path / "again"
    shutil.copytree(tmp_path / "ref", again)
    run_case(case, again, quiet=True, restart=again / "checkpoint.h5")
    got = read_results(again / "results.h5")["histories"]
    for g in ("loads/bar.left", "loads/bar.prescribed1", "energy"):
        for k, v in res["histories"][g].items():
            np.testing.assert_array_equal(v, got[g][k], err_msg=f"{g}/{k}")


MPI_SCRIPT = textwrap.dedent('''
    import numpy as np
    from pdfem.geometry.path import DisplacementPath
    from pdfem.geometry.shapes import Box
    from pdfem.parallel.comm import world
    from pdfem.parallel.partition import choose_partition
    from pdfem.pd.body import IceBody
    from pdfem.pd.layout.split import split_body
    from pdfem.pd.materials.lps import IceMaterial

    def build():
        mat = IceMaterial(density=900.0, youngs_modulus=4.1e9, poisson_ratio=0.3,
                          critical_stretch=1.0)
        dx = 0.01
        b = IceBody.from_shape("bar", Box((0, 0, 0), (0.2, 0.04, 0.04)), mat, dx, 3.015 * dx)
        b.fix(b.x0[:, 2] < dx, name="bottom")  # both regions span the split along x
        b.add_velocity_constraint(b.x0[:, 2] > 3 * dx, name="top",
                                  path=DisplacementPath([[0, 0, 0, 0], [1e-4, 2e-6, 1e-6, 0]]))
        return b

    comm = world()
    ref = build()
    dt = 0.8 * ref.stable_time_step()
    owner, _ = choose_partition(ref.x0, ref.row_ptr, ref.nbr, comm.size)
    dist = split_body(build(), owner, comm)
    ref.start()
    dist.start()
    err, scale = 0.0, 0.0
    for _ in range(150):
        ref.step(dt)
        dist.step(dt)
        a, b = ref.reactions(), dist.reactions()
        for k in a:
            err = max(err, float(np.abs(a[k] - b[k]).max()))
            scale = max(scale, float(np.abs(a[k]).max()))
    work = abs(dist.external_work - ref.external_work) / abs(ref.external_work)
    if comm.rank == 0:
        print(f"RESULT size={comm.size} err={err / scale:.3e} scale={scale:.3e} work={work:.3e}")
''')


def test_reactions_on_two_ranks_agree_with_one(tmp_path):
    """Reaction histories of a bar split over 2 ranks (along its length; its bottom layer fixed,
    its top layer sheared along a path, so both regions span the ranks) equal the serial ones to
    round-off (1e-10 of the largest), and so does the drivers' work."""
    script = tmp_path / "regions_mpi.py"
    script.write_text(MPI_SCRIPT)
    r = run_script(script, 2, timeout=300)
    line = next(s for s in r.stdout.splitlines() if s.startswith("RESULT"))
    values = dict(kv.split("=") for kv in line.split()[1:])
    assert values["size"] == "2" and float(values["scale"]) > 1.0
    assert float(values["err"]) < 1e-10
    assert float(values["work"]) < 1e-10


WALL_CASE = """
[run]
end_time = 3.0e-4
output_interval = 1.0e-4
[[ice]]
name = "bar"
dx = 0.005
shape = {{ box = {{ min = [0.0, 0.0, -0.002499], max = [0.02, 0.02, 0.1] }} }}
material = {{ critical_stretch = 1.0 }}
[[structure]]
name = "wall"
kind = "rigid"
mesh = "{box}"
motion = {{ path = [[0, 0, 0, 0], [1e-4, 0, 0, 1e-4], [2e-4, 0, 0, 5e-5]] }}
[structure.params]
surface_only = true
origin_x = -0.05
origin_y = -0.05
origin_z = -0.02
length_x = 0.12
length_y = 0.12
length_z = 0.02
element_size = 0.02
"""


def test_rigid_wall_on_a_path_pushes_the_ice_and_the_energy_balance_closes(tmp_path):
    """A rigid wall (the top face of models/validation/box.py) rises 0.1 mm into an ice bar
    resting on it at 1 m/s, backs off 0.05 mm and stops: at every frame its displacement is the
    path's, interpolated linearly; it pushes the ice (load > 0) and the energy balance closes
    within 0.5 % of the work it did (the velocity jumps at the path's points are booked as
    the displacement over each step)."""
    box = Path(__file__).resolve().parents[2] / "models" / "validation" / "box.py"
    (tmp_path / "case.toml").write_text(WALL_CASE.format(box=box))
    summary = run_case(load_case(tmp_path / "case.toml"), tmp_path / "o", quiet=True)
    res = read_results(summary.results)
    t = res["time"]
    expected = np.interp(t, [0, 1e-4, 2e-4], [0, 1e-4, 5e-5])
    np.testing.assert_allclose(res["structure"]["wall"]["u"][:, :, 2],
                               np.repeat(expected[:, None], res["structure"]["wall"]["u"].shape[1],
                                         axis=1), rtol=0, atol=1e-15)
    assert res["histories"]["loads/wall"]["force"][:, 2].min() < -100.0  # pushes the ice up
    e = res["histories"]["energy"]
    assert e["rigid_body_work"][-1] > 0
    assert np.abs(e["residual"]).max() < 5e-3 * e["rigid_body_work"][-1]
