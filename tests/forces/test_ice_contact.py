"""Short-range contact between ice particles (pdfem.forces.short_range).

References: a brute-force O(N^2) evaluation of Silling & Askari's (2005) short-range force
written independently here with numpy; Newton's third law (momentum conservation); the
force-potential relation f = -grad U (central differences); and, for two colliding cubes,
conservation of momentum and energy by velocity Verlet on a conservative system.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from pdfem.forces.short_range import (DENSE_CELLS_PER_PARTICLE, ShortRangeContact,
                                        short_range_constant)
from pdfem.pd.body import IceBody
from pdfem.pd.layout.base import WholeLayout
from pdfem.pd.materials.lps import IceMaterial
from pdfem.geometry.shapes import Box

RHO = 900.0
ICE = IceMaterial(density=RHO, youngs_modulus=4.0e9, poisson_ratio=0.3)
SOFT = IceMaterial(density=RHO, youngs_modulus=1.0e9, poisson_ratio=0.25)


def cloud_body(x0, y, dx, delta, material, vol=None):
    """A stand-in with the attributes the contact reads (no bonds needed): a whole body."""
    n = x0.shape[0]
    return SimpleNamespace(x0=np.ascontiguousarray(x0), y=np.ascontiguousarray(y),
                           vol=np.full(n, dx ** 3) if vol is None else vol, dx=dx, delta=delta,
                           material=material, f=np.zeros((n, 3)), layout=WholeLayout(n),
                           n_global=n)


def brute_force(bodies, factor=15.0):
    """Silling & Askari's short-range force density and potential, all pairs, numpy O(N^2)."""
    x0 = np.concatenate([b.x0 for b in bodies])
    y = np.concatenate([b.y for b in bodies])
    vol = np.concatenate([b.vol for b in bodies])
    bid = np.concatenate([np.full(b.x0.shape[0], k) for k, b in enumerate(bodies)])
    rad = np.concatenate([np.full(b.x0.shape[0], b.dx / 2) for b in bodies])
    kc = np.concatenate([np.full(b.x0.shape[0], 15.0 * 18 * b.material.K / (math.pi * b.delta ** 4)
                                 / b.delta) for b in bodies]) * (factor / 15.0)
    p = y[None, :, :] - y[:, None, :]                      # p[i, j] = y_j - y_i
    d = np.sqrt(np.einsum("ijk,ijk->ij", p, p))
    xi = np.linalg.norm(x0[None, :, :] - x0[:, None, :], axis=2)
    rsum = rad[:, None] + rad[None, :]
    r = np.where(bid[:, None] == bid[None, :], np.minimum(0.9 * xi, 1.35 * rsum), 0.9 * rsum)
    k = 2 * kc[:, None] * kc[None, :] / (kc[:, None] + kc[None, :])
    act = (d < r) & ~np.eye(len(y), dtype=bool)
    dd = np.where(act, d, 1.0)
    mag = np.where(act, k * (r - dd) / dd, 0.0)            # f_i = -sum_j mag p V_j
    f = -np.einsum("ij,ijk,j->ik", mag, p, vol)
    U = 0.25 * np.sum(np.where(act, k * vol[:, None] * vol[None, :] * (r - d) ** 2, 0.0))
    split = np.cumsum([b.x0.shape[0] for b in bodies])[:-1]
    return np.split(f, split), U, int(act.sum()) // 2


def tree_reference(body, h):
    """The same force for one body from scipy's cKDTree pair list (an independent search)."""
    from scipy.spatial import cKDTree
    pairs = cKDTree(body.y).query_pairs(h, output_type="ndarray")
    i, j = pairs[:, 0], pairs[:, 1]
    p = body.y[j] - body.y[i]
    d = np.linalg.norm(p, axis=1)
    xi = np.linalg.norm(body.x0[j] - body.x0[i], axis=1)
    r = np.minimum(0.9 * xi, 1.35 * body.dx)
    act = d < r
    k = 15.0 * 18 * body.material.K / (math.pi * body.delta ** 5)
    mag = np.where(act, k * (r - d) / np.where(act, d, 1.0), 0.0)[:, None] * p
    f = np.zeros_like(body.y)
    np.add.at(f, i, -mag * body.vol[j, None])
    np.add.at(f, j, mag * body.vol[i, None])
    return f, int(act.sum())


