"""Per-rank checkpoints: a 3-rank checkpoint restarts on 3, 2 and 1 ranks; a crash between the
part files and the manifest leaves the previous checkpoint usable.

Reference: the uninterrupted 3-rank run of the same case (the seed's rigid cylinder breaking an
ice plate, as in tests/run/test_mpi_run.py, here floating in water with drag and added mass, whose
per-particle counters the checkpoint carries; checkpoints every 60 of its 121 steps). One
``mpiexec -n 3`` launch runs it, then the same case again with the checkpoint hook
(:func:`pdfem.run.checkpoint.before_manifest`) raising at step 120, once every rank's part file
of that generation is on disk and before rank 0 writes the manifest, as a crash mid-write would.
That run's directory, copied three times, is restarted from its step-60 checkpoint on all 3
ranks (every frame and history equal to the reference bit for bit), and at the same time on 2
ranks (ranks 0-1) and on 1 rank (rank 2), which agree with it to round-off: ice displacements
to 1e-10 of their largest, identical damage, the water's drag loss to 1e-10. The same launch
pulls an ice-only bar apart on 3 ranks (the distributed set-up, which has no global bond
numbers) and restarts it from its step-110 checkpoint on 2 and on 1 rank: displacements to
1e-10, identical damage. One numba thread per process (the pair loops'
chunks then do not depend on the machine). The format checks run without MPI.
"""

from __future__ import annotations

import os
import textwrap
from pathlib import Path

import h5py
import numpy as np
import pytest

from pdfem.errors import InputError
from pdfem.output import read_results
from pdfem.run.checkpoint import CHECKPOINT_NAME, case_hash, read_checkpoint

from support.cases import CYLINDER_BODIES
from support.mpi import run_script

CASE = """
[run]
end_time = 6.0e-4
output_interval = 2.0e-4
checkpoint_interval_steps = 60
checkpoint_interval_minutes = 0
[water]
level = 0.0351
linear_drag = 2.0
drag_coefficient = 1.0
added_mass = 0.5
""" + CYLINDER_BODIES

BAR = """
[run]
end_time = 3.0e-4
output_interval = 1.0e-4
checkpoint_interval_steps = 110
checkpoint_interval_minutes = 0
[[ice]]
name = "bar"
dx = 0.005
shape = { box = { min = [0.0, 0.0, 0.0], max = [0.12, 0.04, 0.03] } }
material = { density = 900.0, youngs_modulus = 4.0e9, poisson_ratio = 0.3, fracture_energy = 1.0 }
prescribed_velocity = [
  { region = { box = { min = [-0.01, -0.01, -0.01], max = [0.01, 0.05, 0.04] } }, velocity = [-2.0, 0.0, 0.0], ramp_time = 2.0e-5 },
  { region = { box = { min = [0.11, -0.01, -0.01], max = [0.13, 0.05, 0.04] } }, velocity = [2.0, 0.0, 0.0], ramp_time = 2.0e-5 } ]
"""

SCRIPT = textwrap.dedent('''
    import shutil, sys
    from pathlib import Path
    from mpi4py import MPI
    from pdfem.case.schema import load_case
    from pdfem.parallel.comm import MPIComm, SerialComm, world
    from pdfem.run import checkpoint
    from pdfem.run.driver import run_case

    d = Path(sys.argv[1])
    case = load_case(d / "case.toml")
    comm = world()
    run_case(case, d / "ref", quiet=True, comm=comm)

    class Crash(Exception):
        pass

    def crash(generation):
        if generation == 120:
            raise Crash()

    checkpoint.before_manifest = crash
    try:
        run_case(case, d / "killed", quiet=True, comm=comm)
    except Crash:
        pass
    checkpoint.before_manifest = lambda generation: None
    if comm.rank == 0:
        print("LEFT", sorted(p.name for p in (d / "killed").glob("checkpoint*")))
        for n in (3, 2, 1):
            shutil.copytree(d / "killed", d / f"k{n}")
    comm.bcast(0)
    ckpt = lambda k: d / f"k{k}" / "checkpoint.h5"
    run_case(case, d / "k3", quiet=True, comm=comm, restart=ckpt(3))
    sub = MPI.COMM_WORLD.Split(0 if comm.rank < 2 else 1, comm.rank)
    k = 2 if comm.rank < 2 else 1
    run_case(case, d / f"k{k}", quiet=True, comm=MPIComm(sub) if k == 2 else SerialComm(),
             restart=ckpt(k))
    comm.bcast(0)
    # the ice-only bar: the distributed set-up (no global bond numbers anywhere)
    bar = load_case(d / "bar.toml")
    run_case(bar, d / "bar3", quiet=True, comm=comm)
    if comm.rank == 0:
        for n in (2, 1):
            shutil.copytree(d / "bar3", d / f"bar{n}")
    comm.bcast(0)
    run_case(bar, d / f"bar{k}", quiet=True, comm=MPIComm(sub) if k == 2 else SerialComm(),
             restart=d / f"bar{k}" / "checkpoint.h5")
    comm.bcast(0)
    if comm.rank == 0:
        for k in (3, 2, 1):
            print(f"AFTER{k}", sorted(p.name for p in (d / f"k{k}").glob("checkpoint*")))
''')


