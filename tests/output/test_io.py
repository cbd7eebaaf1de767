"""Tests of the results file (pdfem.output): HDF5 layout, histories, XDMF, and a killed writer.

References: the arrays handed to the writer (an HDF5 round trip must be exact), h5py reading
the file directly, and a small XDMF reader of the tests (tests/support/xdmf.py: the standard
library's XML parser and h5py). ParaView's own readers are tests/output/test_paraview.py's.
"""

from __future__ import annotations

import datetime
import os
import shutil
import signal
import subprocess
import sys
import textwrap
import time
import xml.etree.ElementTree as ET

import h5py
import meshio
import numpy as np
import pytest

import pdfem
from pdfem.output import ResultsWriter, read_results
from pdfem.output.frames import VIEW_BATCH
from pdfem.output.histories import HISTORY_BLOCK

from support.xdmf import read_xdmf


def _frame(rng: np.random.Generator, n: int, extra: bool = False) -> dict[str, np.ndarray]:
    fields = {"u": rng.standard_normal((n, 3)), "v": rng.standard_normal((n, 3)),
              "damage": rng.random(n)}
    if extra:
        fields["theta"] = rng.standard_normal(n)
    return fields


def _write_two_bodies(path, n_frames: int = 4):
    """Write a file with two ice bodies; return what was written, for comparison."""
    rng = np.random.default_rng(42)
    bodies = {"sheet": (rng.random((50, 3)), rng.random(50) * 1e-3),
              "floe": (rng.random((7, 3)), None)}
    times = 1e-3 * np.arange(1, n_frames + 1) + 1e-9 * rng.random(n_frames)
    frames = []
    case = '[run]\nend_time = 0.05\n'
    with ResultsWriter(path, case_text=case, meta={"ranks": 2, "title": "t"}) as w:
        for name, (x0, vol) in bodies.items():
            w.add_ice_body(name, x0, volume=vol)
        for t in times:
            fr = {"sheet": _frame(rng, 50, extra=True), "floe": _frame(rng, 7)}
            frames.append(fr)
            assert w.write_frame(t, fr) == len(frames) - 1
    return bodies, times, frames


def test_round_trip_exact_and_meta(tmp_path):
    """Reference: the arrays written; frames read back (read_results, raw h5py) are identical."""
    path = tmp_path / "run.h5"
    bodies, times, frames = _write_two_bodies(path)
    r = read_results(path)
    np.testing.assert_array_equal(r["time"], times)
    for name, (x0, vol) in bodies.items():
        b = r["ice"][name]
        np.testing.assert_array_equal(b["x0"], x0)
        if vol is None:
            assert "volume" not in b
        else:
            np.testing.assert_array_equal(b["volume"], vol)
        for field in frames[0][name]:
            np.testing.assert_array_equal(b[field], np.stack([fr[name][field] for fr in frames]))
    assert set(r["ice"]["floe"]) == {"x0", "u", "v", "damage", "x"}
    for name, (x0, _) in bodies.items():  # the positions the writer records: x0 + u
        np.testing.assert_array_equal(r["ice"][name]["x"], x0 + r["ice"][name]["u"])
    meta = r["meta"]
    assert meta["units"] == "SI"
    assert meta["version"] == pdfem.__version__
    assert meta["case"] == '[run]\nend_time = 0.05\n'
    assert meta["ranks"] == 2 and meta["title"] == "t"
    assert datetime.datetime.fromisoformat(meta["created"]).tzinfo is not None
    with h5py.File(path, "r") as f:  # documented layout: float64, 64 small frames a chunk,
        u = f["ice/sheet/u"]        # resizable
        assert u.dtype == np.float64 and u.shape == (4, 50, 3)
        assert u.chunks == (64, 50, 3) and u.maxshape == (None, 50, 3)
        assert f["ice/sheet/damage"].shape == (4, 50) and f["ice/sheet/theta"].chunks == (64, 50)
        np.testing.assert_array_equal(f["ice/floe/v"][2], frames[2]["floe"]["v"])


