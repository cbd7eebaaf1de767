"""Numba kernels of the short-range contact's Verlet pair list (:mod:`pdfem.forces.short_range`).

:func:`pair_rows` turns the candidate pairs found by the search
(:mod:`pdfem.forces.short_range_kernels`) into the list: a CSR over the local particles whose
row i holds every partner j of an owned particle i (both directions of each pair), ascending
by local index, with the pair's critical distance r_ij and constant k_ij V_i V_j. Every step,
:func:`pair_forces` walks the owned particles' rows (``prange``), each particle summing its own
force from its interacting partners in row order and skipping the others, so its force depends
only on the positions and not on when the list was built, on the thread count or on the rank
layout; it walks only the rows of the particles that :func:`contacts_near` (each pair's
distance tested once, from its lower-numbered end) found in a contact; :func:`tally` counts
the interacting pairs and their potential, and :func:`add_owned` adds the force densities
into the bodies' force arrays.
"""

from __future__ import annotations

import math

import numba
from numba import prange

from pdfem.parallel.kernels import twin


@numba.njit(cache=True)
def pair_rows(counts, cap, pair, val, owned, row_ptr, nbr, crit, kvv, split):
    """The pair list from the candidates of :class:`~pdfem.forces.short_range_kernels.Found`
    (chunk c in slots ``[c cap, c cap + counts[c])`` of ``pair``, i < j, and ``val``, r_ij and
    k_ij V_i V_j): for every owned particle i the partners j of its pairs into
    ``nbr[row_ptr[i]:row_ptr[i + 1]]``, ascending, with ``crit`` r_ij (m) and ``kvv`` (N m) of
    the pair (rows of particles not ``owned`` are empty), and into ``split[i]`` the first entry
    of the row that :func:`contacts_near` tests: its first partner above i, or the row's start
    where a partner below i is not owned. ``nbr``, ``crit``, ``kvv`` hold at least twice the
    candidates; ``row_ptr`` and ``split`` have one entry more than ``owned``. Returns the
    entries written."""
    m = owned.shape[0]
    for i in range(m + 1):
        row_ptr[i] = 0
    for c in range(counts.shape[0]):
        for t in range(c * cap, c * cap + counts[c]):
            if owned[pair[t, 0]]:
                row_ptr[pair[t, 0] + 1] += 1
            if owned[pair[t, 1]]:
                row_ptr[pair[t, 1] + 1] += 1
    for i in range(m):
        row_ptr[i + 1] += row_ptr[i]
    fill = row_ptr[:m].copy()
    for c in range(counts.shape[0]):
        for t in range(c * cap, c * cap + counts[c]):
            for e in range(2):
                i = pair[t, e]
                if owned[i]:
                    s = fill[i]
                    nbr[s] = pair[t, 1 - e]
                    crit[s] = val[t, 0]
                    kvv[s] = val[t, 1]
                    fill[i] = s + 1
    for i in range(m):  # insertion sort of each row by partner (rows are short)
        for s in range(row_ptr[i] + 1, row_ptr[i + 1]):
            j, r, k = nbr[s], crit[s], kvv[s]
            u = s - 1
            while u >= row_ptr[i] and nbr[u] > j:
                nbr[u + 1] = nbr[u]
                crit[u + 1] = crit[u]
                kvv[u + 1] = kvv[u]
                u -= 1
            nbr[u + 1] = j
            crit[u + 1] = r
            kvv[u + 1] = k
    for i in range(m):
        s = row_ptr[i]
        while s < row_ptr[i + 1] and nbr[s] < i:
            if not owned[nbr[s]]:
                s = row_ptr[i]
                break
            s += 1
        split[i] = s
    split[m] = row_ptr[m]
    return row_ptr[m]


@numba.njit(cache=True)
def row_margins(rows, row_ptr, split, nbr, crit, y, owned, margin):
    """``margin[i]`` = the smallest ``|y_j - y_i| - r_ij`` (m) over the entries of row i that
    :func:`contacts_near` tests, at the positions ``y`` of the list's build (inf for a row
    without such entries): none of them interacts while both ends have moved less than half of
    it since."""
    for t in range(rows.shape[0]):
        i = rows[t]
        low = math.inf
        for s in range(split[i], row_ptr[i + 1]):
            j = nbr[s]
            if j < i and owned[j]:
                continue
            px = y[j, 0] - y[i, 0]
            py = y[j, 1] - y[i, 1]
            pz = y[j, 2] - y[i, 2]
            low = min(low, math.sqrt(px * px + py * py + pz * pz) - crit[s])
        margin[i] = low


