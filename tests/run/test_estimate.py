"""Memory per rank and per node, and ``pdfem run --estimate`` (issue 17, items 2 and 6).

References: hand counts on small lattices (nearest-neighbour horizon, one cut), the exact
bond-list counts of :func:`pdfem.parallel.partition.partition_stats` on a real lattice and
partition (an independent count: the bonds themselves), and the seed plate's halo of the MPI
partition model in BENCHMARKS.md (600 x 300 x 8 particles: 7,200 on 2 ranks, 10,832 on 4).
The large case below (48 GiB of ice, more than this 24 GB machine) is sized, never run.
"""

from __future__ import annotations

import os

import numpy as np
import pytest

from pdfem.case.schema import load_case
from pdfem.cli.main import main
from pdfem.geometry.lattice import fill
from pdfem.geometry.shapes import Box
from pdfem.parallel.nodes import block_layout
from pdfem.parallel.partition import grid_partition, partition_stats
from pdfem.pd.bonds.search import cell_pairs
from pdfem.run.estimates import BYTES_PER_PAIR, BYTES_PER_PARTICLE, FIXED_BYTES, split_lattice
from pdfem.run.preflight import estimate_rank_memory, node_needs, nodes_needed
from pdfem.run.sizing import parse_bytes

from support.cli import run_ok

LARGE = """
# a 20 m x 20 m x 1 m ice box at dx = 2.5 cm: 25.6 M particles, 1.51 G bonds, 48 GiB of ice;
# for sizing only (pdfem run --estimate): it does not fit on one 24 GB machine
[run]
end_time = 0.01
[[ice]]
name = "box"
dx = 0.025
shape = { box = { min = [0.0, 0.0, 0.0], max = [20.0, 20.0, 1.0] } }
"""

SMALL = """
[run]
end_time = 1.0e-4
[[ice]]
name = "box"
dx = 0.01
shape = { box = { min = [0.0, 0.0, 0.0], max = [0.12, 0.06, 0.04] } }
"""