@pytest.mark.slow
def test_three_rank_checkpoint_restarts_on_three_two_and_one_rank(tmp_path):
    (tmp_path / "case.toml").write_text(CASE)
    (tmp_path / "script.py").write_text(SCRIPT)
    (tmp_path / "bar.toml").write_text(BAR)
    env = dict(os.environ, NUMBA_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    r = run_script(tmp_path / "script.py", 3, str(tmp_path), timeout=300, env=env)
    lines = dict(line.split(" ", 1) for line in r.stdout.splitlines() if " " in line)
    # the crash left the step-60 manifest with its parts and the unnamed step-120 parts
    assert lines["LEFT"] == str(sorted([f"checkpoint.g{g}.rank{r}.h5" for g in (60, 120)
                                        for r in range(3)] + ["checkpoint.h5"]))
    with h5py.File(tmp_path / "killed" / CHECKPOINT_NAME, "r") as f:
        assert int(f["driver"].attrs["step"]) == 60 and int(f.attrs["parts"]) == 3
    # each restart's step-120 checkpoint replaced the older generation (one part per rank)
    assert lines["AFTER3"] == str([f"checkpoint.g120.rank{r}.h5" for r in range(3)]
                                  + ["checkpoint.h5"])
    assert lines["AFTER2"] == str([f"checkpoint.g120.rank{r}.h5" for r in range(2)]
                                  + ["checkpoint.h5"])
    assert lines["AFTER1"] == str(["checkpoint.g120.rank0.h5", "checkpoint.h5"])
    ref = read_results(tmp_path / "ref" / "results.h5")
    u = ref["ice"]["plate"]["u"]
    assert ref["ice"]["plate"]["damage"][-1].max() > 0  # bonds broke: broken flags matter
    assert ref["histories"]["energy"]["water_drag_dissipated"][-1] > 0  # water state matters
    assert len(ref["time"]) == 4  # frames at 0, 0.2, 0.4, 0.6 ms: two after the restart
    same = read_results(tmp_path / "k3" / "results.h5")
    np.testing.assert_array_equal(same["time"], ref["time"])
    for k in ("u", "v", "damage"):
        np.testing.assert_array_equal(same["ice"]["plate"][k], ref["ice"]["plate"][k])
    for g, rows in ref["histories"].items():
        for k, v in rows.items():
            np.testing.assert_array_equal(same["histories"][g][k], v, err_msg=f"{g}/{k}")
    for ranks in (2, 1):
        got = read_results(tmp_path / f"k{ranks}" / "results.h5")
        np.testing.assert_array_equal(got["time"], ref["time"])
        np.testing.assert_allclose(got["ice"]["plate"]["u"], u, rtol=0,
                                   atol=1e-10 * np.abs(u).max())
        np.testing.assert_array_equal(got["ice"]["plate"]["damage"], ref["ice"]["plate"]["damage"])
        drag = ref["histories"]["energy"]["water_drag_dissipated"]
        np.testing.assert_allclose(got["histories"]["energy"]["water_drag_dissipated"], drag,
                                   rtol=1e-10, atol=0)
        force = ref["histories"]["loads/cylinder"]["force"]
        np.testing.assert_allclose(got["histories"]["loads/cylinder"]["force"], force, rtol=0,
                                   atol=1e-10 * np.abs(force).max())


    # the bar pulled apart on 3 ranks (distributed set-up), restarted from step 110 of 220
    ref = read_results(tmp_path / "bar3" / "results.h5")
    u = ref["ice"]["bar"]["u"]
    assert ref["ice"]["bar"]["damage"][-1].max() > 0.5  # torn apart after the checkpoint
    assert ref["ice"]["bar"]["damage"][1].max() > 0  # and breaking before it
    for ranks in (2, 1):
        got = read_results(tmp_path / f"bar{ranks}" / "results.h5")
        np.testing.assert_array_equal(got["time"], ref["time"])
        np.testing.assert_allclose(got["ice"]["bar"]["u"], u, rtol=0,
                                   atol=1e-10 * np.abs(u).max())
        np.testing.assert_array_equal(got["ice"]["bar"]["damage"], ref["ice"]["bar"]["damage"])


def _manifest(path: Path, fmt: int, parts: int = 0) -> None:
    with h5py.File(path, "w") as f:
        f.attrs["format"] = fmt
        f.attrs["case_sha256"] = case_hash("x = 1\n")
        f.attrs["generation"] = 8
        f.attrs["parts"] = parts
        f.create_dataset("part_sizes", data=np.full(parts, 10, dtype=np.int64))
        d = f.create_group("driver")
        for k in ("step", "time", "time_step", "ice_substeps", "structure_substeps",
                  "next_output", "frames", "broken", "initial_energy"):
            d.attrs[k] = 1
        d.create_group("history_rows")
        f.create_group("bodies")
        f.create_group("coupler")


def test_old_format_and_missing_part_are_refused(tmp_path):
    """A format-1 checkpoint (one gathered file) is refused naming both formats; a manifest
    whose part file is missing is refused naming the file (both exit 2 as bad input)."""
    old = tmp_path / "old.h5"
    _manifest(old, 1)
    with pytest.raises(InputError, match="checkpoint format 1 is not the format 2"):
        read_checkpoint(old, "x = 1\n", "case.toml")
    new = tmp_path / "checkpoint.h5"
    _manifest(new, 2, parts=2)
    (tmp_path / "checkpoint.g8.rank0.h5").write_bytes(b"0123456789")
    with pytest.raises(InputError, match=r"checkpoint\.g8\.rank1\.h5 \(rank 1 of 2\) is missing"):
        read_checkpoint(new, "x = 1\n", "case.toml")


def test_per_rank_xdmf_opens_the_whole_run(tmp_path):
    """The main XDMF file of a run with per-rank ice files shows, per frame, one spatial
    collection of every rank's grid; each DataItem names a dataset of its rank's file whose
    shape is the one declared and whose values are the frame written there (read back through
    the XDMF references with h5py, independently of the writer). Per-rank output is the default
    above 2 M particles on several ranks, and on request."""
    import xml.etree.ElementTree as ET

    from pdfem.output import ResultsWriter, rank_file
    from pdfem.output.ranks import PER_RANK_PARTICLES, per_rank_output, rank_grid_files

    assert PER_RANK_PARTICLES == 2_000_000
    assert per_rank_output(False, 4, 2_000_001) and not per_rank_output(False, 4, 2_000_000)
    assert per_rank_output(True, 2, 10) and not per_rank_output(True, 1, 10 ** 9)
    main = tmp_path / "results.h5"
    rng = np.random.default_rng(3)
    parts = [np.array([0, 2, 5]), np.array([1, 3, 4, 6])]
    writers = [ResultsWriter(rank_file(main, r), "", {"rank": r}) for r in range(2)]
    for w, idx in zip(writers, parts):
        w.add_ice_body("sheet", rng.random((len(idx), 3)), np.full(len(idx), 1e-3), index=idx)
    top = ResultsWriter(main, "", {"ice_per_rank": 2})
    top.add_rank_ice_body("sheet", rank_grid_files(main, [len(p) for p in parts]), True)
    written = []
    for t in (0.0, 1e-3):
        frame = [{"u": rng.random((len(p), 3)), "v": rng.random((len(p), 3)),
                  "damage": rng.random(len(p))} for p in parts]
        for w, fields in zip(writers, frame):
            w.write_frame(t, {"sheet": fields})
        top.write_frame(t, {})
        written.append(frame)
    for w in (*writers, top):
        w.close()
    root = ET.parse(main.with_suffix(".xdmf")).getroot()
    temporal = root.find("Domain/Grid")
    assert temporal.get("CollectionType") == "Temporal"
    frames = temporal.findall("Grid")
    assert [f.get("CollectionType") for f in frames] == ["Spatial", "Spatial"]
    for index, frame in enumerate(frames):
        grids = frame.findall("Grid")
        assert len(grids) == 2
        for r, grid in enumerate(grids):
            for item in grid.iter("DataItem"):  # topology, geometry and fields: all resolve
                name, path = item.text.split(":")
                with h5py.File(tmp_path / name, "r") as f:
                    shape = f[path].shape
                assert shape == tuple(int(d) for d in item.get("Dimensions").split())
            for attr in grid.findall("Attribute"):
                item = attr.find("DataItem")
                name, path = item.text.split(":")
                assert name == f"results.rank{r}.h5"
                with h5py.File(tmp_path / name, "r") as f:
                    a = f[path][()]
                dims = tuple(int(d) for d in item.get("Dimensions").split())
                assert a.shape == dims
                key = attr.get("Name")
                want = parts[r] * 0 + 1e-3 if key == "volume" else written[index][r][key]
                np.testing.assert_array_equal(a, want)
    merged = read_results(main)
    assert merged["ice"]["sheet"]["u"].shape == (2, 7, 3)
    np.testing.assert_array_equal(merged["ice"]["sheet"]["u"][1, parts[1]], written[1][1]["u"])