def test_extra_field_and_field_set_errors(tmp_path):
    """The field set is fixed by the first frame; rejected frames leave the file unchanged."""
    rng = np.random.default_rng(0)
    x0 = rng.random((5, 3))
    path = tmp_path / "r.h5"
    with ResultsWriter(path) as w:
        w.add_ice_body("b", x0)
        with pytest.raises(ValueError, match="required"):
            w.write_frame(0.0, {"b": {"u": np.zeros((5, 3)), "v": np.zeros((5, 3))}})
        first = _frame(rng, 5)
        first["theta"] = rng.random(5)
        first["omega"] = rng.random((5, 3))
        w.write_frame(0.0, {"b": first})
        missing = {k: v for k, v in _frame(rng, 5).items()}
        missing["omega"] = rng.random((5, 3))  # theta missing
        with pytest.raises(ValueError, match="missing \\['theta'\\]"):
            w.write_frame(1.0, {"b": missing})
        with pytest.raises(ValueError, match="unexpected \\['psi'\\]"):
            w.write_frame(1.0, {"b": dict(first, psi=np.zeros(5))})
        with pytest.raises(ValueError, match="shape"):
            w.write_frame(1.0, {"b": dict(first, theta=np.zeros(4))})
        with pytest.raises(ValueError, match="greater than the previous"):
            w.write_frame(0.0, {"b": first})
        with pytest.raises(ValueError, match="every registered body"):
            w.write_frame(1.0, {"c": first})
        with pytest.raises(ValueError, match="after the first frame"):
            w.add_ice_body("late", x0)
        with pytest.raises(ValueError, match="'x' is recorded by the writer"):
            w.write_frame(1.0, {"b": dict(first, x=x0)})
        assert w.write_frame(1.0, {"b": first}) == 1
    with pytest.raises(ValueError, match="closed"):
        w.write_frame(2.0, {"b": first})
    r = read_results(path)
    np.testing.assert_array_equal(r["time"], [0.0, 1.0])
    np.testing.assert_array_equal(r["ice"]["b"]["theta"], np.stack([first["theta"]] * 2))
    np.testing.assert_array_equal(r["ice"]["b"]["omega"], np.stack([first["omega"]] * 2))
    assert r["ice"]["b"]["omega"].shape == (2, 5, 3)


def test_bad_shapes_and_names(tmp_path):
    """Input validation: (N, 3) reference positions, (N,) volumes, plain names."""
    with ResultsWriter(tmp_path / "r.h5") as w:
        with pytest.raises(ValueError, match="expected \\(N, 3\\)"):
            w.add_ice_body("a", np.zeros((4, 2)))
        with pytest.raises(ValueError, match="volume"):
            w.add_ice_body("a", np.zeros((4, 3)), volume=np.zeros(3))
        with pytest.raises(ValueError, match="not a valid name"):
            w.add_ice_body("a/b", np.zeros((4, 3)))
        with pytest.raises(ValueError, match="collide"):
            w.append_history("ice", 0.0, {"x": 1.0})
        w.add_ice_body("a", np.zeros((4, 3)))
        with pytest.raises(ValueError, match="already registered"):
            w.add_ice_body("a", np.zeros((4, 3)))
        w.append_history("loads/panel", 0.0, {"force": np.zeros(3)})
        with pytest.raises(ValueError, match="nest"):
            w.append_history("loads/panel/x", 0.0, {"y": 1.0})
        with pytest.raises(ValueError, match="nest"):
            w.append_history("loads", 0.0, {"y": 1.0})
    with pytest.raises(ValueError, match="HDF5 file"):
        ResultsWriter(tmp_path / "r.xdmf")
    with pytest.raises(TypeError, match="meta item 'bad'"):
        ResultsWriter(tmp_path / "m.h5", meta={"bad": {"a": 1}})