def _case(tmp_path, text, name="case.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_split_by_hand_nearest_neighbours():
    """4 x 2 x 2 points, nearest neighbours only (horizon 1 dx), cut into 2 along x: each rank
    owns 2 x 2 x 2 = 8, its halo is the facing plane (2 x 2 = 4), its bonds the 12 inside
    its block (3 directions x 4 lines) plus the 4 crossing the cut."""
    owned, halo, bonds = split_lattice((4, 2, 2), (2, 1, 1), 1.0)
    assert owned.tolist() == [8, 8] and halo.tolist() == [4, 4] and bonds.tolist() == [16, 16]


def test_split_matches_the_bond_list():
    """Owned, halo and bonds-with-an-owned-end of every rank of grid splits equal the counts
    from the real lattice, its bonds (pdfem.pd.bonds.search) and pdfem.parallel.partition (grids
    that cut at whole lattice planes, as the estimate assumes)."""
    counts, dx, delta = (16, 12, 8), 1.0, 3.015
    x = fill(Box((0, 0, 0), counts), dx)
    perm, row_ptr, nbr = cell_pairs(x, delta)
    x = x[perm]
    i = np.repeat(np.arange(len(x)), np.diff(row_ptr))
    for grid in ((2, 1, 1), (4, 3, 1), (2, 2, 2)):
        owner = grid_partition(x, grid)
        st = partition_stats(owner, row_ptr, nbr, int(np.prod(grid)))
        o, h, b = split_lattice(counts, grid, delta / dx)
        touched = [int(((owner[i] == r) | (owner[nbr] == r)).sum()) for r in range(len(o))]
        assert o.tolist() == st.owned.tolist()
        assert h.tolist() == st.halo.tolist()
        assert b.tolist() == touched


def test_seed_plate_halo():
    """The partition model of BENCHMARKS.md (bond-list counts): the 600 x 300 x 8 plate has a
    halo of 7,200 particles per rank on 2 ranks and 10,832 on 4 (2 x 2 grid)."""
    assert split_lattice((600, 300, 8), (2, 1, 1), 3.015)[1].max() == 7200
    assert split_lattice((600, 300, 8), (2, 2, 1), 3.015)[1].max() == 10832


def test_rank_and_node_memory_arithmetic(tmp_path):
    """A 12 x 6 x 4 box of particles on 2 ranks: owned 144 each, halo 3 planes of 6 x 4 = 72;
    memory = fixed + particles x 240 B + bonds x 30 B; today's global set-up adds the whole
    body to each rank; a node needs the sum of its ranks."""
    case = load_case(_case(tmp_path, SMALL))
    whole = estimate_rank_memory(case, 1, False)[0]
    assert (whole.owned, whole.halo) == (288, 0)
    body = whole.bytes - FIXED_BYTES
    assert body == 288 * BYTES_PER_PARTICLE + whole.bonds * BYTES_PER_PAIR
    dist = estimate_rank_memory(case, 2, True)
    glob = estimate_rank_memory(case, 2, False)
    _, _, bonds = split_lattice((12, 6, 4), (2, 1, 1), 3.015)
    for r in range(2):
        assert (dist[r].owned, dist[r].halo, dist[r].bonds) == (144, 72, bonds[r])
        part = 216 * BYTES_PER_PARTICLE + bonds[r] * BYTES_PER_PAIR
        assert dist[r].bytes == FIXED_BYTES + part
        assert glob[r].bytes == FIXED_BYTES + body + part
    assert node_needs(dist, [0, 0]) == [dist[0].bytes + dist[1].bytes]
    assert block_layout(8, 3) == [0, 0, 0, 1, 1, 1, 2, 2]


def test_large_case_fits_four_nodes_not_one(tmp_path):
    """The 48 GiB box on 8 ranks, distributed set-up: 4 nodes of 24 GB hold it (2 ranks, about
    12.5 GiB each), one node does not, and 3 nodes (3 ranks per node) is the fewest; with
    today's global set-up every rank holds the whole body, so no number of nodes fits."""
    case = load_case(_case(tmp_path, LARGE))
    ranks = estimate_rank_memory(case, 8, True)
    assert sum(r.owned for r in ranks) == 800 * 800 * 40
    node = 24 * 10**9
    assert max(node_needs(ranks, block_layout(8, 4))) <= node
    assert max(node_needs(ranks, block_layout(8, 1))) > 2 * node
    assert nodes_needed(ranks, node) == (3, 3)
    assert nodes_needed(estimate_rank_memory(case, 8, False), node) is None


@pytest.mark.slow
def test_estimate_cli_accepts_and_refuses(tmp_path, capsys):
    """``--estimate`` with 8 ranks: exit 0 on 4 nodes, exit 2 on one with a message naming the
    file, the need per node and rank and the nodes needed; nothing is written into --out."""
    path = _case(tmp_path, LARGE, "large_box.toml")
    out = tmp_path / "out"
    common = ["run", str(path), "--estimate", "--ranks", "8", "--node-memory", "24GB",
              "--setup", "distributed", "--out", str(out)]
    assert main(common + ["--nodes", "4"]) == 0
    text = capsys.readouterr().out
    assert "8 ranks on 4 nodes" in text and "fits" in text and "bond-steps/s" in text
    assert "node 3: 2 ranks" in text and "projected wall time" in text
    assert main(common + ["--nodes", "1"]) == 2
    cap = capsys.readouterr()
    assert "large_box.toml" in cap.err and "node 0 (its 8 ranks)" in cap.err
    assert "it needs 3 nodes of this size (3 ranks per node)" in cap.err
    assert "22.4 GiB is available" in cap.err  # 24 GB
    assert main(["run", str(path), "--estimate", "--ranks", "8", "--nodes", "4",
                 "--node-memory", "24GB", "--setup", "global"]) == 2
    assert "more ranks do not help" in capsys.readouterr().err
    assert not out.exists()


def test_calibration_step_is_the_run_step(tmp_path):
    """The ice step of --estimate is the run's: for a body no larger than the stable-step piece
    (12 x 6 x 4 particles) the piece is the body, so safety_factor x its stable step
    (pdfem.run.build_ice) is reproduced exactly; the rate is positive."""
    from pdfem.run.build_ice import build_ice_body
    from pdfem.run.sizing import calibrate
    case = load_case(_case(tmp_path, SMALL))
    body = build_ice_body(case.ice[0], case.run)
    cal = calibrate(case, seconds=0.05)
    assert cal.ice_step == pytest.approx(case.run.safety_factor * body.stable_time_step(),
                                         rel=1e-12)
    assert cal.bond_steps_per_s > 0


def test_bad_node_memory():
    """--node-memory takes a number with a unit; GB is 10^9, GiB and G 2^30."""
    assert parse_bytes("24GB") == 24 * 10**9 and parse_bytes("2G") == 2 * 2**30
    assert parse_bytes("2.5e10") == 25 * 10**9
    assert main(["run", "x.toml", "--estimate", "--node-memory", "lots"]) == 2


def test_more_ranks_than_planes(tmp_path):
    """12 x 6 x 4 particles cannot be cut into 1,000 non-empty grid cells: a clear refusal
    naming the file and the body's dx."""
    from pdfem.errors import InputError
    path = _case(tmp_path, SMALL)
    with pytest.raises(InputError) as err:
        estimate_rank_memory(load_case(path), 1000, True)
    assert str(path) in err.value.text() and "ice[0].dx" in err.value.text()



@pytest.mark.slow
def test_estimate_on_two_mpi_ranks(tmp_path):
    """``mpiexec -n 2 pdfem run CASE --estimate``: one table with both ranks on one node (the
    shared-memory split of this machine), exit 0, nothing written."""
    path = _case(tmp_path, SMALL)
    r = run_ok("run", path, "--estimate", "--out", tmp_path / "out", ranks=2, timeout=300,
               env={**os.environ, "NUMBA_NUM_THREADS": "1"})
    assert "2 ranks on 1 node" in r.stdout and "node 0: 2 ranks" in r.stdout
    rows = [line.split() for line in r.stdout.splitlines() if line[:6].strip().isdigit()]
    assert [row[:2] for row in rows] == [["0", "0"], ["1", "0"]]
    assert r.stdout.count("pdfem run --estimate") == 1
    assert not (tmp_path / "out").exists()
