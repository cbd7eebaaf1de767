"""Re-partitioning a split ice body mid-run (pdfem.pd.layout.rebalance) keeps the serial answer.

Reference: the serial run of the same body in the same process. On 2 and 3 ranks (3: uneven),
one mpiexec launch each, with one numba thread per rank:

1. a notched bar pulled apart (pre-crack, two prescribed regions), split badly on purpose (by x,
   70 % of the ranks' share on the low ranks), re-partitioned twice while it breaks: positions
   and damage identical to the serial run, the broken flags of the ranks' checkpoint states
   (in the serial pair order) the serial ones, the regions' reactions equal to 1e-12 relative; the imbalance (largest rank's
   bond work over the mean) falls from about 1.44 to 1.00;
2. a block of crushed ice with friction and a rate-dependent strength (Sec. ice failure law),
   from the distributed set-up, squeezed between a driven and a fixed face and re-partitioned
   twice: positions, damage, crushed bonds' rest stretch and shear slip identical;
3. a rigid plate driven into an ice plate's edge (contact, breaking) through the run's
   pdfem.run.balance.LoadBalance (rebalance_every = 20), starting with one rank empty or
   overloaded: contact force history and positions identical, re-partitions at steps 20, 40,
   60, the imbalance history above 1.3 before step 20 and at most 1.01 after; with
   rebalance_imbalance = 1.2 instead, the badly split body is re-partitioned at the first step
   and not again;
4. recursive coordinate bisection (pdfem.parallel.rcb) of 3000 weighted points on a coarse
   grid (many ties) gives the same owners from two different distributions over the ranks
   (no dependence on history), balanced to within one particle's weight;
5. short-range contact across a crack: a bar cut through, its halves thrown at each other at
   15 m/s each, re-partitioned every 20 steps while its faces press: positions identical to the
   serial run, the same number of contact pairs every step (up to 48), three re-partitions;
6. water: a plate floating too deep rises against linear drag, badly split, re-partitioned
   every 20 steps: positions identical to the serial run, the drag's dissipated energy and the
   water's potential energy equal to 1e-12 (the per-particle counters move with the
   particles).

Run as subprocesses with a timeout, so a broken MPI cannot hang the suite.
"""

from __future__ import annotations

import os
import textwrap

import pytest

from support.mpi import run_script

