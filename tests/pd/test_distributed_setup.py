"""The distributed set-up (pdfem.pd.layout.setup) builds exactly the global set-up's parts.

Reference: the global set-up of the same body in the same process (every rank builds the whole
body with IceBody.from_shape and keeps its part, pdfem.pd.layout.halo.DistributedIce with the
same box partition). For a box, a cylinder with an oblique axis, a two-body case (a box and
a sphere) and a closed surface mesh (an oblique octahedron), on 2 and 3 ranks, every rank's local arrays are identical: global numbers, reference
positions, pair lists, bond lengths, weights (cubic influence function and surface correction)
and weighted volumes m, and the halo plans. A notched bar pulled apart on the distributed
set-up agrees with the serial run to 1e-10 relative (measured: identical) with the same broken
bonds, and its stable step equals the serial one; its checkpoint (each rank's local state) is
the serial body's, and a fresh set-up restored from it continues bit for bit. Memory: on a 216,000-particle block each of
3 ranks grows its peak resident set during the set-up by less than 0.6 times what building the
whole body (the global set-up, on every rank) grows it. One numba thread per process (the pair loops'
chunks would otherwise differ between a rank's list and the whole body's, at round-off). Run
as ``mpiexec -n K`` subprocesses with a timeout.
"""

from __future__ import annotations

import os
import textwrap

import pytest

from support.mpi import run_script

EXACT = textwrap.dedent('''
    import numpy as np
    from pdfem.parallel.comm import world
    from pdfem.pd.body import IceBody
    from pdfem.pd.layout.setup import setup_partition
    from pdfem.pd.layout.split import split_body
    from pdfem.pd.materials.lps import IceMaterial
    from pdfem.geometry.shapes import Box, ClosedSurface, Cylinder, Sphere
    from pdfem.run.parallel import warm_before_ranks

    comm = world()
    warm_before_ranks(comm)
    mat = IceMaterial(density=900.0, youngs_modulus=4e9, poisson_ratio=0.3, fracture_energy=1.0)
    dx = 0.01
    delta = 3.015 * dx

    def same(name, shape):
        glob = IceBody.from_shape(name, shape, mat, dx, delta)
        census, part = setup_partition(shape, dx, delta, comm.size)
        local = IceBody.from_shape(name, shape, mat, dx, delta, comm=comm)
        plan = local.layout.plan
        ijk = np.rint((glob.x0 - shape.bounds()[0]) / dx - 0.5).astype(np.int64)
        r = split_body(glob, part.owner(ijk), comm)
        p = r.layout.plan
        checks = [census.n == glob.n, np.array_equal(plan.local, p.local),
                  np.array_equal(plan.owned, p.owned), np.array_equal(local.gid, r.gid)]
        for key in ("x0", "row_ptr", "nbr", "xi_len", "weight", "m", "vol"):
            checks.append(np.array_equal(getattr(local, key), getattr(r, key)))
        checks.append(sorted(plan.send) == sorted(p.send) and sorted(plan.recv) == sorted(p.recv))
        checks += [np.array_equal(plan.send[q], p.send[q]) for q in plan.send]
        checks += [np.array_equal(plan.recv[q], p.recv[q]) for q in plan.recv]
        ok = comm.allgather(all(bool(c) for c in checks))
        if comm.rank == 0:
            print(f"EXACT {name} ranks={comm.size} n={glob.n} {part.name} same={all(ok)}")

    same("box", Box((0, 0, 0), (0.2, 0.12, 0.08)))
    same("cylinder", Cylinder((0.0, 0.0, 0.0), (0.3, 0.2, 1.0), 0.07, 0.15))
    # two bodies, each split over all ranks on its own
    same("floe", Box((0, 0, 0), (0.16, 0.1, 0.05)))
    same("ball", Sphere((0.3, 0.05, 0.05), 0.06))
    # a closed surface mesh (an oblique octahedron, lattice planes through its vertices)
    verts = np.array([[0.0, 0.06, 0.04], [0.2, 0.06, 0.04], [0.1, 0.0, 0.04], [0.1, 0.13, 0.04],
                      [0.1, 0.06, 0.0], [0.07, 0.05, 0.1]])
    tris = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4],
                     [0, 2, 5], [2, 1, 5], [1, 3, 5], [3, 0, 5]])
    same("octahedron", ClosedSurface(verts, tris))

    # a notched bar pulled apart: the distributed set-up against the serial body
    bar = Box((0, 0, 0), (24 * 0.005, 8 * 0.005, 6 * 0.005))
    d = 0.005

    def regions(b):
        b.cut_crack((12 * d, 0, 0), (1, 0, 0), (11 * d, -1, -1), (13 * d, 1, 2 * d))
        x = b.x0[:, 0]
        b.add_velocity_constraint(x < 2 * d, (-0.5, 0, 0))
        b.add_velocity_constraint(x > 22 * d, (0.5, 0, 0))

    ref = IceBody.from_shape("bar", bar, mat, d, 3.015 * d)
    regions(ref)
    dist = IceBody.from_shape("bar", bar, mat, d, 3.015 * d, comm=comm)
    regions(dist)
    dt = 0.8 * ref.stable_time_step()
    same_dt = dist.stable_time_step() == ref.stable_time_step()
    ref.start()
    dist.start()
    broken_ref = broken = 0
    for step in range(300):
        broken_ref += ref.step(dt)
        broken += dist.step(dt)
        if step == 149:  # a checkpoint: each rank's local state is the serial body's there
            state = dist.checkpoint_state()
            lay, whole = dist.checkpoint_layout(), ref.checkpoint_state()
            i, j = lay.bond_ends()
            keys = np.repeat(np.arange(ref.n), np.diff(ref.row_ptr)) * ref.n + ref.nbr
            order = np.argsort(keys)
            at = order[np.searchsorted(keys[order], i * ref.n + j)]
            own, mine = lay.owned, lay.counted
            ok = all(np.array_equal(state[k][own], whole[k][lay.gid[own]])
                     for k in ("y", "v", "f", "theta"))
            ok = ok and np.array_equal(state["broken"][mine], whole["broken"][at[mine]])
            same_state = comm.allreduce_sum(int(not ok)) == 0
    y = dist.gather(dist.y)
    dmg = dist.gather(dist.damage())
    # restart from the checkpoint on a freshly set-up body: the same steps, bit for bit
    again = IceBody.from_shape("bar", bar, mat, d, 3.015 * d, comm=comm)
    regions(again)
    again.restore_state(state)
    for _ in range(150):
        again.step(dt)
    y2 = again.gather(again.y)
    if comm.rank == 0:
        err = np.abs(y - ref.y).max() / np.abs(ref.y - ref.x0).max()
        print(f"RUN ranks={comm.size} broken={broken} ref={broken_ref} err={err:.3e} "
              f"same_damage={bool(np.array_equal(dmg, ref.damage()))} same_dt={same_dt} "
              f"same_state={same_state} restart_same={bool(np.array_equal(y2, y))}")
''')

