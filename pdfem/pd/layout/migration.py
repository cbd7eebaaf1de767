"""Migration of a split ice body's particles and bonds to new owner ranks (load balance).

:func:`pdfem.pd.layout.rebalance.rebalance` decides new owners
(:func:`pdfem.parallel.rcb.rcb_owners` on the current positions, weighted by bond counts) and
calls :func:`migrate`, which moves everything a rank holds per particle and per bond:

* each owned particle's full state (reference and current positions, velocity, force density,
  volume, weighted volume m, dilatation, no-fail and fixed flags, membership of each
  velocity constraint, the rate law's state) goes to its new owner, and to every rank that will
  hold it as halo (the new owners of its bond partners): its old owner holds all its bonds, so
  it knows them without asking anyone;
* each bond, from the rank owning its lower end (which holds the authoritative copy; the other
  end's rank evaluates it alike), goes to the new owners of both ends: both global numbers, the
  reference length, the signed weight (negative = broken), the crushed bond's rest stretch and
  its shear spring's slip.

The receiver sorts its particles by global number and its bonds by global (i, j): the local
pair list is the serial one restricted to the local particles, in the serial order, as the
distributed set-up makes it (:mod:`pdfem.pd.layout.setup`), so each owned particle sums its
family in the serial order and 1 and N ranks still agree bit for bit (one numba thread per
rank). The halo plan is rebuilt from the new owners that came with the particles. No rank ever
holds a global array: messages go only to the ranks a particle or bond is sent to, after one
all-gather of the K message counts per rank. Units: SI.
"""

from __future__ import annotations

import dataclasses

import numba
import numpy as np

from pdfem.pd.bonds.data import Bonds
from pdfem.pd.failure.crushed_shear import CrushedShear


def _particle_columns(body, owner: np.ndarray, carry: dict) -> tuple[list, list]:
    """The per-particle state of ``body`` as (name, float64 (n, k)) and (name, int64 (n, k))
    columns; ``owner`` the new owner rank of every local particle; ``carry`` further float
    columns (named ``carry:<name>``)."""
    n = body.n
    member = np.zeros((n, len(body.constraints)), dtype=np.int64)
    for k, c in enumerate(body.constraints):
        member[c.index, k] = 1
    floats = [("x0", body.x0), ("y", body.y), ("v", body.v), ("f", body.f), ("vol", body.vol),
              ("m", body.m), ("theta", body.theta)]
    floats += [(f"carry:{k}", v) for k, v in sorted(carry.items())]
    r = body.rates
    if r is not None:
        floats += [("rate_theta", r.theta), ("rate_factors", r.factors)]
    ints = [("gid", body.gid), ("owner", owner), ("nofail", body.nofail),
            ("fixed", body.fixed), ("member", member)]
    col = lambda v: v if v.ndim == 2 else v[:, None]  # noqa: E731 (also for n = 0)
    return ([(k, col(v).astype(np.float64)) for k, v in floats if v is not None],
            [(k, col(v).astype(np.int64)) for k, v in ints])


