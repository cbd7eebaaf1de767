"""The energy dissipated by fracture, computed on its own (pdfem.pd.failure.fracture).

Definition: a step that breaks bonds at positions y dissipates W(y; bonds before) - W(y; bonds
after), the LPS strain energy (Silling et al. 2007) with the dilatation of each bond set; the
body sums it in ``fracture_dissipated``. References: the definition itself (the body's own
``strain_energy`` before and after), a lone LPS bond (closed form), the energy balance of
velocity Verlet with its first-order error at a force that drops within a step, the
full-family reference loop, and the serial body for the MPI-split one.
"""

from __future__ import annotations

import textwrap

import numpy as np
import pytest

from pdfem.geometry.shapes import Box
from pdfem.pd.body import IceBody
from pdfem.pd.materials.lps import IceMaterial

from support.mpi import run_script

MAT = IceMaterial(density=900.0, youngs_modulus=4e9, poisson_ratio=0.3, fracture_energy=1.0)
DX = 0.005


def bar(loop: str = "pairs") -> IceBody:
    """A notched bar 24 x 8 x 6 dx, its ends pulled apart at 0.5 m/s (ramped in over 20 us)."""
    b = IceBody.from_shape("bar", Box((0, 0, 0), (24 * DX, 8 * DX, 6 * DX)), MAT, DX,
                           3.015 * DX, loop=loop)
    b.cut_crack((12 * DX, 0, 0), (1, 0, 0), (11 * DX, -1, -1), (13 * DX, 1, 2 * DX))
    x = b.x0[:, 0]
    b.add_velocity_constraint(x < 2 * DX, (-0.5, 0, 0), ramp_time=2e-5)
    b.add_velocity_constraint(x > 22 * DX, (0.5, 0, 0), ramp_time=2e-5)
    return b


def torn_block(loop: str) -> IceBody:
    """A block with random jitter whose right half is shifted past the critical stretch."""
    b = IceBody.from_shape("b", Box((0, 0, 0), (8 * DX, 5 * DX, 5 * DX)), MAT, DX, 3.015 * DX,
                           loop=loop)
    b.y[:] = b.x0 + 0.02 * DX * np.random.default_rng(1).standard_normal(b.x0.shape)
    b.y[b.x0[:, 0] > 4 * DX, 0] += 3.0 * b.s0 * DX
    return b


def test_a_lone_bond_releases_what_it_held():
    """Two particles, one bond, pulled to stretch s > s0. A lone LPS bond has theta = 3 s on
    both ends and no deviatoric part, so it holds W = 2 V K (3 s)^2 / 2 = 9 K V s^2; breaking
    releases all of it: fracture_dissipated = that energy = strain before - strain after."""
    mat = IceMaterial(density=900.0, youngs_modulus=4e9, poisson_ratio=0.3, critical_stretch=1e-3)
    x = np.array([[0.0, 0.0, 0.0], [DX, 0.0, 0.0]])
    b = IceBody.from_points("pair", x, mat, DX, 1.5 * DX)
    assert b.n_bonds == 1
    s = 2.5e-3
    b.y[1] = b.x0[0] + (b.x0[1] - b.x0[0]) * (1.0 + s)
    before = b.strain_energy()
    assert before == pytest.approx(9.0 * mat.K * DX ** 3 * s * s, rel=1e-12)
    assert b.compute_forces() == 1
    assert b.strain_energy() == 0.0
    assert b.fracture_dissipated == pytest.approx(before, rel=1e-14)


@pytest.mark.parametrize("loop", ["pairs", "full_family"])
def test_released_energy_is_strain_before_minus_after(loop):
    """Definition: at fixed positions, one force pass that breaks bonds adds exactly
    strain_energy() before minus after to fracture_dissipated (round-off: 1e-12 of the drop)."""
    b = torn_block(loop)
    before = b.strain_energy()
    nb = b.compute_forces()
    after = b.strain_energy()
    assert nb > 100
    assert before - after > 0.3 * before
    assert b.fracture_dissipated == pytest.approx(before - after, rel=1e-12)
    # a second pass at the same positions breaks nothing more and releases nothing
    assert b.compute_forces() == 0 and b.fracture_dissipated == pytest.approx(before - after,
                                                                              rel=1e-12)


