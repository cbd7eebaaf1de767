"""What ParaView shows of a run's results, with each of its three XDMF readers.

Reference: ParaView's own readers (``XDMFReader``, ``Xdmf3ReaderS``, ``Xdmf3ReaderT``; Debian's
ParaView 5.11, run headless by ``pvbatch``, tests/support/paraview_summary.py) against the run's
HDF5 file read by :func:`pdfem.output.read_results`. Three runs, each shortened to three
frames: the demo (ice sheet against the elastic hull panel, with its contact surface), ice
against the hull panel on 2 MPI ranks writing the ice per rank (``run.output_per_rank``), and
the tiny propeller-ice milling case (a turning elastic propeller). With every reader, at the
last frame: the time steps are the file's; each ice body's ``damage`` has a finite value on
exactly its particles and each elastic structure's ``von_mises`` on exactly its elements, in
what the reader gives and in what a view draws (ParaView's geometry filter); the ice and the
structures are drawn where they are (bounds of reference + ``u``). ``XDMFReader`` and
``Xdmf3ReaderT`` give every body its own block named after it, the same name at the first and
the last frame; ``Xdmf3ReaderS`` gives one unnamed block of every grid (it cannot name them,
``pdfem.output.xdmf_grids``). Skipped without ``pvbatch``, except under CI (``CI=true``), which
installs ParaView (.ci/run): there a missing ``pvbatch`` fails.
"""

from __future__ import annotations

import dataclasses
import json
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from pdfem.case.schema import load_case
from pdfem.output import read_results
from pdfem.run.driver import run_case
from pdfem.validation.case import case_path

from support.cases import PANEL_BODIES
from support.cli import run_ok

ROOT = Path(__file__).resolve().parents[2]
SUMMARY = Path(__file__).resolve().parents[1] / "support" / "paraview_summary.py"
READERS = ("XDMFReader", "Xdmf3ReaderS", "Xdmf3ReaderT")

PER_RANK = """
[run]
end_time = 2.0e-4
output_interval = 1.0e-4
output_per_rank = true
""" + PANEL_BODIES
"""Ice pushed against the hull panel (tests/run/test_mpi_run.py's case), its ice per rank."""

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def pvbatch() -> str:
    """ParaView's ``pvbatch``; the test is skipped without it, except under CI."""
    found = shutil.which("pvbatch")
    if found is None:
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail("pvbatch is missing under CI: .ci/run installs Debian's paraview")
        pytest.skip("ParaView's pvbatch is not installed (Debian: apt-get install paraview "
                    "python3-paraview)")
    return found


def shortened(path: Path, end: float, frame: float):
    """The case file ``path`` ending at ``end`` (s), a frame every ``frame`` (s)."""
    case = load_case(path)
    return dataclasses.replace(case, run=dataclasses.replace(case.run, end_time=end,
                                                             output_interval=frame))


def views(pvbatch: str, xdmf: Path) -> dict:
    """Every reader's view of ``xdmf`` (tests/support/paraview_summary.py)."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    r = subprocess.run([pvbatch, str(SUMMARY), str(xdmf)], capture_output=True, text=True,
                       timeout=600, env=env, cwd=xdmf.parent)
    assert r.returncode == 0, r.stderr[-3000:]
    line = next(s for s in r.stdout.splitlines() if s.startswith("SUMMARY "))
    return json.loads(line.removeprefix("SUMMARY "))


def body_of(reader: str, path: list) -> str | None:
    """The body a leaf of ``reader``'s output shows (None: Xdmf3ReaderS names none)."""
    if reader == "XDMFReader":
        return path[0]            # the body's temporal collection
    if reader == "Xdmf3ReaderT":
        return path[-1].split(".rank")[0]  # the body's grid, or a rank's part of it
    return None


def bounds(x: np.ndarray) -> list[float]:
    """VTK's bounds (xmin, xmax, ymin, ymax, zmin, zmax) of the (n, 3) positions ``x``."""
    return [float(v) for pair in zip(x.min(axis=0), x.max(axis=0)) for v in pair]


