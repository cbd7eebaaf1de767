"""``pdfem post``: summary figures, CSV, plots and the spectrum, checked against the file itself.

References: the HDF5 datasets read directly with h5py (peaks, times, CSV columns); the
trapezoid rule written out by hand (mean force); the analytic Fourier series of a sine (the
spectrum); values planted in hand-made files (locations, damage, reactions).
"""

from __future__ import annotations

import contextlib
import json
from pathlib import Path

import h5py
import numpy as np
import pytest

from pdfem.cli import main as cli
from pdfem.cli import run as cli_run
from pdfem import post
from pdfem.case.schema import load_case
from pdfem.run.driver import run_case
from pdfem.output import ResultsWriter

PNG = b"\x89PNG\r\n\x1a\n"

# A 10 x 6 x 3 ice box (dx = 0.01 m) hit by a rigid cylinder: a coupled run of ~1 s.
TINY_CASE = """
[run]
title = "tiny coupled case"
end_time = 4.0e-4
output_interval = 1.0e-4

[[ice]]
name = "box"
dx = 0.01
shape = { box = { min = [0.0, 0.0, 0.0], max = [0.1, 0.06, 0.03] } }
material = { density = 900.0, youngs_modulus = 4.1e9, poisson_ratio = 0.3, fracture_energy = 10.0 }
initial_velocity = [0.0, 2.0, 0.0]

[[structure]]
name = "cyl"
kind = "rigid"
mesh = "indenters"
params = { shape = "cylinder", radius = 0.03, length = 0.04, axis = "z", center_x = 0.05, center_y = 0.0856, center_z = 0.015, element_size = 0.01 }
motion = { velocity = [0.0, -2.0, 0.0] }

[[contact]]
ice = "box"
structure = "cyl"
"""


def run_post(capsys, *args) -> tuple[int, str, str]:
    """``pdfem post ...`` in this process: (exit status, stdout, stderr)."""
    capsys.readouterr()
    rc = cli.main(["post", *map(str, args)])
    out = capsys.readouterr()
    return rc, out.out, out.err


@pytest.fixture(scope="module")
def tiny_case(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("case") / "tiny.toml"
    path.write_text(TINY_CASE)
    return path


@pytest.fixture(scope="module")
def coupled(tiny_case) -> Path:
    """Results of a real coupled run (pdfem.run.driver.run_case)."""
    summary = run_case(load_case(tiny_case), tiny_case.parent / "out", quiet=True)
    return summary.results


def _ice(writer: ResultsWriter, rng) -> np.ndarray:
    g = np.stack(np.meshgrid(np.arange(6), np.arange(4), np.arange(2), indexing="ij"), -1)
    x0 = 0.01 * g.reshape(-1, 3).astype(float)   # extents 0.05 (x), 0.03 (y), 0.01 (z) m
    writer.add_ice_body("floe", x0, volume=rng.uniform(0.5e-6, 1.5e-6, len(x0)))
    return x0


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory) -> dict:
    """A hand-made file with an elastic structure, loads, a monitor, reactions and energies;
    the planted extremes are returned with it."""
    rng = np.random.default_rng(1)
    path = tmp_path_factory.mktemp("synthetic") / "results.h5"
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], float)
    cells = np.array([[0, 1, 2, 3], [1, 2, 3, 4]])
    frames = np.array([0.0, 1e-3, 2e-3])
    with ResultsWriter(path, "", {"title": "synthetic"}) as w:
        x0 = _ice(w, rng)
        w.add_structure("panel", points, cells, "tetra")
        n = len(x0)
        for f, t in enumerate(frames):
            u = np.zeros((5, 3))
            vm = np.array([1e6, 2e6]) * (1 + f)
            if f == 1:
                u[4] = [3e-4, -4e-4, 0.0]     # |u| = 5e-4 m at node 4, t = 1 ms
                vm[1] = 9e7                   # max von Mises in element 1 at t = 1 ms
            damage = np.linspace(0.0, 1.0, n) * f / 2
            w.write_frame(t, {"floe": {"u": np.zeros((n, 3)), "v": np.zeros((n, 3)),
                                       "damage": damage}},
                          {"panel": {"u": u, "von_mises": vm}})
            w.append_history("structures/panel", t, {
                "kinetic": f, "strain": 2.0 * f, "reaction_fixed": [0.0, 30.0 * f, -40.0 * f]})
            w.append_history("energy", t, {"kinetic": 1.0 + f, "strain": 0.5 * f})
        for t in np.linspace(0.0, 2e-3, 201):
            w.append_history("loads/panel", t, {"force": [1e6 * t, -2e6 * t, 5.0], "moment": [0, 0, t],
                                                "contacts": 3.0})
            w.append_history("monitors/probe", t, {"u": [0.0, 0.0, -t * 1e-2],
                                                   "von_mises": 1e8 * np.sin(1e3 * t)})
    return {"path": path, "points": points, "cells": cells}