def test_pre_cracks_and_the_initial_state_are_not_dissipation():
    """Bonds cut at set-up (cut_crack) and bonds breaking in start() happen before the run:
    fracture_dissipated stays 0 through them, and the first step counts only its own breaks."""
    b = torn_block("pairs")
    b.cut_crack((2 * DX, 0, 0), (1, 0, 0), (-1, -1, -1), (1, 1, 1))
    b.start()
    assert int(b.broken.sum()) > 100 and b.fracture_dissipated == 0.0
    before = b.strain_energy()
    b.y[b.x0[:, 1] > 2.5 * DX, 1] += 3.0 * b.s0 * DX  # tear along y as well
    w0 = b.strain_energy()
    assert b.compute_forces() > 0
    assert b.fracture_dissipated == pytest.approx(w0 - b.strain_energy(), rel=1e-12)
    assert before > 0.0


def _run_bar(dt_factor: float, steps_at_08: int = 400):
    """Step the bar over a fixed time; per step: residual of strain before + work in = strain
    + kinetic + fracture, the fracture increment, and the first-order bound of Verlet's energy
    error at breaking bonds (below)."""
    b = bar()
    i_of = np.repeat(np.arange(b.n), np.diff(b.row_ptr))
    dt = dt_factor * b.stable_time_step()
    n = int(round(steps_at_08 * 0.8 / dt_factor))
    b.start()
    w0 = b.strain_energy()
    rows, bound = [], 0.0
    K, mu = MAT.K, MAT.mu
    for _ in range(n):
        was, y_old, f_old = b.broken.copy(), b.y.copy(), b.fracture_dissipated
        b.step(dt)
        new = np.flatnonzero((b.broken != 0) & (was == 0))
        if len(new):
            # a bond that breaks in a step exerts its force F over the first half kick only,
            # while its energy drop is counted over the whole step: Verlet's energy error is
            # about F dr / 2 per breaking bond (first order in dt)
            i, j, l = i_of[new], b.nbr[new], b.xi_len[new]
            r = np.linalg.norm(b.y[j] - b.y[i], axis=1)
            r_old = np.linalg.norm(y_old[j] - y_old[i], axis=1)
            a, c = b.theta * (3 * K - 5 * mu) / b.m, 15 * mu / b.m  # t_ij = a_i l + c_i e
            t = (a[i] + a[j]) * l + (c[i] + c[j]) * (r - l)
            F = t * np.abs(b.weight[new]) * b.vol[i] * b.vol[j]  # the bond's force, N
            bound += 0.5 * float(np.sum(np.abs(F * (r - r_old))))
        stored = b.strain_energy() + b.kinetic_energy() + b.fracture_dissipated
        rows.append((w0 + b.external_work - stored, b.fracture_dissipated - f_old, bound,
                     b.external_work, b.fracture_dissipated))
    return np.array(rows)


def test_energy_balance_of_a_bar_torn_apart():
    """A notched bar pulled apart until it separates: strain before + work of the grips =
    strain + kinetic + fracture_dissipated at every step, within 1 % of the work put in, at
    two time steps. A bond that breaks at the end of a step still acts in both half kicks
    around it and the next step starts with the forces without it, so no first-order error
    appears where forces jump (before that change the balance was off by about the sum of
    F dr / 2 over the breaking bonds, 6.5 % of the work here); what is left is Verlet's smooth
    O(dt^2) error and the grips' trapezoidal work (measured 0.2 % and 0.7 %). The fracture
    increments are never negative, and without the fracture term the balance would miss
    about half of the work put in."""
    for dt_factor in (0.8, 0.4):
        res, inc, bound, work, frac = _run_bar(dt_factor).T
        assert np.all(inc >= 0.0)
        assert frac[-1] > 0.4 * work[-1]
        assert np.all(np.abs(res) <= 0.01 * work[-1])