def test_histories_buffered_blocks(tmp_path):
    """Reference: the rows appended (exact); rows reach the file in blocks of HISTORY_BLOCK,
    and all of them after close; (K, 3) force and moment."""
    path = tmp_path / "h.h5"
    k_rows = 2 * HISTORY_BLOCK + 300
    t = np.arange(k_rows) * 1e-6
    force = np.stack([np.sin(t * 1e4), np.cos(t * 1e4), t], axis=1)
    with ResultsWriter(path) as w:
        for i in range(k_rows):
            w.append_history("energy", t[i], {"kinetic": 0.5 * i, "strain": float(i * i),
                                              "external_work": -1.0 * i, "dissipated": 1e-3 * i})
            w.append_history("loads/panel", t[i], {"force": force[i], "moment": 2.0 * force[i]})
            if i == HISTORY_BLOCK + 9:
                # same process: h5py sees the writer's state; only full blocks are written yet
                assert w._file["energy/time"].shape == (HISTORY_BLOCK,)
                assert w._file["loads/panel/force"].shape == (HISTORY_BLOCK, 3)
        w.flush()
        assert w._file["energy/kinetic"].shape == (k_rows,)
        assert w._file["loads/panel/force"].chunks == (HISTORY_BLOCK, 3)
        with pytest.raises(ValueError, match="keys are fixed"):
            w.append_history("energy", 1.0, {"kinetic": 1.0})
        with pytest.raises(ValueError, match="shape"):
            w.append_history("loads/panel", 1.0, {"force": 1.0, "moment": force[0]})
        for i in range(5):  # a tail written by close()
            w.append_history("monitors/mid", float(i), {"u": [i, 0.0, 0.0]})
    h = read_results(path)["histories"]
    assert set(h) == {"energy", "loads/panel", "monitors/mid"}
    np.testing.assert_array_equal(h["energy"]["time"], t)
    np.testing.assert_array_equal(h["energy"]["kinetic"], 0.5 * np.arange(k_rows))
    np.testing.assert_array_equal(h["energy"]["strain"], np.arange(k_rows, dtype=float) ** 2)
    assert h["loads/panel"]["force"].shape == (k_rows, 3)
    np.testing.assert_array_equal(h["loads/panel"]["force"], force)
    np.testing.assert_array_equal(h["loads/panel"]["moment"], 2.0 * force)
    np.testing.assert_array_equal(h["monitors/mid"]["u"][:, 0], np.arange(5.0))


def test_reader_drops_uncommitted_rows(tmp_path):
    """A run killed inside write_frame can leave datasets extended past the last committed time
    row (time rows read NaN where unwritten). Simulated here by extending the datasets by hand:
    read_results must return exactly the committed frames and history rows."""
    rng = np.random.default_rng(7)
    path = tmp_path / "cut.h5"
    written = [_frame(rng, 4) for _ in range(3)]
    with ResultsWriter(path) as w:
        w.add_ice_body("b", rng.random((4, 3)))
        for k, fr in enumerate(written):
            w.write_frame(float(k), {"b": fr})
            w.append_history("energy", float(k), {"kinetic": 10.0 * k})
    with h5py.File(path, "a") as f:
        for name in ("u", "v", "damage"):
            f[f"ice/b/{name}"].resize(5, axis=0)  # data of frames 3, 4 "on disk"
        f["time"].resize(5, axis=0)  # their time rows never written: NaN fill
        f["energy/kinetic"].resize(6, axis=0)
        f["energy/time"].resize(6, axis=0)
    assert np.isnan(h5py.File(path, "r")["time"][4])
    r = read_results(path)
    np.testing.assert_array_equal(r["time"], [0.0, 1.0, 2.0])
    assert r["ice"]["b"]["u"].shape == (3, 4, 3)
    np.testing.assert_array_equal(r["ice"]["b"]["damage"],
                                  np.stack([fr["damage"] for fr in written]))
    np.testing.assert_array_equal(r["histories"]["energy"]["kinetic"], [0.0, 10.0, 20.0])
    np.testing.assert_array_equal(r["histories"]["energy"]["time"], [0.0, 1.0, 2.0])


def _check_data_items(xdmf_path) -> int:
    """Every HDF DataItem of the XDMF names an existing dataset of the declared shape."""
    root = ET.parse(xdmf_path).getroot()
    count = 0
    with h5py.File(xdmf_path.with_suffix(".h5"), "r") as f:
        for item in root.iter("DataItem"):
            assert item.get("Format") == "HDF"
            fname, h5path = item.text.strip().split(":")
            assert fname == xdmf_path.with_suffix(".h5").name  # relative to the .xdmf
            dims = tuple(int(d) for d in item.get("Dimensions").split())
            assert f[h5path].shape == dims
            count += 1
    return count