def test_json_peak_and_mean_equal_the_load_history_in_the_file(coupled, capsys):
    """Peak |F|, its time, the signed component peaks and the trapezoid mean, against the
    file's /loads/cyl datasets read with h5py: the headline peak is that of the force averaged
    over 0.1 ms (a moving average of the per-step forces, computed here by convolution), the
    per-step peak the raw history's."""
    rc, out, err = run_post(capsys, coupled, "--json")
    assert rc == 0, err
    summary = json.loads(out)                      # exactly one JSON object on stdout
    with h5py.File(coupled, "r") as f:
        t = f["loads/cyl/time"][()]
        force = f["loads/cyl/force"][()]
        contacts = f["loads/cyl/contacts"][()]
    mag = np.linalg.norm(force, axis=1)
    assert mag.max() > 100.0                       # the cylinder did hit the ice
    got = summary["loads"]["cyl"]
    assert got["magnitude"]["per_step_peak"] == pytest.approx(mag.max(), rel=1e-12)
    assert got["magnitude"]["per_step_time"] == t[np.argmax(mag)]
    n = round(1e-4 / (t[1] - t[0]))
    assert got["window"] == pytest.approx(n * (t[1] - t[0]), rel=1e-9)
    avg = np.stack([np.convolve(force[:, a], np.ones(n) / n, mode="valid") for a in range(3)], 1)
    amag = np.linalg.norm(avg, axis=1)
    assert got["magnitude"]["peak"] == pytest.approx(amag.max(), rel=1e-9)
    assert got["magnitude"]["time"] == t[n - 1 + np.argmax(amag)]
    assert got["magnitude"]["peak"] < 0.9 * mag.max()   # the impacts' one-step spikes
    for a, c in enumerate("xyz"):
        j = np.argmax(np.abs(avg[:, a]))
        assert got[c]["peak"] == pytest.approx(avg[j, a], rel=1e-9, abs=1e-12 * mag.max())
    # mean: trapezoid rule over the run, dt * (sum - ends / 2) / span on the uniform steps
    span = t[-1] - t[0]
    assert span == pytest.approx(4.0e-4, rel=1e-9)
    dt = np.diff(t)
    for a, c in enumerate("xyz"):
        i = np.argmax(np.abs(force[:, a]))
        assert got[c]["per_step_peak"] == force[i, a] and got[c]["per_step_time"] == t[i]
        trap = np.sum(0.5 * (force[1:, a] + force[:-1, a]) * dt) / span
        assert got[c]["mean"] == pytest.approx(trap, rel=1e-9, abs=1e-9 * mag.max())
    trap = np.sum(0.5 * (mag[1:] + mag[:-1]) * dt) / span
    assert got["magnitude"]["mean"] == pytest.approx(trap, rel=1e-9)
    assert got["max_contacts"] == contacts.max()
    assert summary["ice"]["box"]["particles"] == 180
    assert summary["structures"]["cyl"]["kind"] == "rigid"


def test_text_summary_has_units_and_sections(coupled, capsys):
    rc, out, _ = run_post(capsys, coupled)
    assert rc == 0
    for text in ("Ice force on structure 'cyl'", "peak [N]", "at t [s]", "mean [N]",
                 "time average over the run", "max |u| [m]", "Energies", "value [J]",
                 "max damage"):
        assert text in out


