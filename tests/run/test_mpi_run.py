"""`mpiexec -n K pdfem run CASE` gives the serial answer, for K = 2 and 3 (3: an uneven split).

Reference: the serial run of the same case. Two coupled cases: the seed's rigid cylinder
striking an ice plate that breaks (coarsened), and ice pushed against the elastic hull panel
(the structure subcycling, replicated on every rank). Particle displacements and the load
histories agree with the serial run to 1e-10 relative, damage fields are identical. Run as
subprocesses with a timeout from the ordinary suite.
"""

from __future__ import annotations


import numpy as np
import pytest

from pdfem.output import read_results

from support.cases import CYLINDER, PANEL_BODIES
from support.cli import run_ok, run_pdfem


PANEL = """
[run]
end_time = 1.0e-3
output_interval = 5.0e-4
""" + PANEL_BODIES + """
[[monitor]]
name = "centre"
structure = "panel"
point = [1.0, 0.6, 0.0]
"""


@pytest.mark.slow
@pytest.mark.parametrize("text, body, structure, split", [(CYLINDER, "plate", "cylinder", (2, 3)),
                                                          (PANEL, "floe", "panel", (3,))],
                         ids=["cylinder_plate", "hull_panel"])
def test_one_two_and_three_ranks_agree(tmp_path, text, body, structure, split):
    """The hull panel runs on 3 ranks only (the uneven split): its 2-rank run is the demo's
    (tests/forces/test_mpi_short_range.py)."""
    case = tmp_path / "case.toml"
    case.write_text(text)
    results = {}
    for ranks in (1, *split):
        r = run_ok("run", case, "--out", tmp_path / f"r{ranks}", "--quiet", ranks=ranks, timeout=600)
        results[ranks] = read_results(tmp_path / f"r{ranks}" / "results.h5")
    ref = results[1]
    # the whole run, bonds breaking where the floe is crushed against the panel: the contact
    # impulses reach the structure summed in global particle order on any split, so the runs
    # agree bit for bit (1e-10 is the tolerance the ice's own sums over ranks allow)
    tol = 1e-10
    u_ref = ref["ice"][body]["u"]
    f_ref = ref["histories"][f"loads/{structure}"]["force"]
    assert np.abs(f_ref).max() > 1e3  # N: there was contact
    assert ref["ice"][body]["damage"][-1].max() > 0  # bonds broke
    for ranks in split:
        r = results[ranks]
        assert r["meta"]["ranks"] == ranks
        np.testing.assert_allclose(r["ice"][body]["u"], u_ref, rtol=0,
                                   atol=tol * np.abs(u_ref).max())
        np.testing.assert_array_equal(r["ice"][body]["damage"], ref["ice"][body]["damage"])
        np.testing.assert_allclose(r["histories"][f"loads/{structure}"]["force"], f_ref,
                                   rtol=0, atol=tol * np.abs(f_ref).max())
        su = ref["structure"][structure]["u"]
        np.testing.assert_allclose(r["structure"][structure]["u"], su, rtol=0,
                                   atol=tol * np.abs(su).max())
        # the contact pressure per facet: summed contact by contact in the same order
        cp = ref["structure"][f"{structure}.contact"]["contact_pressure"]
        assert cp.max() > 0
        np.testing.assert_allclose(r["structure"][f"{structure}.contact"]["contact_pressure"],
                                   cp, rtol=0, atol=tol * cp.max())


@pytest.mark.slow
def test_per_rank_ice_files_read_as_one_run(tmp_path):
    """``run.output_per_rank``: on 3 ranks each rank writes its own particles to
    results.rank<R>.h5 (with its XDMF) and rank 0 the rest to results.h5; read_results puts the
    ice back in global order, equal to the serial run (reference) to 1e-10 with identical
    damage, and ``pdfem post`` reads it like any results file."""
    case = tmp_path / "case.toml"
    case.write_text(CYLINDER.replace("output_interval = 4.0e-4",
                                     "output_interval = 4.0e-4\noutput_per_rank = true"))
    for ranks in (1, 3):
        run_ok("run", case, "--out", tmp_path / f"r{ranks}", "--quiet", ranks=ranks, timeout=600)
    assert not (tmp_path / "r1" / "results.rank0.h5").exists()  # one rank: one file
    for k in range(3):
        assert (tmp_path / "r3" / f"results.rank{k}.h5").is_file()
        assert (tmp_path / "r3" / f"results.rank{k}.xdmf").is_file()
    ref = read_results(tmp_path / "r1" / "results.h5")
    got = read_results(tmp_path / "r3" / "results.h5")
    assert got["meta"]["ice_per_rank"] == 3
    np.testing.assert_array_equal(got["time"], ref["time"])
    a, b = ref["ice"]["plate"], got["ice"]["plate"]
    assert sorted(a) == sorted(b)
    np.testing.assert_array_equal(b["x0"], a["x0"])
    np.testing.assert_allclose(b["u"], a["u"], rtol=0, atol=1e-10 * np.abs(a["u"]).max())
    np.testing.assert_array_equal(b["damage"], a["damage"])
    assert a["damage"][-1].max() > 0
    run_ok("post", tmp_path / "r3" / "results.h5", "--json", timeout=300)


def test_bad_input_on_several_ranks_exits_2_without_traceback(tmp_path):
    """A bad case value under mpiexec: exit 2, the message names the field, no traceback."""
    case = tmp_path / "bad.toml"
    case.write_text(CYLINDER.replace("output_interval = 4.0e-4",
                                     "output_interval = 4.0e-4\noutput_per_rank = \"yes\""))
    r = run_pdfem("run", case, "--out", tmp_path / "o", ranks=2, timeout=120)
    assert r.returncode == 2
    assert "run.output_per_rank" in r.stderr and "Traceback" not in r.stderr


@pytest.mark.slow
def test_bench_mpi_reports_both_runs(tmp_path):
    """`pdfem bench mpi` (strong scaling of the distributed step) runs 1 and 2 ranks on the
    same plate and reports both, the partition of the 2-rank run with a halo (no timing is
    asserted: timings belong to BENCHMARKS.md)."""
    import json

    r = run_ok("bench", "mpi", "--n", "4000", "--json", timeout=600)
    res = json.loads(r.stdout)
    one, two = res["runs"]
    assert (one["ranks"], two["ranks"]) == (1, 2)
    assert one["n_pairs"] == two["n_pairs"] == res["n_pairs"] > 0
    assert one["halo_max"] == 0 and two["halo_max"] > 0