def test_pair_and_full_family_loops_dissipate_alike():
    """The full-family reference loop gives the pair loop's fracture_dissipated (and broken
    bonds) over 300 steps of the torn bar, to round-off (1e-9 relative)."""
    a, b = bar("pairs"), bar("full_family")
    dt = 0.8 * a.stable_time_step()
    a.start()
    b.start()
    na = nb = 0
    for _ in range(300):
        na += a.step(dt)
        nb += b.step(dt)
    assert na == nb > 1000
    assert a.fracture_dissipated > 0.0
    assert b.fracture_dissipated == pytest.approx(a.fracture_dissipated, rel=1e-9)


def test_a_restored_body_continues_bit_for_bit():
    """checkpoint_state / restore_state keep fracture_dissipated and the accounted bonds: a
    body restored mid-fracture and stepped on gives the uninterrupted run's value exactly."""
    a = bar()
    dt = 0.8 * a.stable_time_step()
    a.start()
    for _ in range(60):
        a.step(dt)
    state = {k: np.array(v) if isinstance(v, np.ndarray) else v
             for k, v in a.checkpoint_state().items()}
    assert state["fracture_dissipated"] > 0.0
    b = bar()
    b.restore_state(state)
    for _ in range(100):
        a.step(dt)
        b.step(dt)
    assert a.fracture_dissipated > state["fracture_dissipated"]
    assert b.fracture_dissipated == a.fracture_dissipated
    np.testing.assert_array_equal(b.y, a.y)


MPI_SCRIPT = textwrap.dedent('''
    import numpy as np
    from pdfem.parallel.comm import world
    from pdfem.parallel.partition import choose_partition
    from pdfem.pd.layout.split import split_body
    from pdfem.pd.body import IceBody
    from pdfem.pd.materials.lps import IceMaterial
    from pdfem.geometry.shapes import Box

    DX = 0.005
    def build():
        mat = IceMaterial(density=900.0, youngs_modulus=4e9, poisson_ratio=0.3, fracture_energy=1.0)
        b = IceBody.from_shape("bar", Box((0, 0, 0), (24 * DX, 8 * DX, 6 * DX)), mat, DX, 3.015 * DX)
        b.cut_crack((12 * DX, 0, 0), (1, 0, 0), (11 * DX, -1, -1), (13 * DX, 1, 2 * DX))
        x = b.x0[:, 0]
        b.add_velocity_constraint(x < 2 * DX, (-0.5, 0, 0), ramp_time=2e-5)
        b.add_velocity_constraint(x > 22 * DX, (0.5, 0, 0), ramp_time=2e-5)
        return b

    comm = world()
    ref = build()
    dt = 0.8 * ref.stable_time_step()
    owner, _ = choose_partition(ref.x0, ref.row_ptr, ref.nbr, comm.size)
    dist = split_body(build(), owner, comm)
    ref.start()
    dist.start()
    for _ in range(200):
        ref.step(dt)
        dist.step(dt)
    total = dist.fracture_dissipated
    ckpt = {"fracture_dissipated":  # each rank's checkpoint part holds its own share
            comm.allreduce_sum(dist.checkpoint_state()["fracture_dissipated"])}
    part = dist.local_fracture_dissipated
    if comm.rank == 0:
        print(f"RESULT ref={ref.fracture_dissipated!r} dist={total!r} "
              f"ckpt={ckpt['fracture_dissipated']!r} part={part!r}")
''')


