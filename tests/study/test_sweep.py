"""Parameter studies (pdfem.study, ``pdfem sweep``): the grid, its validation, the study folder,
skipping finished runs, the table, the SLURM job array.

References: the cartesian product of the values (itertools-free counts: 2 x 2 = 4 runs, first
key slowest); linear elasticity (the tiny elastic block of support.cases.BLOCK pushed twice as
fast carries twice the reactions, to the order of its strain, 3.3e-4); bash itself (``bash -n``
and the script run with a stand-in for ``pdfem`` that records its arguments).
"""

from __future__ import annotations

import csv
import json
import os
import stat
import subprocess
from pathlib import Path

import pytest

import pdfem
from pdfem.case import load_case
from pdfem.cli.main import main
from pdfem.errors import InputError
from pdfem.study.folder import SweepFolder
from pdfem.study.grid import grid_runs, parse_set
from pdfem.study.local import run_command
from pdfem.study.plan import plan_sweep
from pdfem.study.plot import choose
from pdfem.study.runner import sweep_status
from pdfem.study.table import collect

from support.cases import BLOCK
from support.cli import run_pdfem

E = "ice.0.material.youngs_modulus"
V = "ice.0.prescribed_velocity.0.velocity"
SETS = ["--set", f"{E}=3e9,4e9", "--set", f"{V}=[0,0,-0.5],[0,0,-1.0]"]
NAMES = ["youngs_modulus=3e+09__velocity=0,0,-0.5", "youngs_modulus=3e+09__velocity=0,0,-1.0",
         "youngs_modulus=4e+09__velocity=0,0,-0.5", "youngs_modulus=4e+09__velocity=0,0,-1.0"]
COLUMNS = ["run", E, V, "regions.block.base.peak [N]", "regions.block.base.mean [N]",
           "regions.block.base.per_step_peak [N]", "regions.block.top.peak [N]",
           "regions.block.top.mean [N]", "regions.block.top.per_step_peak [N]",
           "energy.residual [J]", "energy.supplied [J]", "exit_status"]


@pytest.fixture
def block(tmp_path) -> Path:
    path = tmp_path / "block.toml"
    path.write_text(BLOCK)
    return path


def _grid(sets: list[str]) -> dict:
    return dict(parse_set(s) for s in sets[1::2])


def _rows(out: Path) -> list[dict]:
    with open(out / "summary.csv", newline="") as f:
        return list(csv.DictReader(f))


def _check_table(out: Path) -> None:
    """summary.csv: 4 rows in grid order, the expected columns, every run done, and the
    reactions doubled by the doubled push (linear elasticity, to the strain 3.3e-4)."""
    with open(out / "summary.csv", newline="") as f:
        assert next(csv.reader(f)) == COLUMNS
    rows = _rows(out)
    assert [r["run"] for r in rows] == NAMES and {r["exit_status"] for r in rows} == {"0"}
    for slow, fast in ((rows[0], rows[1]), (rows[2], rows[3])):
        for col in ("regions.block.base.peak [N]", "regions.block.top.peak [N]"):
            assert float(fast[col]) == pytest.approx(2 * float(slow[col]), rel=3.3e-4)
    assert (out / f"regions.block.top.peak_vs_{E}.png").read_bytes()[:4] == b"\x89PNG"


def test_set_values_are_toml_values_split_at_commas_outside_brackets():
    key, values = parse_set('run.x=0.5,2,true,[0, 0,-1],[1,2],pairs,"a,b",{ a = 1, b = [2,3] }')
    assert key == "run.x"
    assert values == [0.5, 2, True, [0, 0, -1], [1, 2], "pairs", "a,b", {"a": 1, "b": [2, 3]}]


def test_the_runs_are_the_cartesian_product_first_key_slowest_with_stable_names():
    runs = grid_runs(_grid(SETS))
    assert [r.name for r in runs] == NAMES
    assert [r.values[E] for r in runs] == [3e9, 3e9, 4e9, 4e9]
    names = [r.name for r in grid_runs({"ice.0.dx": [0.01], "ice.1.dx": [0.02], "run.x": [True]})]
    assert names == ["ice.0.dx=0.01__ice.1.dx=0.02__x=true"]


@pytest.mark.parametrize("grid, field", [
    ({}, "--set"),
    ({"run.end_time": []}, "--set run.end_time"),
    ({"run.end_time": 1.0}, "--set run.end_time"),
    ({"ice.0.dx": [0.01], "ice[0].dx": [0.02]}, "--set ice[0].dx"),
    ({"run.title": ["a b", "a_b"]}, "--set run.title"),  # the same run name twice
])
def test_a_bad_grid_is_bad_input_naming_the_key(grid, field):
    with pytest.raises(InputError) as e:
        grid_runs(grid)
    assert e.value.field == field