def _bond_columns(body, i_of: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The state of the bonds ``rows`` as one float64 (k, c) and one int64 (k, 2) (global i,
    j) matrix; ``i_of`` the lower end of every local bond."""
    ints = np.stack([body.gid[i_of[rows]], body.gid[body.nbr[rows]]], axis=1).astype(np.int64)
    cols = [body.xi_len[rows, None], body.weight[rows].astype(np.float64)[:, None]]
    if body.rest is not None:
        cols.append(body.rest[rows].astype(np.float64)[:, None])
    if body.shear is not None:
        cols.append(body.shear.slip[rows].astype(np.float64))
    return np.concatenate(cols, axis=1), ints


def _send_all(comm, parts: dict, width_f: int, width_i: int) -> tuple[np.ndarray, np.ndarray]:
    """Send ``parts[q] = (floats, ints)`` to each rank q; returns what arrived, stacked in rank
    order (own part included). Collective."""
    counts = np.zeros(comm.size, dtype=np.int64)
    for q, (fl, _) in parts.items():
        counts[q] = len(fl)
    table = np.array(comm.allgather(counts))  # table[p, q]: rows p sends to q
    mine = comm.rank
    recv_f = {p: ((int(table[p, mine]), width_f), np.float64) for p in range(comm.size)
              if p != mine and table[p, mine]}
    recv_i = {p: ((int(table[p, mine]), width_i), np.int64) for p in range(comm.size)
              if p != mine and table[p, mine]}
    send = {q: v for q, v in parts.items() if q != mine and len(v[0])}
    got_f = comm.exchange({q: v[0] for q, v in send.items()}, recv_f)
    got_i = comm.exchange({q: v[1] for q, v in send.items()}, recv_i)
    empty = (np.zeros((0, width_f)), np.zeros((0, width_i), dtype=np.int64))
    own = parts.pop(mine, empty)
    parts.clear()  # what was sent is no longer needed (the caller's dict: memory)
    del send
    fl = [got_f[p] if p != mine else own[0] for p in range(comm.size) if p in got_f or p == mine]
    it = [got_i[p] if p != mine else own[1] for p in range(comm.size) if p in got_i or p == mine]
    return np.concatenate(fl), np.concatenate(it)


def _destinations(dest: np.ndarray, size: int) -> np.ndarray:
    """The ranks that occur in ``dest`` (ascending; a count per rank, no sort)."""
    return np.flatnonzero(np.bincount(dest, minlength=size))


@numba.njit(cache=True)
def _local_numbers(gid, query):
    """Position of each of ``query`` in the ascending unique ``gid`` (every query is in it),
    by an open-addressing hash table (one or two probes instead of a binary search)."""
    n = gid.shape[0]
    bits = 1
    while (1 << bits) < 2 * n:
        bits += 1
    mask = (1 << bits) - 1
    keys = np.full(mask + 1, -1, dtype=np.int64)
    vals = np.empty(mask + 1, dtype=np.int64)
    mult = np.uint64(11400714819323198485)  # Fibonacci hashing
    shift = np.uint64(64 - bits)
    for k in range(n):
        h = np.int64((np.uint64(gid[k]) * mult) >> shift)
        while keys[h] != -1:
            h = (h + 1) & mask
        keys[h] = gid[k]
        vals[h] = k
    out = np.empty(query.shape[0], dtype=np.int32)
    for k in range(query.shape[0]):
        h = np.int64((np.uint64(query[k]) * mult) >> shift)
        while keys[h] != query[k]:
            h = (h + 1) & mask
        out[k] = vals[h]
    return out


def migrate(body, owned: np.ndarray, owner: np.ndarray, comm, carry: dict | None = None):
    """This rank's new local body after every rank's owned particles moved to ``owner``.

    Parameters
    ----------
    body
        The rank's local :class:`~pdfem.pd.body.IceBody` (owned and halo particles in global
        order, ``gid`` their global numbers, bonds with an owned end, constraints over owned
        particles).
    owned
        (n,) bool, the particles this rank owns now.
    owner
        (n,) new owner rank of every local particle (the halo's from their owners).
    comm
        The communicator. Collective.
    carry
        Further per-particle arrays ((n, k) or (n,) float64) to move with the particles.

    Returns
    -------
    parts, owned, new_owner, carried
        The new local arrays (``x0``, ``vol``, ``m``, ``bonds``, ``nofail``, ``fixed``, the
        ``state`` keywords of :class:`~pdfem.pd.body.IceBody` and the global numbers ``gid``),
        which particles this rank owns, every local particle's owner, and the ``carry`` arrays
        in the new local order ((n_new, k) each).
    """
    fcols, icols = _particle_columns(body, owner, dict(carry or {}))
    pf = np.concatenate([v for _, v in fcols], axis=1)
    pi = np.concatenate([v for _, v in icols], axis=1)
    owner = owner.astype(np.int32)
    i_of = np.repeat(np.arange(body.n, dtype=np.int32), np.diff(body.row_ptr))
    oi, oj = owner[i_of], owner[body.nbr]
    counted = owned[i_of]  # bonds whose lower end this rank owns
    # particles: to the new owner, and to the new owners of their partners (as halo)
    cross = oi != oj
    fi, fj = cross & counted, cross & owned[body.nbr]
    parts = {}
    for q in _destinations(np.concatenate([owner[owned], oj[fi], oi[fj]]), comm.size):
        mark = owned & (owner == q)
        mark[i_of[fi & (oj == q)]] = True
        mark[body.nbr[fj & (oi == q)]] = True
        sel = np.flatnonzero(mark & owned)
        parts[int(q)] = (pf[sel], pi[sel])
    del fi, fj
    pf, pi = _send_all(comm, parts, pf.shape[1], pi.shape[1])
    # bonds: from the owner of the lower end, to the new owners of both ends (each rank's
    # part in the bond order, which is ascending global (i, j))
    parts = {}
    for q in _destinations(np.concatenate([oi[counted], oj[counted & cross]]), comm.size):
        sel = np.flatnonzero(counted & ((oi == q) | (oj == q)))
        parts[int(q)] = _bond_columns(body, i_of, sel)
    width = parts[next(iter(parts))][0].shape[1] if parts else 2 + (body.rest is not None) + \
        3 * (body.shear is not None)
    del i_of, oi, oj, counted, cross
    bf, bi = _send_all(comm, parts, width, 2)
    del parts
    return _assemble(body, fcols, icols, pf, pi, bf, bi, comm.rank)


def _assemble(body, fcols, icols, pf, pi, bf, bi, rank: int):
    """The new local body from the particle and bond rows that arrived."""
    order = np.argsort(pi[:, 0], kind="stable")
    pf, pi = pf[order], pi[order]
    gid = np.ascontiguousarray(pi[:, 0])
    n = len(gid)
    fields, c = {}, 0
    for name, v in fcols:
        fields[name] = pf[:, c:c + v.shape[1]]
        c += v.shape[1]
    c = 0
    for name, v in icols:
        fields[name] = pi[:, c:c + v.shape[1]]
        c += v.shape[1]
    # each sender's part is in global (i, j) order: a stable sort merges the runs
    big = int(gid[-1]) + 1 if n else 1  # (i, j) as one key i * big + j while it fits
    order = (np.argsort(bi[:, 0] * big + bi[:, 1], kind="stable") if big < 3_000_000_000
             else np.lexsort((bi[:, 1], bi[:, 0])))
    gi, gj = bi[order, 0], bi[order, 1]
    del bi
    bf = bf[order]
    del order
    row_ptr = np.searchsorted(gi, np.append(gid, np.iinfo(np.int64).max)).astype(np.int64)
    row_ptr[-1] = len(gi)
    lj = _local_numbers(gid, gj)
    del gi, gj
    new_owner = fields["owner"][:, 0]
    owned = new_owner == rank
    vec = lambda k: np.ascontiguousarray(fields[k])  # noqa: E731
    sca = lambda k: np.ascontiguousarray(fields[k][:, 0])  # noqa: E731
    constraints = [dataclasses.replace(con, index=np.flatnonzero(owned & (fields["member"][:, k]
                                                                          == 1)))
                   for k, con in enumerate(body.constraints)]
    c = 2
    state = {"y": vec("y"), "v": vec("v"), "f": vec("f"), "theta": sca("theta"),
             "constraints": constraints, "time": body.time, "gravity": body.gravity}
    if body.rest is not None:
        state["rest"] = np.ascontiguousarray(bf[:, c], dtype=np.float32)
        c += 1
    if body.shear is not None:
        state["shear"] = CrushedShear(np.ascontiguousarray(bf[:, c:c + 3], dtype=np.float32),
                                      body.shear.friction, body.shear.stiffness_ratio)
    rates = body.rates
    if rates is not None:
        rates.theta = sca("rate_theta") if "rate_theta" in fields else None
        rates.factors = sca("rate_factors") if "rate_factors" in fields else None
        state["rates"] = rates
    bonds = Bonds(row_ptr, lj, np.ascontiguousarray(bf[:, 0]),
                  np.ascontiguousarray(bf[:, 1], dtype=np.float32))
    parts = {"x0": vec("x0"), "vol": sca("vol"), "m": sca("m"), "bonds": bonds,
             "nofail": sca("nofail").astype(np.uint8), "fixed": sca("fixed").astype(bool),
             "state": state, "gid": gid}
    carried = {k[len("carry:"):]: vec(k) for k in fields if k.startswith("carry:")}
    return parts, owned, new_owner, carried


def halo_lists(row_ptr: np.ndarray, nbr: np.ndarray, owned: np.ndarray,
               owner: np.ndarray) -> tuple[dict, dict]:
    """``send``, ``recv`` of a halo plan (neighbour rank -> local indices, ascending = global
    order): what each neighbour holds of ours as halo, and our halo by owner."""
    n = len(owned)
    i_of = np.repeat(np.arange(n, dtype=np.int32), np.diff(row_ptr))
    oi, oj = owner[i_of], owner[nbr]
    fi, fj = owned[i_of] & ~owned[nbr], owned[nbr] & ~owned[i_of]
    send = {}
    for q in _destinations(np.concatenate([oj[fi], oi[fj]]), int(owner.max(initial=0)) + 1):
        mark = np.zeros(n, dtype=bool)
        mark[i_of[fi & (oj == q)]] = True
        mark[nbr[fj & (oi == q)]] = True
        send[int(q)] = np.flatnonzero(mark)
    halo = np.flatnonzero(~owned)
    recv = {int(r): halo[owner[halo] == r] for r in np.unique(owner[halo])}
    return send, recv


@numba.njit(cache=True)
def bond_work(row_ptr: np.ndarray, nbr: np.ndarray, n: int) -> np.ndarray:
    """(n,) int64 bonds of each local particle (intact or broken: the pair loop visits both);
    right for owned particles, whose bonds are all local. One pass over the bonds and nothing
    of their size allocated (a run measures the balance every coupling step)."""
    out = np.empty(n, dtype=np.int64)
    for i in range(n):
        out[i] = row_ptr[i + 1] - row_ptr[i]
    for k in range(nbr.shape[0]):
        out[nbr[k]] += 1
    return out