SCRIPT = textwrap.dedent('''
import time
import numpy as np
from pdfem.parallel.comm import SerialComm, world
from pdfem.parallel.rcb import rcb_owners
from pdfem.pd.layout.split import split_body
from pdfem.pd.body import IceBody
from pdfem.pd.materials.lps import IceMaterial
from pdfem.pd.failure.ice import IceFailure
from pdfem.geometry.shapes import Box

T0 = time.perf_counter()
comm = world()
dx = 0.005

def bonds_in_serial_order(dist, state, keys):
    """The bond arrays ``keys`` of the ranks' checkpoint states, in the serial pair order
    (sorted by global (i, j)), on rank 0."""
    lay = dist.checkpoint_layout()
    i, j = lay.bond_ends()
    c = lay.counted
    parts = comm.gather([i[c], j[c]] + [state[k][c] for k in keys])
    if comm.rank:
        return None
    cols = [np.concatenate([p[n] for p in parts]) for n in range(2 + len(keys))]
    order = np.lexsort((cols[1], cols[0]))
    return {k: cols[2 + n][order] for n, k in enumerate(keys)}

def report(tag, dist, ref, imb):
    y, d = dist.gather(dist.y), dist.gather(dist.damage())
    keys = ["broken"] + (["rest", "slip"] if ref.rest is not None else [])
    st = bonds_in_serial_order(dist, dist.checkpoint_state(), keys)
    R, Rr = dist.reactions(), ref.reactions()
    if comm.rank == 0:
        same = (np.array_equal(y, ref.y) and np.array_equal(d, ref.damage())
                and np.array_equal(st["broken"], ref.broken))
        if ref.rest is not None:
            same = (same and np.array_equal(st["rest"], ref.rest, equal_nan=True)
                    and np.array_equal(st["slip"], ref.shear.slip))
        err = np.abs(y - ref.y).max() / np.abs(ref.y - ref.x0).max()
        rerr = max(np.abs(R[k] - Rr[k]).max() / np.abs(Rr[k]).max() for k in Rr)
        print(f"RESULT {tag} ranks={comm.size} err={err:.3e} same={same} react={rerr:.3e} "
              f"broken={int(ref.broken.sum())} crushed={0 if ref.rest is None else int(np.isfinite(ref.rest).sum())} "
              f"imb0={imb[0]:.4f} imb1={imb[1]:.4f} imb2={imb[2]:.4f} layout={dist.layout_version}")

# 1. a notched bar pulled apart, poorly split (global set-up), re-partitioned twice mid-run
mat = IceMaterial(density=900.0, youngs_modulus=4e9, poisson_ratio=0.3, fracture_energy=1.0)
bar = Box((0, 0, 0), (24 * dx, 8 * dx, 6 * dx))
def regions(b):
    b.cut_crack((12 * dx, 0, 0), (1, 0, 0), (11 * dx, -1, -1), (13 * dx, 1, 2 * dx))
    x = b.x0[:, 0]
    b.add_velocity_constraint(x < 2 * dx, (-0.5, 0, 0))
    b.add_velocity_constraint(x > 22 * dx, (0.5, 0, 0))
    return b
ref = regions(IceBody.from_shape("bar", bar, mat, dx, 3.015 * dx))
dt = 0.8 * ref.stable_time_step()
x = ref.x0[:, 0]
owner = np.minimum((x / x.max() * comm.size * 0.7).astype(np.int32), comm.size - 1)
dist = split_body(regions(IceBody.from_shape("bar", bar, mat, dx, 3.015 * dx)), owner, comm)
ref.start(); dist.start()
imb = [dist.imbalance()]
for s in range(80):
    ref.step(dt); dist.step(dt)
    if s in (30, 60):
        dist.rebalance()
        imb.append(dist.imbalance())
report("bar", dist, ref, imb)

# 2. crushed ice with friction and a rate-dependent strength (distributed set-up), squeezed
ice = IceMaterial(density=900.0, youngs_modulus=4e9, poisson_ratio=0.3, fracture_energy=1.0,
                  compressive_strength=2e6, friction_angle=20.0, transition_rate=1e-2,
                  crushed_friction=0.3)
blk = Box((0, 0, 0), (10 * dx, 6 * dx, 6 * dx))
law = IceFailure.from_material(ice, 3.015 * dx)
def squeeze(b):
    z = b.x0[:, 2]
    b.add_velocity_constraint(z < dx, (0, 0, 1.0))
    b.fix(z > 5 * dx)
    return b
ref = squeeze(IceBody.from_shape("blk", blk, ice, dx, 3.015 * dx, failure=law))
dist = IceBody.from_shape("blk", blk, ice, dx, 3.015 * dx, comm=comm, failure=law)
squeeze(dist)
dt = 0.8 * ref.stable_time_step()
ref.start(); dist.start()
imb = [dist.imbalance()]
for s in range(40):
    ref.step(dt); dist.step(dt)
    if s in (15, 30):
        dist.rebalance()
        imb.append(dist.imbalance())
report("crush", dist, ref, imb)


# 3. a rigid plate driven into an ice plate (contact, breaking) through the run's load balance
# (pdfem.run.balance.LoadBalance: an imbalance above 1.2, and every 40 coupling steps)
from types import SimpleNamespace
from pdfem.coupling.contact import SurfaceContact
from pdfem.coupling.coupler import ContactPair, Coupler
from pdfem.motion.rigid import RigidBody
from pdfem.run.balance import LoadBalance

mat2 = IceMaterial(density=900.0, youngs_modulus=4e9, poisson_ratio=0.3, fracture_energy=2.0)
plate = Box((0, 0, 0), (0.2, 0.12, 0.03))
d2 = 0.01

def wall():
    pts = np.array([[0.06, 0.1151, -0.1], [0.14, 0.1151, -0.1], [0.14, 0.1151, 0.2],
                    [0.06, 0.1151, 0.2]])
    return RigidBody(pts, np.array([[0, 1, 2], [0, 2, 3]]), velocity=(0, -3.0, 0), name="w")

class Rows:
    def __init__(self):
        self.rows = []
    def append_history(self, group, t, row):
        self.rows.append((group, row["imbalance"], row["rebalanced"]))

def coupled(body, c):
    w = wall()
    pair = ContactPair("p", body, w, SurfaceContact(w, 0.5 * d2))
    dt = 0.8 * IceBody.stable_time_step(IceBody.from_shape("plate", plate, mat2, d2, 3.015 * d2))
    cp = Coupler([body], [w], [pair], dt, comm=c)
    cp.start()
    return cp, pair

ref = IceBody.from_shape("plate", plate, mat2, d2, 3.015 * d2)
cp_ref, pair_ref = coupled(ref, SerialComm())
y0 = ref.x0[:, 1]
owner = np.minimum((y0 / y0.max() * comm.size * 0.6).astype(np.int32), comm.size - 1)
dist = split_body(IceBody.from_shape("plate", plate, mat2, d2, 3.015 * d2), owner, comm)
cp, pair = coupled(dist, comm)
run = SimpleNamespace(rebalance_every=20, rebalance_imbalance=0.0)
setup = SimpleNamespace(bodies=[dist], coupler=cp)
balance = LoadBalance(SimpleNamespace(run=run, water=None, file="test"), setup, comm)
rows = Rows()
f, f_ref = [], []
for step in range(1, 61):
    cp_ref.step()
    cp.step()
    balance.after_step(step, step * cp.dt, rows)
    f.append(pair.force.copy())
    f_ref.append(pair_ref.force.copy())
y, dmg = dist.gather(dist.y), dist.gather(dist.damage())
if comm.rank == 0:
    f, f_ref = np.array(f), np.array(f_ref)
    moved = ",".join(str(k + 1) for k, r in enumerate(rows.rows) if r[2])
    print(f"RESULT coupled ranks={comm.size} same={np.array_equal(y, ref.y) and np.array_equal(dmg, ref.damage())} "
          f"err_f={np.abs(f - f_ref).max() / np.abs(f_ref).max():.3e} fmax={np.abs(f_ref).max():.4g} "
          f"broken={int(ref.broken.sum())} moved={moved} first={rows.rows[0][1]:.4f} "
          f"before={max(r[1] for r in rows.rows[:19]):.4f} "
          f"last={rows.rows[-1][1]:.4f} layout={dist.layout_version}")

# 5. short-range contact across a crack: a bar cut through at its middle, its halves thrown
# at each other, re-partitioned every 20 steps while the faces press (the contact's halo follows)
from pdfem.forces.short_range import ShortRangeContact

def halves(b):
    b.cut_crack((12 * dx, 0, 0), (1, 0, 0), (11 * dx, -1, -1), (13 * dx, 1, 1))
    b.v[:, 0] = np.where(b.x0[:, 0] < 12 * dx, 15.0, -15.0)
    return b

ref5 = halves(IceBody.from_shape("bar", bar, mat, dx, 3.015 * dx))
x5 = ref5.x0[:, 0]
owner5 = np.minimum((x5 / x5.max() * comm.size * 0.7).astype(np.int32), comm.size - 1)
dist5 = split_body(halves(IceBody.from_shape("bar", bar, mat, dx, 3.015 * dx)), owner5, comm)
src_ref, src = ShortRangeContact([ref5]), ShortRangeContact([dist5])
dt = 0.8 * ref5.stable_time_step()
cp5_ref = Coupler([ref5], [], [], dt, forces=[src_ref])
cp5 = Coupler([dist5], [], [], dt, forces=[src], comm=comm)
cp5_ref.start(); cp5.start()
balance = LoadBalance(SimpleNamespace(run=SimpleNamespace(rebalance_every=20, rebalance_imbalance=0.0),
                                      water=None, file="test"),
                      SimpleNamespace(bodies=[dist5], coupler=cp5), comm)
rows, pairs = Rows(), []
for step in range(1, 61):
    cp5_ref.step()
    cp5.step()
    balance.after_step(step, step * dt, rows)
    pairs.append((src_ref.total_pairs(), src.total_pairs()))
y = dist5.gather(dist5.y)
if comm.rank == 0:
    p = np.array(pairs)
    print(f"RESULT contact ranks={comm.size} same={np.array_equal(y, ref5.y)} "
          f"pairs={int(p[:, 0].max())} agree={np.array_equal(p[:, 0], p[:, 1])} "
          f"moved={sum(int(r[2]) for r in rows.rows)} layout={dist5.layout_version}")

# 6. water: a plate floating too deep rises under buoyancy against linear drag, badly split and
# re-partitioned every 20 steps; the water's per-particle drag counters move with the particles
from pdfem.forces.water import Water

def water(body):
    return Water([body], density=1025.0, level=0.025, g=9.81, linear_drag=50.0)

ref6 = IceBody.from_shape("plate", plate, mat2, d2, 3.015 * d2)
dist6 = split_body(IceBody.from_shape("plate", plate, mat2, d2, 3.015 * d2), owner, comm)
w_ref, w = water(ref6), water(dist6)
dt6 = 0.8 * ref6.stable_time_step()
cp6_ref = Coupler([ref6], [], [], dt6, forces=[w_ref])
cp6 = Coupler([dist6], [], [], dt6, forces=[w], comm=comm)
cp6_ref.start(); cp6.start()
balance = LoadBalance(SimpleNamespace(run=SimpleNamespace(rebalance_every=20, rebalance_imbalance=0.0),
                                      water=None, file="test"),
                      SimpleNamespace(bodies=[dist6], coupler=cp6), comm)
rows = Rows()
for step in range(1, 61):
    cp6_ref.step()
    cp6.step()
    balance.after_step(step, step * dt6, rows)
y = dist6.gather(dist6.y)
lost, lost_ref = w.dissipated(), w_ref.dissipated()
pot, pot_ref = w.potential_energy(), w_ref.potential_energy()
if comm.rank == 0:
    print(f"RESULT water ranks={comm.size} same={np.array_equal(y, ref6.y)} "
          f"lost={lost:.6e} lost_err={abs(lost - lost_ref) / lost_ref:.3e} "
          f"pot_err={abs(pot - pot_ref) / abs(pot_ref):.3e} "
          f"moved={sum(int(r[2]) for r in rows.rows)} layout={dist6.layout_version}")

# the imbalance limit: a badly split body is re-partitioned at once, then left alone
bad = split_body(IceBody.from_shape("plate", plate, mat2, d2, 3.015 * d2), owner, comm)
limit = LoadBalance(SimpleNamespace(run=SimpleNamespace(rebalance_every=0, rebalance_imbalance=1.2),
                                    water=None, file="test"),
                    SimpleNamespace(bodies=[bad], coupler=Coupler([bad], [], [], 1e-6, comm=comm)),
                    comm)
lim = Rows()
start = bad.imbalance()
for step in (1, 2, 3):
    limit.after_step(step, step * 1e-6, lim)
if comm.rank == 0:
    print(f"RESULT limit start={start:.4f} flags={','.join(str(int(r[2])) for r in lim.rows)} "
          f"after={lim.rows[0][1]:.4f}")

# 4. the partition depends only on the particles, not on where they are now
rng = np.random.default_rng(1)
N = 3000
X = np.round(rng.random((N, 3)) * 10) / 10 * np.array([2.0, 1.0, 0.5])  # ties on planes
W = rng.integers(1, 40, N)
G = np.arange(N)
res = []
for seed in (2, 3):
    mine = np.random.default_rng(seed).integers(0, comm.size, N) == comm.rank
    o = rcb_owners(X[mine], G[mine], W[mine], comm.size, comm, N)
    full = np.full(N, -1)
    for g, oo in comm.allgather((G[mine], o)):
        full[g] = oo
    res.append(full)
work = np.bincount(res[0], weights=W, minlength=comm.size)
if comm.rank == 0:
    print(f"RESULT rcb same={np.array_equal(res[0], res[1])} imb={work.max() / work.mean():.5f} "
          f"maxw={W.max()} mean={work.mean():.1f} sec={time.perf_counter() - T0:.1f}")
''')