def test_xdmf_frames_show_each_body_where_it_is(tmp_path):
    """Reference: the arrays written, read back through the XDMF file (tests/support/xdmf.py),
    also after the pair is moved to another directory (the .h5 is named relative to the .xdmf):
    one temporal collection per body, each frame a spatial collection holding the body's grid,
    drawn at x0 + u, with every field of the file (NaN where the body has none: ``volume``
    and ``theta`` on the floe, stored in a dataset that holds no data). meshio's
    ``TimeSeriesReader`` does not read this layout (docs/post.md says so)."""
    path = tmp_path / "a" / "run.h5"
    path.parent.mkdir()
    bodies, times, frames = _write_two_bodies(path, n_frames=3)
    xdmf = path.with_suffix(".xdmf")
    root = ET.parse(xdmf).getroot()
    assert root.tag == "Xdmf" and root.get("Version") == "3.0"
    collections = root.find("Domain").findall("Grid")
    assert [c.get("Name") for c in collections] == ["ice/sheet", "ice/floe"]
    assert all(c.get("CollectionType") == "Temporal" and len(c) == 3 for c in collections)
    spatial = collections[0].findall("Grid")
    assert {g.get("CollectionType") for g in spatial} == {"Spatial"}
    assert all(g.get("Name") is None for g in spatial)  # unnamed: see pdfem.output.xdmf_grids
    # each grid: topology, geometry, volume, u, v, damage, theta (the floe's last two NaN)
    assert _check_data_items(xdmf) == 3 * 7 + 3 * 7
    with h5py.File(path, "r") as f:
        assert f["xdmf/missing/7"].id.get_storage_size() == 0
    moved = tmp_path / "b"
    moved.mkdir()
    for p in (path, xdmf):
        shutil.move(p, moved / p.name)
    seen = read_xdmf(moved / "run.xdmf")
    for name, (x0, vol) in bodies.items():
        assert [f.time for f in seen[f"ice/{name}"]] == list(times)
        for k, frame in enumerate(seen[f"ice/{name}"]):
            (grid_name, grid), = frame.grids.items()
            assert grid_name == f"ice/{name}" and grid.topology == "Polyvertex"
            np.testing.assert_array_equal(grid.points, x0 + frames[k][name]["u"])
            for field, a in frames[k][name].items():
                np.testing.assert_array_equal(grid.point_data[field], a)
    floe = seen["ice/floe"][-1].grids["ice/floe"]
    assert set(floe.point_data) == {"volume", "u", "v", "damage", "theta"}
    assert np.isnan(floe.point_data["volume"]).all() and np.isnan(floe.point_data["theta"]).all()
    with pytest.raises(meshio.ReadError, match="mesh grid"):
        meshio.xdmf.TimeSeriesReader(moved / "run.xdmf")


def test_xdmf_single_body_values(tmp_path):
    """Reference: every frame of a one-body file read through the XDMF file equals the arrays
    written; more frames than one batch of views (VIEW_BATCH), and no unused view left after
    close."""
    rng = np.random.default_rng(3)
    x0 = rng.random((20, 3))
    path = tmp_path / "one.h5"
    n_frames = VIEW_BATCH + 6
    written = []
    with ResultsWriter(path) as w:
        w.add_ice_body("sheet", x0, volume=np.full(20, 2e-4))
        for k in range(n_frames):
            written.append(_frame(rng, 20, extra=True))
            w.write_frame(0.01 * k, {"sheet": written[-1]})
    seen = read_xdmf(path.with_suffix(".xdmf"))["ice/sheet"]
    assert len(seen) == n_frames
    for k, frame in enumerate(seen):
        assert frame.time == 0.01 * k
        grid = frame.grids["ice/sheet"]
        np.testing.assert_array_equal(grid.points, x0 + written[k]["u"])
        for name, a in written[k].items():
            np.testing.assert_array_equal(grid.point_data[name], a)
        np.testing.assert_array_equal(grid.point_data["volume"], np.full(20, 2e-4))
    with h5py.File(path, "r") as f:
        for name in ("u", "v", "damage", "theta", "x"):
            assert len(f[f"xdmf/ice/sheet/{name}"]) == n_frames