def _check_csv_against_file(csv: Path, h5: Path) -> int:
    """Every CSV column equals its HDF5 dataset (column) exactly; returns the column count."""
    header = csv.read_text().splitlines()[0].split(",")
    table = np.loadtxt(csv, delimiter=",", skiprows=1, ndmin=2)
    assert header[0] == "time [s]"
    with h5py.File(h5, "r") as f:
        for j, name in enumerate(header[1:], start=1):
            path, unit = name.split(" [")
            group, key = path.rsplit("/", 1)
            assert group.split("/")[0] in ("loads", "contacts", "monitors", "shaft", "motions")
            assert unit.rstrip("]") == post.UNITS[key.rsplit("_", 1)[0] if key[-2:] in
                                                  ("_x", "_y", "_z") else key]
            if key in f[group]:
                ref = f[group][key][()]
            else:
                key, comp = key.rsplit("_", 1)
                ref = f[group][key][()][:, "xyz".index(comp)]
            np.testing.assert_array_equal(table[:, 0], f[group]["time"][()])
            np.testing.assert_array_equal(table[:, j], ref)
    return len(header)


def test_csv_round_trips(coupled, synthetic, tmp_path, capsys):
    """CSV columns equal the HDF5 datasets bit for bit (17 significant digits)."""
    csv = tmp_path / "coupled.csv"
    rc, _, err = run_post(capsys, coupled, "--csv", csv)
    assert rc == 0, err
    # time, then force, moment, contacts (+ the applied load of the structure) of the structure
    # (loads) and of the pair (contacts)
    assert _check_csv_against_file(csv, coupled) == 1 + 2 * (3 + 3 + 1) + 3
    csv = tmp_path / "synthetic.csv"
    assert post.write_csv(post.load_results(synthetic["path"]), csv)[-1] \
        == "monitors/probe/von_mises [Pa]"
    assert _check_csv_against_file(csv, synthetic["path"]) == 1 + 7 + 4