MEMORY = textwrap.dedent('''
    import resource
    from types import SimpleNamespace
    import numpy as np
    from pdfem.parallel.comm import world
    from pdfem.pd.body import IceBody
    from pdfem.pd.layout.halo import HaloPlan
    from pdfem.pd.materials.lps import IceMaterial
    from pdfem.geometry.shapes import Box
    from pdfem.run.parallel import warm_before_ranks

    def hwm():
        with open("/proc/self/status") as f:
            return next(int(l.split()[1]) * 1024 for l in f if l.startswith("VmHWM"))

    comm = world()
    warm_before_ranks(comm)
    mat = IceMaterial(density=900.0, youngs_modulus=4e9, poisson_ratio=0.3, fracture_energy=1.0)
    dx = 0.01
    block = Box((0, 0, 0), (0.6, 0.6, 0.6))
    before = hwm()
    if comm.size == 1:  # the reference: the whole body, as the global set-up builds on every rank
        local = IceBody.from_shape("block", block, mat, dx, 3.015 * dx)
        plan = HaloPlan(None, np.ones(local.n, dtype=bool), None, {}, {})
        census = local
    else:
        local = IceBody.from_shape("block", block, mat, dx, 3.015 * dx, comm=comm)
        plan = local.layout.plan
        census = SimpleNamespace(n=local.n_global)
    grown = hwm() - before
    bonds = comm.allreduce_sum(np.int64(plan.owned[np.repeat(np.arange(local.n),
                                                             np.diff(local.row_ptr))].sum()))
    largest = max(a.nbytes for a in (local.x0, local.nbr, local.xi_len, local.weight, local.m))
    figures = comm.gather((grown, largest, local.n))
    if comm.rank == 0:
        print(f"MEMORY n={census.n} bonds={int(bonds)} global_bond_bytes={16 * int(bonds)} "
              f"grown_max={max(f[0] for f in figures)} "
              f"largest_array_max={max(f[1] for f in figures)} "
              f"local_max={max(f[2] for f in figures)}")
''')