def test_file_being_written_elsewhere(tmp_path):
    """Another process may not start a second writer on a file being written (HDF5 would
    truncate it before noticing the lock), but read_results can read it meanwhile."""
    path = tmp_path / "busy.h5"
    rng = np.random.default_rng(5)
    x0 = rng.random((6, 3))
    written = [_frame(rng, 6) for _ in range(3)]
    code = textwrap.dedent(f"""
        from pdfem.output import ResultsWriter, read_results
        try:
            ResultsWriter({str(path)!r})
        except FileExistsError:
            print("refused")
        r = read_results({str(path)!r})
        print(len(r["time"]), r["ice"]["b"]["u"][1, 2, 0].hex())
    """)
    with ResultsWriter(path) as w:
        w.add_ice_body("b", x0)
        w.write_frame(0.0, {"b": written[0]})
        w.write_frame(0.5, {"b": written[1]})
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             timeout=120)
        assert out.returncode == 0, out.stderr
        assert out.stdout.split() == ["refused", "2", written[1]["u"][2, 0].hex()]
        w.write_frame(1.0, {"b": written[2]})
    r = read_results(path)
    np.testing.assert_array_equal(r["time"], [0.0, 0.5, 1.0])
    np.testing.assert_array_equal(r["ice"]["b"]["u"], np.stack([fr["u"] for fr in written]))


_KILLED_WRITER = textwrap.dedent("""
    import sys, time
    import numpy as np
    from pdfem.output import ResultsWriter
    n = 300
    x0 = np.arange(3.0 * n).reshape(n, 3)
    w = ResultsWriter(sys.argv[1], case_text="killed", meta={"ranks": 1})
    w.add_ice_body("sheet", x0)
    for k in range(100000):
        for s in range(20):
            w.append_history("loads/p", k + s / 20, {"force": [20.0 * k + s, 0.0, 1.0]})
        w.write_frame(1e-3 * (k + 1), {"sheet": {"u": x0 + k, "v": -x0 * k,
                                                 "damage": np.full(n, k / 1e3)}})
        print(k, flush=True)
        time.sleep(0.03)
""")


def test_killed_writer_leaves_readable_file(tmp_path):
    """A writer killed with SIGKILL mid-run leaves an HDF5 file that h5py opens, holding frames
    0..k each complete (reference: the closed-form values the child wrote), and an XDMF file
    that parses and reads (every data item) up to a frame present in the HDF5 file."""
    script = tmp_path / "child.py"
    script.write_text(_KILLED_WRITER)
    path = tmp_path / "killed.h5"
    proc = subprocess.Popen([sys.executable, str(script), str(path)], stdout=subprocess.PIPE,
                            text=True)
    try:
        deadline = time.monotonic() + 60.0
        last = -1
        while last < 4 and time.monotonic() < deadline:
            line = proc.stdout.readline()
            if not line:
                break
            last = int(line)
        assert last >= 4, "the child writer did not produce frames"
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        proc.kill()
        proc.wait(timeout=30)
        proc.stdout.close()
    assert proc.returncode == -signal.SIGKILL
    with h5py.File(path, "r") as f:
        n_frames = f["time"].shape[0]
        assert n_frames >= last + 1
        assert f["ice/sheet/u"].shape[0] >= n_frames
    r = read_results(path)
    n = len(r["time"])
    assert n >= last + 1
    x0 = r["ice"]["sheet"]["x0"]
    for k in range(n):
        assert r["time"][k] == 1e-3 * (k + 1)
        np.testing.assert_array_equal(r["ice"]["sheet"]["u"][k], x0 + k)
        np.testing.assert_array_equal(r["ice"]["sheet"]["v"][k], -x0 * k)
        np.testing.assert_array_equal(r["ice"]["sheet"]["damage"][k], np.full(len(x0), k / 1e3))
    force = r["histories"]["loads/p"]["force"]
    assert len(force) >= 20 * n  # a committed frame implies the rows appended before it
    np.testing.assert_array_equal(force[:, 0], np.arange(len(force), dtype=float))
    seen = read_xdmf(path.with_suffix(".xdmf"))["ice/sheet"]
    steps = len(seen)
    assert last + 1 <= steps <= n
    assert seen[-1].time == 1e-3 * steps
    np.testing.assert_array_equal(seen[-1].grids["ice/sheet"].point_data["u"], x0 + steps - 1)
    np.testing.assert_array_equal(seen[-1].grids["ice/sheet"].points, 2 * x0 + steps - 1)