def test_split_body_dissipates_the_serial_total(tmp_path):
    """The bar torn on 2 MPI ranks: each rank counts its owned particles, and the total
    (fracture_dissipated, collective, and the checkpoint parts' sum over ranks) equals the serial
    body's to round-off (1e-10 relative), with each rank holding a part of it."""
    script = tmp_path / "split.py"
    script.write_text(MPI_SCRIPT)
    r = run_script(script, 2, timeout=300)
    line = next(x for x in r.stdout.splitlines() if x.startswith("RESULT"))
    v = {k: float(x) for k, x in (kv.split("=") for kv in line.split()[1:])}
    assert v["ref"] > 0.0
    assert v["dist"] == pytest.approx(v["ref"], rel=1e-10)
    assert v["ckpt"] == v["dist"]
    assert 0.0 < v["part"] < v["dist"]


@pytest.mark.parametrize("loop", ["pairs", "full_family"])
def test_strain_energy_from_the_step_s_dilatation_is_the_recomputed_one(loop):
    """After every step of the torn bar (bonds break in 1 of 3 steps) and after a restore, the
    strain energy taken with the body's own dilatation (``forces_current``, what the run's
    energy rows use) is the one with a dilatation pass of its own, bit for bit."""
    b = bar(loop)
    dt = 0.8 * b.stable_time_step()
    b.start()
    broke = 0
    for _ in range(150):
        broke += b.step(dt) > 0
        assert b.strain_energy(forces_current=True) == b.strain_energy()
    assert broke > 20
    c = bar(loop)
    c.restore_state({k: np.array(v) if isinstance(v, np.ndarray) else v
                     for k, v in b.checkpoint_state().items()})
    assert c.strain_energy(forces_current=True) == b.strain_energy()


@pytest.mark.parametrize("on_path", [False, True])
def test_strain_energy_reads_the_step_s_bond_lengths_only_where_current(on_path):
    """The energy rows read the bond lengths the step's dilatation pass kept
    (``workspace.lengths_current``) instead of taking them from the positions: the torn bar's
    strain energy so is the one with its lengths taken from the positions, bit for bit, after
    every step. Ends that follow a displacement path are put back on it after the pass
    (``end_step``), which moves them by round-off: there the kept lengths are not current
    (unless bonds broke and the forces were taken again at those positions). A restored body
    has no current lengths."""
    from pdfem.geometry.path import DisplacementPath

    b = IceBody.from_shape("bar", Box((0, 0, 0), (24 * DX, 8 * DX, 6 * DX)), MAT, DX,
                           3.015 * DX)
    b.cut_crack((12 * DX, 0, 0), (1, 0, 0), (11 * DX, -1, -1), (13 * DX, 1, 2 * DX))
    x = b.x0[:, 0]
    for mask, sign in ((x < 2 * DX, -1.0), (x > 22 * DX, 1.0)):
        if on_path:
            b.add_velocity_constraint(mask, path=DisplacementPath(
                [[0.0, 0, 0, 0], [1e-4, sign * 3e-5, 0, 0], [1.0, sign * 0.5, 0, 0]]))
        else:
            b.add_velocity_constraint(mask, (sign * 0.5, 0, 0), ramp_time=2e-5)
    dt = 0.8 * b.stable_time_step()
    b.start()
    used = broke = 0
    for _ in range(150):
        n = b.step(dt)
        broke += n > 0
        used += b.workspace.lengths_current
        assert b.workspace.lengths_current == (not on_path or n > 0)
        kept = b.strain_energy(forces_current=True)
        current, b.workspace.lengths_current = b.workspace.lengths_current, False
        assert kept == b.strain_energy(forces_current=True)  # lengths from the positions
        b.workspace.lengths_current = current
        if current:  # the forces were taken at these positions: a fresh pass agrees too
            assert kept == b.strain_energy()
    assert broke > 20 and used == (broke if on_path else 150)
    c = IceBody.from_shape("bar", Box((0, 0, 0), (24 * DX, 8 * DX, 6 * DX)), MAT, DX,
                           3.015 * DX)
    c.compute_forces()
    c.restore_state({k: np.array(v) if isinstance(v, np.ndarray) else v
                     for k, v in b.checkpoint_state().items()})
    assert not c.workspace.lengths_current
    assert c.strain_energy(forces_current=True) == b.strain_energy()