def check(seen: dict, results: dict, pieces: set[str]) -> None:
    """Each reader's view against the results file (module docstring); ``pieces``: the grid
    names of one frame."""
    ice, structures = results["ice"], results["structure"]
    elastic = {k for k, s in structures.items() if "von_mises" in s}
    assert elastic
    particles = sum(b["x0"].shape[0] for b in ice.values())
    for reader in READERS:
        view = seen[reader]
        np.testing.assert_allclose(view["times"], results["time"], rtol=1e-12, atol=0)
        last = view["last"]
        drawn = view["drawn"]
        if reader == "Xdmf3ReaderS":   # one unnamed block of every grid, drawn merged
            assert len(last) == len(pieces) and all(set(leaf["path"]) == {None} for leaf in last)
            assert sum(leaf["point"].get("damage", 0) for leaf in last) == particles
            assert sum(leaf["cell"].get("von_mises", 0) for leaf in last) == sum(
                structures[s]["von_mises"].shape[1] for s in elastic)
            (merged,) = drawn
            assert merged["point"].get("damage", 0) == particles
            assert merged["cell"].get("von_mises", 0) > 0
            continue
        names = [leaf["path"][0 if reader == "XDMFReader" else -1] for leaf in last]
        assert names == [leaf["path"][0 if reader == "XDMFReader" else -1]
                         for leaf in view["first"]]  # the same names at every time
        if reader == "Xdmf3ReaderT":
            assert set(names) == pieces
        by_body: dict[str, list] = {}
        for leaf in last:
            by_body.setdefault(body_of(reader, leaf["path"]), []).append(leaf)
        assert set(by_body) == {f"ice/{k}" for k in ice} | {f"structure/{k}" for k in structures}
        for name, body in ice.items():
            leaves = by_body[f"ice/{name}"]
            n = body["x0"].shape[0]
            assert sum(leaf["points"] for leaf in leaves) == n
            assert sum(leaf["point"].get("damage", 0) for leaf in leaves) == n
            lo = np.min([leaf["bounds"][0::2] for leaf in leaves], axis=0)
            hi = np.max([leaf["bounds"][1::2] for leaf in leaves], axis=0)
            np.testing.assert_allclose(np.stack([lo, hi], 1).ravel(),
                                       bounds(body["x0"] + body["u"][-1]), rtol=0, atol=1e-12)
            assert sum(leaf["point"].get("damage", 0) for leaf in drawn
                       if body_of(reader, leaf["path"]) == f"ice/{name}") == n
        for name, s in structures.items():
            (leaf,) = by_body[f"structure/{name}"]
            assert (leaf["points"], leaf["cells"]) == (s["points"].shape[0], s["cells"].shape[0])
            np.testing.assert_allclose(leaf["bounds"], bounds(s["points"] + s["u"][-1]),
                                       rtol=0, atol=1e-12)
            if name in elastic:
                assert leaf["cell"].get("von_mises", 0) == s["cells"].shape[0]
                (shown,) = [d for d in drawn if body_of(reader, d["path"]) == f"structure/{name}"]
                assert shown["cell"].get("von_mises", 0) == shown["cells"] > 0


def test_demo_in_paraview(pvbatch, tmp_path):
    """The demo (0.2 ms): the sheet, the panel's contact surface and the panel."""
    run_case(shortened(ROOT / "models" / "demo_ice_sheet_panel.toml", 2e-4, 1e-4), tmp_path,
             quiet=True)
    results = read_results(tmp_path / "results.h5")
    assert len(results["time"]) == 3
    check(views(pvbatch, tmp_path / "results.xdmf"), results,
          {"ice/sheet", "structure/panel.contact", "structure/panel"})


def test_per_rank_run_in_paraview(pvbatch, tmp_path):
    """Ice against the hull panel on 2 ranks, the ice in results.rank0.h5 and
    results.rank1.h5: the main XDMF file shows both parts of the floe, from their files."""
    case = tmp_path / "case.toml"
    case.write_text(PER_RANK)
    run_ok("run", case, "--out", tmp_path / "out", "--quiet", ranks=2, timeout=600)
    results = read_results(tmp_path / "out" / "results.h5")
    assert results["meta"]["ice_per_rank"] == 2 and len(results["time"]) == 3
    check(views(pvbatch, tmp_path / "out" / "results.xdmf"), results,
          {"ice/floe.rank0", "ice/floe.rank1", "structure/panel.contact", "structure/panel"})


def test_turning_propeller_in_paraview(pvbatch, tmp_path):
    """The tiny milling propeller spinning up (0.5 ms): drawn turned, as far as ``u`` says."""
    with case_path("propeller_milling_tiny.toml") as path:
        case = shortened(path, 5e-4, 2.5e-4)
    run_case(case, tmp_path, quiet=True)
    results = read_results(tmp_path / "results.h5")
    turned = results["structure"]["propeller"]["u"][-1]
    assert np.abs(turned).max() > 1e-3  # m: the blade tips have moved
    check(views(pvbatch, tmp_path / "results.xdmf"), results,
          {"ice/block", "structure/propeller.contact", "structure/propeller"})