def _run(tmp_path, text: str, ranks: int) -> str:
    script = tmp_path / "script.py"
    script.write_text(text)
    env = dict(os.environ, NUMBA_NUM_THREADS="1")
    r = run_script(script, ranks, timeout=600, env=env)
    return r.stdout


@pytest.mark.slow
@pytest.mark.parametrize("ranks", [2, 3])
def test_distributed_setup_equals_global_setup(tmp_path, ranks):
    out = _run(tmp_path, EXACT, ranks)
    exact = [line for line in out.splitlines() if line.startswith("EXACT")]
    assert len(exact) == 5, out
    for line in exact:
        assert line.endswith("same=True"), line
    run = dict(kv.split("=") for kv in next(
        line for line in out.splitlines() if line.startswith("RUN")).split()[1:])
    assert int(run["broken"]) == int(run["ref"]) > 0
    assert float(run["err"]) <= 1e-10
    assert run["same_damage"] == "True"
    assert run["same_dt"] == "True"
    assert run["same_state"] == "True"  # each rank's checkpoint state is the serial body's
    assert run["restart_same"] == "True"  # a restart on as many ranks continues bit for bit


@pytest.mark.slow
def test_no_rank_holds_the_global_body(tmp_path):
    """216,000 particles: each of 3 ranks grows its peak resident set during the set-up by less
    than 0.6 times what the global set-up (the whole body, which every rank builds today) grows
    it, and no rank's array is as large as half the whole body's bond-length array."""
    figures = {}
    for ranks in (1, 3):
        out = _run(tmp_path, MEMORY, ranks)
        line = next(line for line in out.splitlines() if line.startswith("MEMORY"))
        figures[ranks] = {k: int(v) for k, v in (kv.split("=") for kv in line.split()[1:])}
    whole, split = figures[1], figures[3]
    assert whole["n"] == split["n"] == 216_000
    assert whole["bonds"] == split["bonds"]
    assert split["grown_max"] < 0.6 * whole["grown_max"], figures
    assert split["largest_array_max"] < 0.5 * 8 * split["bonds"], figures
    assert split["local_max"] < 0.6 * split["n"], figures


def test_lattice_planes_are_the_lattice_bit_for_bit():
    """Any plane block generated from the axes equals the rows of the whole lattice."""
    import numpy as np

    from pdfem.geometry.lattice import lattice_axes, lattice_plane, lattice_points

    lo, hi, dx = np.array([0.013, -0.2, 0.1]), np.array([0.113, 0.05, 0.23]), 0.0101
    whole = lattice_points(lo, hi, dx)
    axes = lattice_axes(lo, hi, dx)
    nx, ny, nz = (len(a) for a in axes)
    grid = whole.reshape(nx, ny, nz, 3)
    for i in (0, nx // 2, nx - 1):
        assert np.array_equal(lattice_plane(axes, i), grid[i].reshape(-1, 3))
        assert np.array_equal(lattice_plane(axes, i, (2, 7), (1, 4)),
                              grid[i, 2:7, 1:4].reshape(-1, 3))


def test_box_partition_balances_a_box_exactly():
    """For a box every plane holds as many particles: 4 ranks on a 12 x 12 x 20 lattice get
    720 particles each, and each lattice point's owner is the box that holds its indices."""
    import numpy as np

    from pdfem.parallel.box_partition import choose_box_partition

    counts = [np.full(12, 240), np.full(12, 240), np.full(20, 144)]
    part = choose_box_partition(counts, 4, 3)
    ijk = np.stack(np.meshgrid(np.arange(12), np.arange(12), np.arange(20), indexing="ij"),
                   -1).reshape(-1, 3)
    owner = part.owner(ijk)
    assert np.array_equal(np.bincount(owner, minlength=4), [720] * 4)
    for r in range(4):
        lo, hi = part.box(r)
        inside = np.all((ijk >= lo) & (ijk < hi), axis=1)
        assert np.array_equal(inside, owner == r)