@twin(fastmath=False, one_thread="serial")
def contacts_near(rows, row_ptr, split, nbr, crit, y, owned, margin, reach, near):
    """``near[p]`` = 1 for every local particle p of a pair that interacts at the positions
    ``y``, else 0 (``near`` (m,) over the local particles). Each pair of owned particles is
    tested once, from its lower-numbered end i (in ``rows``): row i's entries from
    ``split[i]`` on, its higher-numbered partners (and, where the row has any, the partners
    that are not ``owned``: another rank's, whose row is not here), with the test of
    :func:`pair_forces` (d^2 < r_ij^2, the same bits from either end). A row whose
    :func:`row_margins` exceeds ``reach`` (m: twice the largest move of any particle since the
    build, and a round-off allowance) is skipped: every pair of it is still farther apart than
    its r_ij. Threads may mark the same particle at once: every mark is a 1, so the result is
    the same."""
    for p in prange(near.shape[0]):
        near[p] = 0
    for t in prange(rows.shape[0]):
        i = rows[t]
        if margin[i] > reach:
            continue
        yix = y[i, 0]
        yiy = y[i, 1]
        yiz = y[i, 2]
        for s in range(split[i], row_ptr[i + 1]):
            j = nbr[s]
            if j < i and owned[j]:
                continue
            px = y[j, 0] - yix
            py = y[j, 1] - yiy
            pz = y[j, 2] - yiz
            r = crit[s]
            if px * px + py * py + pz * pz < r * r:
                near[i] = 1
                near[j] = 1


@twin(fastmath=False, one_thread="serial")
def pair_forces(rows, row_ptr, nbr, crit, kvv, y, vol, near, acc, hit, n_up, e_up):
    """Whether each particle i of ``rows`` (local indices) has an interacting partner at the
    positions ``y`` (``hit[i]``); if so its short-range force density (N/m^3) into ``acc[i]``,
    summed over its partners ``nbr[row_ptr[i]:row_ptr[i + 1]]`` in that order, and the number
    and potential (J) of its interacting pairs with a higher-numbered partner (``n_up[i]``,
    ``e_up[i]``; all three left as they were where not hit).

    A partner j interacts when d = |p| < r_ij, p = y_j - y_i: the force on i is
    -k_ij V_i V_j (r_ij - d) / d p, its potential 1/2 k_ij V_i V_j (r_ij - d)^2. The others add
    nothing (not even a zero). From j's row the same pair gives -p exactly, the same d and the
    same stored constants, so the exactly negated force.

    ``near`` is :func:`contacts_near` at these positions: only the rows of particles in an
    interacting pair are walked (the others have no partner to add, and their ``hit`` is 0 as
    the walk would leave it).
    """
    for t in prange(rows.shape[0]):
        i = rows[t]
        if near[i] == 0:
            hit[i] = 0
            continue
        yix = y[i, 0]
        yiy = y[i, 1]
        yiz = y[i, 2]
        fx = 0.0
        fy = 0.0
        fz = 0.0
        found = 0
        up = 0
        e = 0.0
        for s in range(row_ptr[i], row_ptr[i + 1]):
            j = nbr[s]
            px = y[j, 0] - yix
            py = y[j, 1] - yiy
            pz = y[j, 2] - yiz
            d2 = px * px + py * py + pz * pz
            r = crit[s]
            if d2 >= r * r:
                continue
            d = math.sqrt(d2)
            w = -kvv[s] * (r - d) / d  # force on i (N) = w p
            fx += w * px
            fy += w * py
            fz += w * pz
            found = 1
            if j > i:
                up += 1
                e += 0.5 * kvv[s] * (r - d) * (r - d)
        hit[i] = found
        if found:  # the rest is read only where hit
            inv_v = 1.0 / vol[i]
            acc[i, 0] = fx * inv_v
            acc[i, 1] = fy * inv_v
            acc[i, 2] = fz * inv_v
            n_up[i] = up
            e_up[i] = e


@numba.njit(cache=True)
def tally(rows, hit, n_up, e_up):
    """Interacting pairs and their potential (J) over the particles ``rows`` that are ``hit``,
    summed in that order."""
    n = 0
    energy = 0.0
    for t in range(rows.shape[0]):
        i = rows[t]
        if hit[i]:
            n += n_up[i]
            energy += e_up[i]
    return n, energy


@numba.njit(cache=True)
def add_owned(f, idx, pos, acc, hit):
    """``f[idx[t]] += acc[pos[t]]`` for the owned particles that have an interacting partner
    (``hit``); the others' ``f`` is not touched."""
    for t in range(idx.shape[0]):
        p = pos[t]
        if hit[p]:
            i = idx[t]
            f[i, 0] += acc[p, 0]
            f[i, 1] += acc[p, 1]
            f[i, 2] += acc[p, 2]