def jittered_lattice(rng, n_side, dx, origin, jitter):
    g = np.arange(n_side) * dx
    x0 = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3) + origin
    return x0, x0 + rng.uniform(-jitter, jitter, x0.shape)


def two_body_cloud(seed=0):
    rng = np.random.default_rng(seed)
    xa, ya = jittered_lattice(rng, 7, 0.01, np.zeros(3), 0.004)
    xb, yb = jittered_lattice(rng, 6, 0.013, np.array([0.05, 0.01, 0.0]), 0.005)
    yb -= [0.02, 0.0, 0.0]  # push body b into body a
    a = cloud_body(xa, ya, 0.01, 0.03015, ICE)
    b = cloud_body(xb, yb, 0.013, 0.04, SOFT, vol=rng.uniform(0.8, 1.2, len(xb)) * 0.013 ** 3)
    return a, b


def test_matches_brute_force_on_two_jittered_bodies():
    """Forces and potential on two strongly jittered, interpenetrating lattices of different
    spacing, material and volumes equal the brute-force O(N^2) reference to round-off."""
    a, b = two_body_cloud()
    contact = ShortRangeContact([a, b])
    n = contact.add_forces()
    ref, U, n_ref = brute_force([a, b])
    assert n == n_ref > 100
    scale = max(np.abs(ref[0]).max(), np.abs(ref[1]).max())
    np.testing.assert_allclose(a.f, ref[0], rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(b.f, ref[1], rtol=0, atol=1e-12 * scale)
    assert contact.potential_energy() == pytest.approx(U, rel=1e-12)


def test_matches_brute_force_on_random_cloud_of_one_body():
    """A uniformly random cloud (one body, reference positions random too): same as brute force."""
    rng = np.random.default_rng(3)
    x0 = rng.uniform(0, 0.1, (700, 3))
    y = x0 + rng.normal(0, 0.003, x0.shape)
    body = cloud_body(x0, y, 0.01, 0.03, ICE)
    forces = ShortRangeContact(body).forces()[0]
    ref, _, n_ref = brute_force([body])
    assert n_ref > 100
    np.testing.assert_allclose(forces, ref[0], rtol=0, atol=1e-12 * np.abs(ref[0]).max())


def test_hashed_and_clamped_grids_for_scattered_fragments():
    """Fragments far apart (a grid of 10^5 m, and of 10^12 m where cell coordinates are clamped)
    switch to the hashed grid and still give the brute-force forces."""
    a, b = two_body_cloud(1)
    for far in (1.0e5, 1.0e12):
        a.y[:20] += [far, 0.0, 0.0]
        a.y[20:25] -= [0.0, far, 0.5 * far]
        contact = ShortRangeContact([a, b])
        forces = contact.forces()
        assert not contact.dense
        assert contact.n_buckets <= DENSE_CELLS_PER_PARTICLE * max(contact.n, 1024)  # bounded by N
        ref, _, n_ref = brute_force([a, b])
        assert contact.n_active == n_ref
        scale = max(np.abs(ref[0]).max(), np.abs(ref[1]).max())
        for f, fr in zip(forces, ref):
            np.testing.assert_allclose(f, fr, rtol=0, atol=1e-12 * scale)


def test_momentum_conserved_and_deterministic():
    """sum_i V_i f_i = 0 to round-off (Newton's third law), and the forces are bit-identical
    for any chunk count (the pair sums run in a fixed order)."""
    a, b = two_body_cloud(2)
    forces = ShortRangeContact([a, b]).forces()
    total = a.vol @ forces[0] + b.vol @ forces[1]
    scale = np.abs(a.vol @ np.abs(forces[0])).max()
    assert np.abs(total).max() < 1e-13 * scale
    for chunks in (1, 3, 17):
        other = ShortRangeContact([a, b], n_chunks=chunks).forces()
        for f, g in zip(forces, other):
            assert np.array_equal(f, g)


def test_parallel_scan_matches_tree_search_and_is_deterministic():
    """Above the serial threshold (the threaded scan): forces equal a cKDTree-based reference to
    round-off and are bit-identical for 1, 5 and the default number of chunks."""
    rng = np.random.default_rng(7)
    x0, y = jittered_lattice(rng, 30, 0.01, np.zeros(3), 0.0015)
    body = cloud_body(x0, y, 0.01, 0.03015, ICE)
    forces = ShortRangeContact(body).forces()[0]
    ref, n_ref = tree_reference(body, 1.35 * body.dx * (1 + 1e-9))
    assert n_ref > 1000
    np.testing.assert_allclose(forces, ref, rtol=0, atol=1e-12 * np.abs(ref).max())
    for chunks in (1, 5):
        assert np.array_equal(ShortRangeContact(body, n_chunks=chunks).forces()[0], forces)


def test_force_is_minus_gradient_of_potential():
    """V_i f_i = -dU/dy_i (central differences): the force is conservative."""
    a, b = two_body_cloud(4)
    contact = ShortRangeContact([a, b])
    f = contact.forces()
    rng = np.random.default_rng(5)
    h = 1e-7
    for body, fb in ((a, f[0]), (b, f[1])):
        active = np.flatnonzero(np.abs(fb).sum(axis=1) > 0)
        for i in rng.choice(active, 5, replace=False):
            for k in range(3):
                body.y[i, k] += h
                up = contact.potential_energy()
                body.y[i, k] -= 2 * h
                down = contact.potential_energy()
                body.y[i, k] += h
                grad = (up - down) / (2 * h)
                assert -grad == pytest.approx(body.vol[i] * fb[i, k], rel=1e-5,
                                              abs=1e-6 * body.vol[i] * np.abs(fb).max())


def test_no_force_in_intact_lattice():
    """An undeformed lattice, also rigidly rotated and moved, and one under 5 % uniform
    stretch, feels no short-range force (nearest sites at dx > 0.9 dx, next at sqrt(2) dx >
    1.35 dx)."""
    body = IceBody.from_shape("b", Box((0, 0, 0), (0.12, 0.1, 0.08)), ICE, 0.01, 0.03015)
    contact = ShortRangeContact(body)
    assert contact.add_forces() == 0 and not np.any(body.f)
    c, s = math.cos(0.3), math.sin(0.3)
    rot = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    body.y[:] = body.x0 @ rot.T + [1.0, -2.0, 0.5]
    assert contact.potential_energy() == 0.0 and contact.add_forces() == 0
    body.y[:] = 1.05 * body.x0
    assert contact.add_forces() == 0 and not np.any(body.f)
    body.y[:] = 0.85 * body.x0  # 15 % compression: neighbours at 0.85 dx < 0.9 dx do repel
    assert contact.add_forces() > 0


def test_two_cubes_collide_and_bounce():
    """Two unbonded ice cubes meet head-on at 1 m/s each, with the short-range force in a
    hand-written velocity-Verlet loop: they never interpenetrate, bounce apart, and total
    momentum (to round-off) and kinetic + strain + short-range energy (within 1 %) are conserved
    (Newton's third law; a conservative system integrated by a symplectic scheme)."""
    dx, n_side = 0.01, 7
    L = n_side * dx
    gap = 0.95 * dx  # facing sites 0.95 dx apart: just outside the 0.9 dx critical distance
    left = IceBody.from_shape("left", Box((0, 0, 0), (L, L, L)), ICE, dx, 3.015 * dx)
    right = IceBody.from_shape("right", Box((L - dx + gap, 0, 0), (2 * L - dx + gap, L, L)), ICE,
                               dx, 3.015 * dx)
    bodies = (left, right)
    left.v[:, 0] = 1.0
    right.v[:, 0] = -1.0
    contact = ShortRangeContact([left, right])
    dt = 0.7 * min(b.stable_time_step() for b in bodies)
    for b in bodies:
        b.compute_forces()
    contact.add_forces()

    def energy():
        elastic = sum(b.kinetic_energy() + b.strain_energy() for b in bodies)
        return elastic + contact.potential_energy()

    e0 = energy()
    p0 = left.momentum() + right.momentum()
    c = math.sqrt(ICE.youngs_modulus / RHO)
    # approach (the 0.05 dx to the critical distance at 2 m/s), then about 2 L / c of contact
    # (equal elastic bars), then separation
    steps = int((0.05 * dx / 2.0 + 3.0 * (2 * L / c)) / dt)
    touched, worst_e, worst_gap = 0, 0.0, np.inf
    for k in range(steps):
        for b in bodies:
            b.v += 0.5 * dt * b.f / RHO
            b.y += dt * b.v
            b.compute_forces()
        touched += contact.add_forces() > 0
        for b in bodies:
            b.v += 0.5 * dt * b.f / RHO
        worst_gap = min(worst_gap, right.y[:, 0].min() - left.y[:, 0].max())
        worst_e = max(worst_e, abs(energy() - e0) / e0)
    assert touched > 5
    assert worst_gap > 0.5 * dx  # no interpenetration: the faces never come closer than dx / 2
    assert worst_e < 0.01
    p = left.momentum() + right.momentum()
    scale = RHO * (left.vol.sum() + right.vol.sum()) * 1.0
    assert np.abs(p - p0).max() < 1e-12 * scale
    assert contact.add_forces() == 0  # separated again
    vl = left.momentum()[0] / (RHO * left.vol.sum())
    vr = right.momentum()[0] / (RHO * right.vol.sum())
    assert vl < -0.8 and vr > 0.8  # bounced: both centre-of-mass velocities reversed (0.955)
    assert short_range_constant(ICE.K, left.delta) > 0


def test_bad_input_is_refused():
    """Non-finite positions raise FloatingPointError; non-positive factors raise ValueError."""
    a, b = two_body_cloud(6)
    with pytest.raises(ValueError, match="stiffness_factor"):
        ShortRangeContact([a, b], stiffness_factor=0.0)
    with pytest.raises(ValueError, match="at least one"):
        ShortRangeContact([])
    a.y[3, 1] = np.nan
    with pytest.raises(FloatingPointError, match="not finite"):
        ShortRangeContact([a, b]).add_forces()


def test_split_bodies_on_one_rank_give_the_same_forces():
    """Bodies split over one 'rank' (a halo layout, serial communicator): the same forces,
    pair count and potential as the whole bodies, bit for bit; a NaN position is refused."""
    from pdfem.parallel.comm import SerialComm
    from pdfem.pd.layout.split import split_body

    dx = 0.01
    plain = [IceBody.from_shape(n, Box(lo, hi), ICE, dx, 3.015 * dx)
             for n, lo, hi in (("a", (0, 0, 0), (0.05, 0.06, 0.04)),
                               ("b", (0.045, 0.005, 0), (0.1, 0.065, 0.04)))]
    split = [split_body(IceBody.from_shape(b.name, Box(b.x0.min(0) - dx / 2,
                                                       b.x0.max(0) + dx / 2), ICE, dx,
                                           3.015 * dx), np.zeros(b.n, dtype=np.int64),
                        SerialComm()) for b in plain]
    rng = np.random.default_rng(3)
    for p, s in zip(plain, split):
        assert np.array_equal(p.x0, s.x0)
        p.y[:] = p.x0 + rng.normal(0.0, 0.1 * dx, p.x0.shape)
        s.y[:] = p.y
    ref, dist = ShortRangeContact(plain), ShortRangeContact(split)
    f_ref, f = ref.forces(), dist.forces()
    assert ref.n_active == dist.n_active > 0
    assert all(np.array_equal(a, b) for a, b in zip(f_ref, f))
    assert ref.potential_energy() == dist.potential_energy() > 0
    split[1].y[2, 0] = np.inf
    with pytest.raises(FloatingPointError, match="not finite"):
        dist.add_forces()