@pytest.mark.parametrize("option, field, words", [
    (f"{E}=3e9,-4e9", f"--set {E}", "must be > 0 Pa"),
    ("ice.5.dx=0.01", "--set ice.5.dx", "ice has 1 entry"),
    ("run.no_such_key=1,2", "--set run.no_such_key", "unknown key"),
    (f"{E}=abc", f"--set {E}", "expected a finite number"),
    ("no_equals_sign", "--set", "give KEY=V1,V2"),
    (f"{E}=3e9,", f"--set {E}", "a value is empty"),
])
def test_a_bad_set_exits_2_naming_the_key_before_anything_is_written(block, tmp_path, capsys,
                                                                      option, field, words):
    out = tmp_path / "study"
    assert main(["sweep", str(block), "--set", "run.end_time=2e-5", "--set", option,
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"field '{field}'" in err and words in err and "Traceback" not in err
    assert not out.exists()


@pytest.fixture(scope="module")
def study(tmp_path_factory) -> tuple[Path, Path]:
    """A study of the 2 x 2 grid whose runs were made here in this process, from the case
    files the study wrote (as the local runner's ``pdfem run`` processes would), each with its
    status: (the base case file, the study folder)."""
    tmp = tmp_path_factory.mktemp("study")
    block = tmp / "block.toml"
    block.write_text(BLOCK)
    folder, runs = plan_sweep(load_case(block), _grid(SETS), tmp / "study")
    assert [r.name for r in runs] == NAMES
    for r in runs:
        assert not folder.finished(r.name)
        pdfem.run(folder.case_file(r.name), out=folder.run_dir(r.name))
        folder.write_status(r.name, 0, 0.0)
    return block, folder.root


def test_a_study_run_again_skips_its_finished_runs_and_collects_one_row_per_run(study, capsys):
    block, out = study
    folder = SweepFolder(out)
    written = {n: folder.results(n).stat().st_mtime_ns for n in NAMES}
    assert main(["sweep", str(block), *SETS, "--out", str(out), "--jobs", "2"]) == 0
    assert "4 of 4 runs finished before: skipped" in capsys.readouterr().out
    assert {n: folder.results(n).stat().st_mtime_ns for n in NAMES} == written
    _check_table(out)
    assert json.loads((out / "sweep.json").read_text())["keys"] == [E, V]


def test_the_plot_is_the_chosen_output_against_the_chosen_input(study):
    table = collect(study[1])
    assert len(table.rows) == 4 and table.inputs == [E, V]
    assert choose(table, None) == ("regions.block.top.peak [N]", E)  # the largest peak reaction
    assert choose(table, f"energy.supplied:{V}") == ("energy.supplied [J]", V)
    assert choose(table, f"energy.supplied [J]:{V}") == ("energy.supplied [J]", V)
    for spec in ("energy.supplied", f"no.such.output:{V}", "energy.supplied:run.end_time"):
        with pytest.raises(InputError) as e:
            choose(table, spec)
        assert e.value.field == "--plot"


def test_a_failed_or_killed_run_runs_again_from_its_checkpoint(block, tmp_path):
    folder, _ = plan_sweep(load_case(block), _grid(SETS), tmp_path / "study")
    folder.write_status(NAMES[0], 0, 1.0)
    folder.write_status(NAMES[1], 1, 1.0)
    folder.write_status(NAMES[2], 3, 1.0)  # a blow-up: a second try would blow up the same way
    assert [folder.finished(n) for n in NAMES] == [True, False, True, False]
    checkpoint = folder.run_dir(NAMES[1]) / "checkpoint.h5"
    checkpoint.write_bytes(b"")
    assert run_command(folder, NAMES[1])[3:] == ["run", str(folder.case_file(NAMES[1])), "--out",
                                                 str(folder.run_dir(NAMES[1])), "--restart",
                                                 str(checkpoint)]
    assert run_command(folder, NAMES[3])[3:] == ["run", str(folder.case_file(NAMES[3])), "--out",
                                                 str(folder.run_dir(NAMES[3]))]


def test_a_study_folder_refuses_another_base_case_or_other_keys(block, tmp_path):
    out = tmp_path / "study"
    plan_sweep(load_case(block), _grid(SETS), out)
    plan_sweep(load_case(block), {E: [3e9, 5e9], V: [[0, 0, -0.5]]}, out)  # more values: more runs
    assert len(json.loads((out / "sweep.json").read_text())["runs"]) == 5
    block.write_text(BLOCK.replace("density = 900.0", "density = 917.0"))
    with pytest.raises(InputError, match="case file differs"):
        plan_sweep(load_case(block), _grid(SETS), out)
    with pytest.raises(InputError) as e:
        plan_sweep(load_case(block), {"run.end_time": [2e-5]}, out)
    assert e.value.field == "--out"


@pytest.mark.parametrize("statuses, exit_status", [
    ([0, 0], 0), ([0, 3], 3), ([3, 3], 3), ([0, 1], 1), ([3, 2], 1), ([0, None], 1), ([-9], 1)])
def test_a_studys_exit_status_is_the_worst_of_its_runs(statuses, exit_status):
    assert sweep_status(statuses) == exit_status


def test_collect_refuses_a_folder_without_a_study(tmp_path, capsys):
    assert main(["sweep", "--collect", str(tmp_path)]) == 2
    assert "no sweep here" in capsys.readouterr().err


def _stub(tmp_path: Path) -> Path:
    """A stand-in for ``pdfem`` that records its arguments and exits with $STUB_STATUS."""
    stub = tmp_path / "pdfem-stub"
    stub.write_text('#!/bin/bash\necho "$@" >> "$STUB_LOG"\nexit "${STUB_STATUS:-0}"\n')
    stub.chmod(stub.stat().st_mode | stat.S_IEXEC)
    return stub


def test_slurm_writes_a_job_array_that_runs_each_case_once(block, tmp_path, capsys):
    out = tmp_path / "study"
    assert main(["sweep", str(block), *SETS, "--out", str(out), "--slurm", "--jobs", "2",
                 "--threads", "3"]) == 0
    script = out / "sweep.sbatch"
    text = script.read_text()
    assert "#SBATCH --array=0-3%2" in text and "#SBATCH --cpus-per-task=3" in text
    assert subprocess.run(["bash", "-n", str(script)]).returncode == 0
    assert not any(out.glob("runs/*/results.h5"))  # nothing ran
    folder = SweepFolder(out)
    log = tmp_path / "calls.txt"
    env = {**os.environ, "PDFEM": str(_stub(tmp_path)), "STUB_LOG": str(log)}

    def task(i: int, status: int = 0) -> None:
        r = subprocess.run(["bash", str(script)], env={**env, "SLURM_ARRAY_TASK_ID": str(i),
                                                        "STUB_STATUS": str(status)})
        assert r.returncode == status

    task(2)
    run = folder.run_dir(NAMES[2])
    assert log.read_text().split() == ["run", str(run / "case.toml"), "--out", str(run)]
    assert folder.status(NAMES[2]) == 0 and folder.finished(NAMES[2])
    task(2)  # finished: the task does nothing
    assert len(log.read_text().splitlines()) == 1
    (folder.run_dir(NAMES[1]) / "checkpoint.h5").write_bytes(b"")
    task(1, status=1)  # killed or failed: a status that is not finished, from its checkpoint
    assert log.read_text().splitlines()[1].endswith(f"--restart={folder.run_dir(NAMES[1])}/checkpoint.h5")
    assert folder.status(NAMES[1]) == 1 and not folder.finished(NAMES[1])
    # written again: only the runs left to do
    assert main(["sweep", str(block), *SETS, "--out", str(out), "--slurm"]) == 0
    text = script.read_text()
    assert "#SBATCH --array=0-2\n" in text and NAMES[2] not in text


@pytest.mark.slow
def test_pdfem_sweep_runs_its_cases_as_processes_two_at_once_then_skips_them(block, tmp_path):
    """``pdfem sweep`` as a user types it: 2 ``pdfem run`` processes at once (about 10 s on 2
    busy cores: each process loads pdfem and numba's cache; the 2 x 2 grid's table and skipping
    are tested above on runs made in-process)."""
    out = tmp_path / "study"
    sets = ["--set", f"{E}=3e9,4e9", "--set", f"{V}=[0,0,-0.5]"]
    r = run_pdfem("sweep", block, *sets, "--out", out, "--jobs", "2", cwd=tmp_path)
    assert r.returncode == 0, r.stderr[-3000:]
    lines = r.stdout.splitlines()
    started = [k for k, line in enumerate(lines) if line.startswith("  start ")]
    ended = [k for k, line in enumerate(lines) if line.startswith("  [")]
    assert len(started) == len(ended) == 2 and max(started) < min(ended)  # both ran at once
    names = [NAMES[0], NAMES[2]]
    assert sorted(p.name for p in (out / "runs").iterdir()) == names
    rows = _rows(out)
    assert [x["run"] for x in rows] == names and [x["exit_status"] for x in rows] == ["0", "0"]
    assert list(rows[0]) == [c for c in COLUMNS if c != V]  # V does not vary
    log = (out / "runs" / NAMES[0] / "log.txt").read_text()
    assert log.count("$ pdfem run ") == 1 and "energy budget" in log
    r = run_pdfem("sweep", block, *sets, "--out", out, "--jobs", "2", cwd=tmp_path)
    assert r.returncode == 0 and "2 of 2 runs finished before: skipped" in r.stdout
    assert (out / "runs" / NAMES[0] / "log.txt").read_text() == log