@pytest.mark.parametrize("cell_type, cells, topology", [
    ("tetra", [[0, 1, 2, 3], [1, 2, 3, 4]], "Tetrahedron"),
    ("hexahedron", [[0, 1, 2, 3, 4, 5, 6, 7]], "Hexahedron"),
    ("triangle", [[0, 1, 2], [1, 2, 3], [2, 3, 4]], "Triangle"),
])
def test_structure_frames_round_trip_and_xdmf(tmp_path, cell_type, cells, topology):
    """A structure's mesh, nodal displacement and element von Mises stress: read_results
    returns exactly what was written, and the XDMF file (read with tests/support/xdmf.py)
    shows the same mesh (XDMF topology type, connectivity) drawn at points + u, the nodal ``u``
    as point data and ``von_mises`` as cell data; the ice shows ``von_mises`` as NaN on its
    particles (one Polyvertex cell each) and the structure ``damage`` and ``v`` as NaN."""
    rng = np.random.default_rng(11)
    cells = np.array(cells)
    nn, ne = int(cells.max()) + 1, len(cells)
    points = rng.random((nn, 3))
    path = tmp_path / "s.h5"
    written = []
    with ResultsWriter(path) as w:
        w.add_ice_body("floe", rng.random((6, 3)))
        w.add_structure("panel", points, cells, cell_type)
        for k in range(3):
            st = {"u": rng.standard_normal((nn, 3)), "von_mises": rng.random(ne) * 1e8}
            written.append(st)
            w.write_frame(1e-3 * k, {"floe": _frame(rng, 6)}, structures={"panel": st})
    r = read_results(path)
    s = r["structure"]["panel"]
    np.testing.assert_array_equal(s["points"], points)
    np.testing.assert_array_equal(s["cells"], cells)
    assert s["cell_type"] == cell_type
    np.testing.assert_array_equal(s["u"], np.stack([f["u"] for f in written]))
    np.testing.assert_array_equal(s["von_mises"], np.stack([f["von_mises"] for f in written]))
    np.testing.assert_array_equal(s["x"], points + s["u"])
    seen = read_xdmf(path.with_suffix(".xdmf"))
    assert list(seen) == ["ice/floe", "structure/panel"]
    for k, frame in enumerate(seen["structure/panel"]):
        assert frame.time == 1e-3 * k
        grid = frame.grids["structure/panel"]
        assert grid.topology == topology
        np.testing.assert_array_equal(grid.cells, cells)
        np.testing.assert_array_equal(grid.points, points + written[k]["u"])
        np.testing.assert_array_equal(grid.point_data["u"], written[k]["u"])
        np.testing.assert_array_equal(grid.cell_data["von_mises"], written[k]["von_mises"])
        assert np.isnan(grid.point_data["damage"]).all() and grid.point_data["v"].shape == (nn, 3)
        floe = seen["ice/floe"][k].grids["ice/floe"]
        assert floe.cell_data["von_mises"].shape == (6,)
        assert np.isnan(floe.cell_data["von_mises"]).all()


def test_structure_input_errors(tmp_path):
    """Bad meshes and frames are refused with the structure and the expected shape named."""
    with ResultsWriter(tmp_path / "e.h5") as w:
        with pytest.raises(ValueError, match="cell_type 'prism'"):
            w.add_structure("a", np.zeros((6, 3)), [[0, 1, 2, 3, 4, 5]], "prism")
        with pytest.raises(ValueError, match=r"expected \(Ne, 4\)"):
            w.add_structure("a", np.zeros((4, 3)), [[0, 1, 2]], "tetra")
        with pytest.raises(ValueError, match="outside 0..3"):
            w.add_structure("a", np.zeros((4, 3)), [[0, 1, 2, 4]], "tetra")
        w.add_structure("a", np.zeros((4, 3)), [[0, 1, 2, 3]], "tetra")
        with pytest.raises(ValueError, match="already registered"):
            w.add_structure("a", np.zeros((4, 3)), [[0, 1, 2, 3]], "tetra")
        with pytest.raises(ValueError, match="every registered body"):
            w.write_frame(0.0, {})
        with pytest.raises(ValueError, match="one per cell"):
            w.write_frame(0.0, {}, structures={"a": {"u": np.zeros((4, 3)),
                                                     "von_mises": np.zeros(4)}})
        with pytest.raises(ValueError, match="required fields"):
            w.write_frame(0.0, {}, structures={"a": {"von_mises": np.zeros(1)}})
        w.write_frame(0.0, {}, structures={"a": {"u": np.ones((4, 3))}})
    assert read_results(tmp_path / "e.h5")["structure"]["a"]["u"].shape == (1, 4, 3)