def test_csv_holds_shaft_loads_and_ship_motions():
    """A propeller's shaft history and a free ship's motions are CSV columns too, with their
    units (N m for torques, m for positions, rad for angles)."""
    t = np.array([1e-3, 2e-3, 3e-3])
    results = {"histories": {
        "shaft/prop": {"time": t, "ice_torque": np.array([1.0, 2.0, 3.0]),
                       "ice_force": np.arange(9.0).reshape(3, 3)},
        "shaft/prop.blade1": {"time": t, "spindle_torque": np.array([0.1, 0.2, 0.3])},
        "motions/hull": {"time": t, "position": np.ones((3, 3)), "rotation": np.zeros((3, 3))},
        "energy": {"time": t, "kinetic": np.zeros(3)}}}
    names, table = post.history_table(results)
    assert names == ["time [s]", "shaft/prop/ice_force_x [N]", "shaft/prop/ice_force_y [N]",
                     "shaft/prop/ice_force_z [N]", "shaft/prop/ice_torque [N m]",
                     "shaft/prop.blade1/spindle_torque [N m]", "motions/hull/position_x [m]",
                     "motions/hull/position_y [m]", "motions/hull/position_z [m]",
                     "motions/hull/rotation_x [rad]", "motions/hull/rotation_y [rad]",
                     "motions/hull/rotation_z [rad]"]
    np.testing.assert_array_equal(table[:, 0], t)
    np.testing.assert_array_equal(table[:, 4], [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(table[:, 3], [2.0, 5.0, 8.0])


def test_plots_are_written(coupled, tmp_path, capsys):
    """Six non-empty PNG files for a coupled run (with the pressure-area curves); two (damage,
    energy) for an ice-only file."""
    rc, out, err = run_post(capsys, coupled, "--plots", tmp_path / "plots", "--json")
    assert rc == 0, err
    names = {"load_history.png", "load_spectrum.png", "structure_response.png", "damage.png",
             "energy.png", "pressure_area.png"}
    assert {Path(p).name for p in json.loads(out)["plots"]} == names
    assert {p.name for p in (tmp_path / "plots").iterdir()} == names
    for p in (tmp_path / "plots").iterdir():
        data = p.read_bytes()
        assert data[:8] == PNG and len(data) > 10_000

    ice_only = tmp_path / "ice_only.h5"
    with ResultsWriter(ice_only) as w:
        x0 = _ice(w, np.random.default_rng(2))
        for t in (0.0, 1e-3):
            w.write_frame(t, {"floe": {"u": np.zeros_like(x0), "v": np.zeros_like(x0),
                                       "damage": np.full(len(x0), 10 * t)}})
            w.append_history("energy", t, {"kinetic": 1.0})
    written = post.write_plots(post.load_results(ice_only), tmp_path / "ice_plots")
    assert [p.name for p in written] == ["damage.png", "energy.png"]
    assert all(p.read_bytes()[:8] == PNG for p in written)


@pytest.mark.parametrize("cycles", [12.0, 12.4])
def test_spectrum_of_a_sine_load_peaks_at_its_frequency(tmp_path, cycles):
    """A load F = (F0 + A sin(2 pi f0 t), 0, 0) sampled uniformly: the one-sided amplitude
    spectrum of |F| (= F0 + A sin, as F0 > A) peaks within one bin of f0; with a whole number
    of periods the peak reads A and the 0 Hz bin F0 (analytic Fourier coefficients)."""
    f0, amp, mean, k, dt = cycles / 0.01, 300.0, 1000.0, 1000, 1e-5  # 1000 steps over 10 ms
    path = tmp_path / "sine.h5"
    t = dt * np.arange(k)
    with ResultsWriter(path) as w:
        w.add_ice_body("floe", np.eye(3))
        w.write_frame(0.0, {"floe": {"u": np.zeros((3, 3)), "v": np.zeros((3, 3)),
                                     "damage": np.zeros(3)}})
        for ti in t:
            w.append_history("loads/wall", ti, {"force": [mean + amp * np.sin(2 * np.pi * f0 * ti),
                                                          0.0, 0.0]})
    h = post.load_results(path)["histories"]["loads/wall"]
    f, a = post.amplitude_spectrum(h["time"], np.linalg.norm(h["force"], axis=1))
    df = 1.0 / (k * dt)
    assert f[1] == pytest.approx(df) and len(f) == k // 2 + 1
    peak = f[1 + np.argmax(a[1:])]
    assert abs(peak - f0) <= df
    if cycles == int(cycles):
        assert a[0] == pytest.approx(mean, rel=1e-9)
        assert a[1 + np.argmax(a[1:])] == pytest.approx(amp, rel=1e-9)


def test_summary_of_planted_extremes(synthetic):
    """Max von Mises (element 1 at 1 ms, centre = mean of its nodes), max |u| (node 4, 5e-4 m),
    reaction peak (100 N at 2 ms), monitor peaks, and a linear ramp's time average (F(T) / 2)."""
    s = post.summarize(post.load_results(synthetic["path"]))
    st = s["structures"]["panel"]
    assert st["kind"] == "elastic"
    assert st["max_von_mises"] == {"value": 9e7, "time": 1e-3, "element": 1,
                                   "location": list(synthetic["points"][[1, 2, 3, 4]].mean(0))}
    assert st["max_displacement"]["value"] == pytest.approx(5e-4, rel=1e-12)
    assert st["max_displacement"]["node"] == 4 and st["max_displacement"]["time"] == 1e-3
    assert st["max_displacement"]["location"] == [1.0, 1.0, 1.0]
    assert st["reactions"]["fixed"]["peak"] == pytest.approx(100.0)
    assert st["reactions"]["fixed"]["time"] == 2e-3
    load = s["loads"]["panel"]
    # the headline peak of the ramp averaged over 0.1 ms (the last 10 steps of 10 us): F at
    # their mid-point, 45 us before the end; the per-step peak F(T)
    assert load["window"] == pytest.approx(1e-4)
    assert load["x"]["peak"] == pytest.approx(1e6 * (2e-3 - 4.5e-5))
    assert load["x"]["per_step_peak"] == pytest.approx(2e3) and load["x"]["mean"] == pytest.approx(1e3)
    assert load["y"]["peak"] == pytest.approx(-2e6 * (2e-3 - 4.5e-5))
    assert load["y"]["per_step_peak"] == pytest.approx(-4e3)
    assert load["y"]["time"] == pytest.approx(2e-3)
    assert load["z"]["mean"] == pytest.approx(5.0)
    f = 1e6 * (2e-3 - 4.5e-5)
    assert load["magnitude"]["peak"] == pytest.approx(np.sqrt(f**2 + (2 * f)**2 + 25))
    assert load["magnitude"]["per_step_peak"] == pytest.approx(np.sqrt(2e3**2 + 4e3**2 + 25))
    mon = s["monitors"]["probe"]
    assert mon["peak_u"]["value"] == pytest.approx(2e-5)
    assert mon["peak_von_mises"]["value"] == pytest.approx(1e8, rel=1e-3)     # sin(1) ~ peak
    assert mon["peak_von_mises"]["time"] == pytest.approx(np.pi / 2 * 1e-3, abs=1e-5)
    assert s["energy"] == {"kinetic": 3.0, "strain": 1.0}
    text = post.format_summary(s)
    for header in ("max von Mises [Pa]", "peak |R| [N]", "peak |u| [m]", "peak von Mises [Pa]"):
        assert header in text


def test_ice_only_file_summarises(synthetic, tmp_path):
    """No structure, no loads: ice damage (volume-weighted mean by hand) and energies."""
    path = tmp_path / "pd.h5"
    rng = np.random.default_rng(3)
    with ResultsWriter(path) as w:
        x0 = _ice(w, rng)
        damage = rng.uniform(0.0, 1.0, len(x0))
        w.write_frame(0.0, {"floe": {"u": np.zeros_like(x0), "v": np.zeros_like(x0),
                                     "damage": damage}})
        w.append_history("energy", 0.0, {"kinetic": 2.5, "dissipated": 0.25})
    with h5py.File(path, "r") as f:
        vol = f["ice/floe/volume"][()]
    s = post.summarize(post.load_results(path))
    assert s["loads"] == {} and s["structures"] == {}
    assert s["ice"]["floe"]["max_damage"] == damage.max()
    assert s["ice"]["floe"]["mean_damage"] == pytest.approx(np.sum(vol * damage) / vol.sum())
    assert s["energy"] == {"dissipated": 0.25, "kinetic": 2.5}
    assert "no structure" in post.format_summary(s)


def test_projection_plane_is_that_of_the_two_largest_extents():
    x = np.array([[0, 0, 0], [0.1, 2.0, 1.0]])
    assert post.projection_axes(x) == (1, 2)


def test_bad_files_exit_2_without_traceback(tmp_path, capsys):
    """Missing, non-HDF5 and foreign HDF5 files: exit 2, one paragraph naming the file."""
    text = tmp_path / "notes.h5"
    text.write_text("not HDF5\n")
    foreign = tmp_path / "foreign.h5"
    with h5py.File(foreign, "w") as f:
        f["data"] = np.arange(3)
    for path, words in ((tmp_path / "missing.h5", "no such results file"),
                        (text, "not an HDF5 file"), (foreign, "not a pdfem results file")):
        rc, out, err = run_post(capsys, path, "--json")
        assert rc == 2 and out == ""
        assert "Traceback" not in err and str(path) in err and words in err
        assert len(err.strip().splitlines()) == 1


def test_run_without_case_runs_the_demo_and_summarises(tiny_case, tmp_path, monkeypatch, capsys):
    """``pdfem run`` with no case: the demo (here the tiny case in its place) into
    results/demo_ice_sheet_panel/, then the post summary and where the files are."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(cli_run, "demo_case_file", lambda: contextlib.nullcontext(tiny_case))
    capsys.readouterr()
    assert cli.main(["run"]) == 0
    out = capsys.readouterr().out
    h5 = Path("results/demo_ice_sheet_panel/results.h5")
    assert h5.is_file() and h5.with_suffix(".xdmf").is_file()
    assert "Ice force on structure 'cyl'" in out and str(h5.with_suffix(".xdmf")) in out


def test_builtin_demo_case_is_installed_and_valid():
    """The demo case is package data of pdfem.models and passes validation."""
    with cli_run.demo_case_file() as path:
        case = load_case(path)
    assert {s.name for s in case.structures} == {"panel"} and len(case.ice) == 1
