"""Every case file in ``models/`` runs small, and 1 and 2 MPI ranks give the same answer.

Each case is shortened to two frames of at most 0.5 ms (the first millisecond of each: the demo's
ice strikes its panel, the milling propeller starts to spin up, the icebreakers' water and
gravity act on the floating sheet and the hull before the bow arrives). The serial run
(reference) must write a readable results file with finite fields; the same shortened cases
run under ``mpiexec -n 2`` (one launch for all of them) must then agree with it: every ice,
structure and history array to 1e-10 of its largest value, damage identical (the contract of
docs/parallel.md: 1 and N ranks agree to round-off).
"""

from __future__ import annotations

import dataclasses
import textwrap
from pathlib import Path

import h5py
import numpy as np
import pytest

from pdfem.case.schema import load_case
from pdfem.output import read_results
from pdfem.run.driver import run_case

from support.mpi import run_script

ROOT = Path(__file__).resolve().parents[2]
MODELS = sorted((ROOT / "models").glob("*.toml"))
TOL = 1e-10
"""Relative tolerance (of an array's largest value) of positions and displacements between 1
and 2 ranks: the sums over ranks change only the rounding."""
RATE_TOL = 1e-8
"""The same for velocities, forces and energies. Round-off lives in the lattice's highest modes
(frequency up to 2 / dt), where a displacement difference of 1e-16 of the largest is a
velocity or force difference 2 / dt x |u| / |v| times larger relative to theirs: the
four-point beam after 2 ms differs between 1 and 2 ranks by 2e-11 in u, 1.8e-9 in v and
1.3e-10 in the noses' force (after 4 ms: 7e-11 in u, 1.3e-8 in v)."""

SCRIPT = textwrap.dedent('''
    """Run the given case files shortened (see shorten) into OUT/<stem>, on this MPI world."""
    import dataclasses, sys
    from pathlib import Path
    from pdfem.case.schema import load_case
    from pdfem.run.driver import run_case

    def shorten(case):
        frame = min(case.run.output_interval, 0.5e-3)
        return dataclasses.replace(case, run=dataclasses.replace(
            case.run, end_time=2 * frame, output_interval=frame))

    out = Path(sys.argv[1])
    for path in sys.argv[2:]:
        run_case(shorten(load_case(path)), out / Path(path).stem, quiet=True)
''')


def shorten(case):
    """``case`` ending after two frames of at most 0.5 ms each (as ``SCRIPT`` does)."""
    frame = min(case.run.output_interval, 0.5e-3)
    return dataclasses.replace(case, run=dataclasses.replace(case.run, end_time=2 * frame,
                                                             output_interval=frame))


@pytest.fixture(scope="module")
def two_ranks(tmp_path_factory):
    """The directory holding every model case's shortened run on 2 ranks (one launch)."""
    out = tmp_path_factory.mktemp("mpi_models")
    script = out / "run_models.py"
    script.write_text(SCRIPT)
    run_script(script, 2, out, *MODELS, timeout=900)
    return out


def _largest(arrays) -> float:
    """The largest finite magnitude of the floating-point arrays among ``arrays``."""
    return max((float(np.abs(a[np.isfinite(a)]).max(initial=0.0)) for a in arrays
                if np.issubdtype(a.dtype, np.floating)), default=0.0)


def _assert_close(got: np.ndarray, ref: np.ndarray, where: str, scale: float | None = None) -> None:
    """``got`` equals ``ref`` to :data:`TOL` of ``scale`` (default: ``ref``'s largest value)."""
    assert got.shape == ref.shape, where
    if not np.issubdtype(ref.dtype, np.floating):
        np.testing.assert_array_equal(got, ref, err_msg=where)
        return
    scale = _largest([ref]) if scale is None else scale
    tol = TOL if where.rsplit("/", 1)[-1] in ("x0", "u", "points", "time") else RATE_TOL
    np.testing.assert_allclose(got, ref, rtol=0, atol=tol * scale, err_msg=where)


@pytest.mark.slow
@pytest.mark.parametrize("path", MODELS, ids=[p.stem for p in MODELS])
def test_every_model_case_runs_small_and_two_ranks_agree(path, tmp_path, two_ranks):
    case = shorten(load_case(path))
    summary = run_case(case, tmp_path, quiet=True)
    with h5py.File(summary.results, "r") as f:
        assert f["meta"].attrs["units"] == "SI"
        assert f["time"].shape[0] == summary.frames == 3
        for body in case.ice:
            assert np.isfinite(f[f"ice/{body.name}/u"][...]).all()
        for st in case.structures:
            assert f[f"structure/{st.name}/u"].shape[0] == 3
            assert np.isfinite(f[f"structure/{st.name}/u"][...]).all()
    assert summary.results.with_suffix(".xdmf").is_file()

    ref = read_results(summary.results)
    got = read_results(two_ranks / path.stem / "results.h5")
    assert (ref["meta"]["ranks"], got["meta"]["ranks"]) == (1, 2)
    np.testing.assert_array_equal(got["time"], ref["time"])
    compared = 0
    for group in ("ice", "structure"):
        assert sorted(got[group]) == sorted(ref[group])
        for name, fields in ref[group].items():
            for key, a in fields.items():
                if key == "damage":
                    np.testing.assert_array_equal(got[group][name][key], a, err_msg=name)
                elif key != "cell_type":
                    _assert_close(got[group][name][key], a, f"{group}/{name}/{key}")
                compared += 1
    # the 2-rank run writes the partition's history (parallel/<body>) besides the serial ones
    assert set(ref["histories"]) <= set(got["histories"])
    for name, rows in ref["histories"].items():
        # a history's columns share a scale: the energy residual is a small difference of the
        # energies, rounded at their size
        scale = _largest(a for key, a in rows.items() if key != "time")
        for key, a in rows.items():
            _assert_close(got["histories"][name][key], a, f"histories/{name}/{key}",
                          None if key == "time" else scale)
            compared += 1
    assert compared > 10