def _fields(line: str) -> dict:
    return dict(kv.split("=", 1) for kv in line.split()[2:])


@pytest.mark.slow
@pytest.mark.parametrize("ranks", [2, 3])
def test_rebalance_mid_run_matches_serial(tmp_path, ranks):
    script = tmp_path / "rebalance.py"
    script.write_text(SCRIPT)
    env = dict(os.environ, NUMBA_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    r = run_script(script, ranks, timeout=300, env=env)
    res = {line.split()[1]: _fields(line) for line in r.stdout.splitlines()
           if line.startswith("RESULT")}
    bar, crush, coupled, rcb = res["bar"], res["crush"], res["coupled"], res["rcb"]
    limit = res["limit"]
    for case in (bar, crush):
        assert case["same"] == "True" and float(case["err"]) == 0.0
        assert float(case["react"]) <= 1e-12 and int(case["broken"]) > 0
        assert int(case["layout"]) == 2
        assert max(float(case["imb1"]), float(case["imb2"])) <= 1.01
    assert float(bar["imb0"]) > 1.4  # the bad split
    assert int(crush["crushed"]) > 0
    assert coupled["same"] == "True" and float(coupled["err_f"]) == 0.0
    water = res["water"]
    assert water["same"] == "True" and int(water["moved"]) == 3 and float(water["lost"]) > 0
    assert float(water["lost_err"]) <= 1e-12 and float(water["pot_err"]) <= 1e-12
    contact = res["contact"]
    assert contact["same"] == "True" and contact["agree"] == "True"
    assert int(contact["pairs"]) > 0 and int(contact["moved"]) == 3
    assert float(coupled["fmax"]) > 1e3 and int(coupled["broken"]) > 0
    assert coupled["moved"] == "20,40,60" and int(coupled["layout"]) == 3
    # the imbalance history: high until the first re-partition (step 20), then about 1
    assert float(coupled["first"]) > 1.3 and float(coupled["before"]) > 1.3
    assert float(coupled["last"]) <= 1.01
    assert float(limit["start"]) > 1.3 and limit["flags"] == "1,0,0"
    assert float(limit["after"]) <= 1.01
    assert rcb["same"] == "True" and float(rcb["imb"]) <= 1.0 + 2 * int(rcb["maxw"]) / float(rcb["mean"])


CASE = """
[run]
end_time = 1e-3
{extra}
[[ice]]
name = "floe"
dx = 0.02
shape = {{ box = {{ min = [0.0, 0.0, 0.0], max = [0.2, 0.2, 0.04] }} }}
material = {{ fracture_energy = 3.0 }}
"""


@pytest.mark.parametrize("extra, field", [
    ("rebalance_imbalance = 0.5", "run.rebalance_imbalance"),
    ("rebalance_every = 10\noutput_per_rank = true", "run.output_per_rank")])
def test_bad_rebalance_settings_are_refused(extra, field):
    """A factor <= 1 cannot be exceeded meaningfully; per-rank output keeps each rank's particles
    of the start, which a re-partition would change."""
    from pdfem.case.loader import parse_case
    from pdfem.errors import InputError

    with pytest.raises(InputError) as err:
        parse_case(CASE.format(extra=extra), "case.toml")
    assert err.value.field == field and ("rebalance" in err.value.message or "> 1" in err.value.message)


def test_bond_work_counts_both_ends_and_is_measured_once_per_layout():
    """A rank's bond work (the weights of the bisection and the imbalance) counts each local
    bond at both ends, as the two bincounts of its row and its partner did; the run's load
    balance measures a body again only after its particles moved (the work changes by a
    migration only)."""
    from types import SimpleNamespace

    import numpy as np

    from pdfem.geometry.shapes import Box
    from pdfem.pd.body import IceBody
    from pdfem.pd.layout.migration import bond_work
    from pdfem.pd.materials.lps import IceMaterial
    from pdfem.run.balance import LoadBalance

    mat = IceMaterial(density=900.0, youngs_modulus=4e9, poisson_ratio=0.3, fracture_energy=1.0)
    b = IceBody.from_shape("b", Box((0, 0, 0), (0.07, 0.05, 0.04)), mat, 0.01, 0.03015)
    rows = np.repeat(np.arange(b.n), np.diff(b.row_ptr))
    expected = np.bincount(rows, minlength=b.n) + np.bincount(b.nbr, minlength=b.n)
    work = bond_work(b.row_ptr, b.nbr, b.n)
    assert work.dtype == np.int64 and np.array_equal(work, expected)
    assert np.array_equal(bond_work(np.zeros(1, np.int64), np.zeros(0, np.int32), 0), [])

    calls = []
    body = SimpleNamespace(name="b", layout_version=0,
                           imbalance=lambda: calls.append(1) or 1.25)
    balance = LoadBalance(SimpleNamespace(run=SimpleNamespace(rebalance_every=0,
                                                              rebalance_imbalance=0.0)),
                          SimpleNamespace(bodies=[body], coupler=None), SimpleNamespace(size=2))
    history = []
    writer = SimpleNamespace(append_history=lambda group, t, row: history.append(row))
    for step in range(1, 4):
        balance.after_step(step, 1e-6 * step, writer)
    body.layout_version = 1  # the particles moved
    balance.after_step(4, 4e-6, writer)
    assert len(calls) == 2 and [r["imbalance"] for r in history] == [1.25] * 4
