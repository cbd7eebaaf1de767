"""The Verlet pair list of the short-range contact (pdfem.forces.short_range).

References: the force of a list built at the current positions (forced by ``invalidate``),
which must equal, bit for bit, the force of a list built long ago (the per-particle sums run
over the interacting partners in global order, whatever the list holds besides); and the
brute-force O(N^2) force of test_ice_contact. The list is rebuilt only with the contact halo,
once a particle has moved more than half the skin s from its position at the last build.
"""

from __future__ import annotations

import numpy as np

from pdfem.forces.short_range import ShortRangeContact

from test_ice_contact import brute_force, two_body_cloud


def active_pairs(bodies) -> set:
    """The interacting pairs (global numbers) at the bodies' current positions, brute force."""
    contact = ShortRangeContact(bodies)
    contact.forces()
    rows = contact._rows
    pairs = set()
    for i in rows:
        for s in range(contact._row_ptr[i], contact._row_ptr[i + 1]):
            j = contact._nbr[s]
            p = contact.halo.y[j] - contact.halo.y[i]
            if j > i and p @ p < contact._crit[s] ** 2:
                pairs.add((int(i), int(j)))
    assert len(pairs) == contact.n_active
    return pairs


def test_old_list_gives_the_fresh_lists_forces_bit_for_bit():
    """Two jittered, interpenetrating bodies pushed further into each other and shaken, every
    particle up to 0.49 s from where the list was built: the list built at the start gives the
    forces, pair count and potential of a list built at the current positions, bit for bit, at
    every step, while pairs that did not interact at the build come into contact (and others
    leave it); the forces stay the brute-force ones."""
    a, b = two_body_cloud(8)
    bodies = [a, b]
    old = ShortRangeContact(bodies)
    fresh = ShortRangeContact(bodies, n_chunks=3)
    old.forces()
    s = old.halo.skin
    y0 = [a.y.copy(), b.y.copy()]
    rng = np.random.default_rng(9)
    # per particle a direction: the bodies approach along x, each particle also sideways
    dirs = []
    for k, body in enumerate(bodies):
        d = rng.normal(0.0, 1.0, body.y.shape) + [3.0 if k == 0 else -3.0, 0.0, 0.0]
        dirs.append(d / np.linalg.norm(d, axis=1, keepdims=True))
    start = active_pairs(bodies)
    steps = 12
    counts = []
    for step in range(1, steps + 1):
        reach = 0.49 * s * step / steps
        for body, y, d, sign in zip(bodies, y0, dirs, (1.0, -1.0)):
            body.y[:] = y + reach * d * (1.0 + 0.02 * np.sin(step * np.arange(len(y))))[:, None]
            assert np.linalg.norm(body.y - y, axis=1).max() < 0.5 * s
        f_old = old.forces()
        fresh.invalidate()
        f_new = fresh.forces()
        for f, g in zip(f_old, f_new):
            assert np.array_equal(f, g)
        assert old.n_active == fresh.n_active > 100
        assert old.potential_energy() == fresh.potential_energy() > 0.0
        counts.append(old.n_active)
    assert old.builds == old.halo.refreshes == 1  # the list of the start, all along
    assert fresh.builds == steps
    now = active_pairs(bodies)
    assert len(now - start) > 50 and len(start - now) > 0  # contacts made and lost
    assert counts[-1] > counts[0]
    ref, U, n_ref = brute_force(bodies)
    assert old.n_active == n_ref
    scale = max(np.abs(r).max() for r in ref)
    for f, r in zip(old.forces(), ref):
        np.testing.assert_allclose(f, r, rtol=0, atol=1e-12 * scale)


def test_list_is_rebuilt_only_when_a_particle_moved_half_the_skin():
    """Two bodies drifting sideways together (0.03 s per step, s the skin) while closing
    (0.02 s per step each): every particle moves 0.036 s per step, so over 100 steps the list
    is built 8 times (every 14 steps), not 100, and the forces are the brute-force ones at every
    step. Then one particle alone moved 0.499 s from its position at the last build leaves the
    list as it is; moved 0.501 s it causes a rebuild."""
    a, b = two_body_cloud(10)
    bodies = [a, b]
    contact = ShortRangeContact(bodies)
    s = contact.halo.skin
    worst, steps = 0.0, 100
    for step in range(steps):
        a.y[:] += [0.02 * s, 0.03 * s, 0.0]
        b.y[:] += [-0.02 * s, 0.03 * s, 0.0]
        f = contact.forces()
        ref, _, n_ref = brute_force(bodies)
        assert contact.n_active == n_ref > 100
        scale = max(np.abs(r).max() for r in ref)
        worst = max(worst, max(np.abs(g - r).max() for g, r in zip(f, ref)) / scale)
    assert contact.builds == contact.halo.refreshes == 1 + (steps - 1) // 14
    assert worst < 1e-12
    contact.invalidate()  # a list built here, at these positions
    contact.add_forces()
    built = contact.builds
    base = a.y[5].copy()
    for move, rebuilt in ((0.3, False), (0.499, False), (0.501, True)):
        a.y[5] = base + move * s * np.array([0.6, 0.0, 0.8])
        contact.add_forces()
        assert contact.builds == built + rebuilt


def test_a_call_at_the_last_pass_positions_reuses_that_pass():
    """The forces again at positions unchanged bit for bit (the coupler's forces after bonds
    broke, an energy row) take the last pass's forces, pair count and potential: the same
    values and no new pass; a move of one coordinate by one ulp, or back, makes a new pass
    whose forces are the brute-force ones there."""
    a, b = two_body_cloud(8)
    bodies = [a, b]
    contact = ShortRangeContact(bodies)
    first = contact.forces()
    energy, n = contact.potential_energy(), contact.n_active
    assert n > 50 and energy > 0.0
    passes = contact.passes
    again = contact.forces()
    assert contact.passes == passes
    assert all(np.array_equal(f, g) for f, g in zip(first, again))
    assert contact.potential_energy() == energy and contact.n_active == n
    assert contact.passes == passes
    i = int(np.flatnonzero(np.abs(first[0]).sum(axis=1) > 0)[0])  # a particle in contact
    for y in (np.nextafter(a.y[i, 0], np.inf), a.y[i, 0] - 0.0):
        a.y[i, 0] = y
        moved = contact.forces()
        passes += 1
        assert contact.passes == passes
        ref, U, n_ref = brute_force(bodies)
        assert contact.n_active == n_ref
        scale = max(np.abs(r).max() for r in ref)
        for f, r in zip(moved, ref):
            np.testing.assert_allclose(f, r, rtol=0, atol=1e-12 * scale)
