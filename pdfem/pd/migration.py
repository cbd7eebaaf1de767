"""Migration of a split ice body's particles and bonds to new owner ranks (load balance).

:meth:`pdfem.pd.rebalance.Rebalancing.rebalance` decides new owners
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
distributed set-up makes it (:mod:`pdfem.pd.distributed_setup`), so each owned particle sums its
family in the serial order and 1 and N ranks still agree bit for bit (one numba thread per
rank). The halo plan is rebuilt from the new owners that came with the particles. No rank ever
holds a global array: messages go only to the ranks a particle or bond is sent to, after one
all-gather of the K message counts per rank. Units: SI.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from pdfem.pd.crushed_shear import CrushedShear


def _particle_columns(body, owner: np.ndarray) -> tuple[list, list]:
    """The per-particle state of ``body`` as (name, float64 (n, k)) and (name, int64 (n, k))
    columns; ``owner`` the new owner rank of every local particle."""
    n = body.n
    member = np.zeros((n, len(body.constraints)), dtype=np.int64)
    for k, c in enumerate(body.constraints):
        member[c.index, k] = 1
    floats = [("x0", body.x0), ("y", body.y), ("v", body.v), ("f", body.f), ("vol", body.vol),
              ("m", body.m), ("theta", body.theta)]
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
    own = parts.get(mine, empty)
    fl = [got_f[p] if p != mine else own[0] for p in range(comm.size) if p in got_f or p == mine]
    it = [got_i[p] if p != mine else own[1] for p in range(comm.size) if p in got_i or p == mine]
    return np.concatenate(fl), np.concatenate(it)


def _by_rank(rows: np.ndarray, dest: np.ndarray, floats: np.ndarray, ints: np.ndarray) -> dict:
    """``{q: (floats[rows to q], ints[rows to q])}`` for the (row, dest) pairs given."""
    order = np.argsort(dest, kind="stable")
    rows, dest = rows[order], dest[order]
    bounds = np.flatnonzero(np.diff(dest)) + 1
    return {int(d[0]): (floats[r], ints[r]) for r, d in zip(np.split(rows, bounds),
                                                            np.split(dest, bounds)) if len(d)}


def _unique(keys: np.ndarray) -> np.ndarray:
    """Sorted unique int64 ``keys`` (by sorting: faster than numpy's hashing here)."""
    keys = np.sort(keys)
    return keys[np.concatenate([[True], keys[1:] != keys[:-1]])] if len(keys) else keys


def migrate(body, owned: np.ndarray, owner: np.ndarray, comm):
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

    Returns
    -------
    local, owned, new_owner
        The new local body (no workspace, ledger or intact volume yet: the caller sets them
        up), which particles of it this rank owns, and every local particle's owner.
    """
    fcols, icols = _particle_columns(body, owner)
    pf = np.concatenate([v for _, v in fcols], axis=1)
    pi = np.concatenate([v for _, v in icols], axis=1)
    # particles: to the new owner, and to the new owners of their partners (as halo)
    i_of = np.repeat(np.arange(body.n), np.diff(body.row_ptr))
    j_of = body.nbr.astype(np.int64)
    own = np.flatnonzero(owned)
    split = owner[i_of] != owner[j_of]  # bonds whose ends' new owners differ
    fi, fj = split & owned[i_of], split & owned[j_of]
    key = _unique(np.concatenate([i_of[fi] * comm.size + owner[j_of[fi]],
                                  j_of[fj] * comm.size + owner[i_of[fj]]]))
    a = np.concatenate([own, key // comm.size])
    q = np.concatenate([owner[own], key % comm.size])
    pf, pi = _send_all(comm, _by_rank(a, q, pf, pi), pf.shape[1], pi.shape[1])
    # bonds: from the owner of the lower end, to the new owners of both ends
    counted = np.flatnonzero(owned[i_of])
    bf, bi = _bond_columns(body, i_of, counted)
    other = np.flatnonzero(split[counted])
    rows = np.concatenate([np.arange(len(counted)), other])
    dest = np.concatenate([owner[i_of[counted]], owner[j_of[counted[other]]]])
    bf, bi = _send_all(comm, _by_rank(rows, dest, bf, bi), bf.shape[1], bi.shape[1])
    return _assemble(body, fcols, icols, pf, pi, bf, bi, comm.rank)


def _assemble(body, fcols, icols, pf, pi, bf, bi, rank: int):
    """The new local body from the particle and bond rows that arrived."""
    order = np.argsort(pi[:, 0], kind="stable")
    pf, pi = pf[order], pi[order]
    gid = pi[:, 0]
    n = len(gid)
    fields, c = {}, 0
    for name, v in fcols:
        fields[name] = pf[:, c:c + v.shape[1]]
        c += v.shape[1]
    c = 0
    for name, v in icols:
        fields[name] = pi[:, c:c + v.shape[1]]
        c += v.shape[1]
    big = int(gid[-1]) + 1 if n else 1  # (i, j) as one key i * big + j while it fits
    order = (np.argsort(bi[:, 0] * big + bi[:, 1]) if big < 3_000_000_000
             else np.lexsort((bi[:, 1], bi[:, 0])))
    bf, bi = bf[order], bi[order]
    li, lj = np.searchsorted(gid, bi[:, 0]), np.searchsorted(gid, bi[:, 1])
    row_ptr = np.concatenate([[0], np.cumsum(np.bincount(li, minlength=n))]).astype(np.int64)
    new_owner = fields["owner"][:, 0]
    owned = new_owner == rank
    vec = lambda k: np.ascontiguousarray(fields[k])  # noqa: E731
    sca = lambda k: np.ascontiguousarray(fields[k][:, 0])  # noqa: E731
    constraints = [dataclasses.replace(con, index=np.flatnonzero(owned & (fields["member"][:, k]
                                                                          == 1)))
                   for k, con in enumerate(body.constraints)]
    c = 2
    rest = shear = None
    if body.rest is not None:
        rest = np.ascontiguousarray(bf[:, c], dtype=np.float32)
        c += 1
    if body.shear is not None:
        shear = CrushedShear(np.ascontiguousarray(bf[:, c:c + 3], dtype=np.float32),
                             body.shear.friction, body.shear.stiffness_ratio)
    rates = body.rates
    if rates is not None:
        rates.theta = sca("rate_theta") if "rate_theta" in fields else None
        rates.factors = sca("rate_factors") if "rate_factors" in fields else None
    local = dataclasses.replace(
        body, x0=vec("x0"), y=vec("y"), v=vec("v"), f=vec("f"), vol=sca("vol"), m=sca("m"),
        theta=sca("theta"), nofail=sca("nofail").astype(np.uint8),
        fixed=sca("fixed").astype(bool), row_ptr=row_ptr, nbr=lj.astype(np.int32),
        xi_len=np.ascontiguousarray(bf[:, 0]),
        weight=np.ascontiguousarray(bf[:, 1], dtype=np.float32), flags=None,
        constraints=constraints, rest=rest, shear=shear, rates=rates, gid=gid)
    return local, owned, new_owner


def halo_lists(row_ptr: np.ndarray, nbr: np.ndarray, owned: np.ndarray,
               owner: np.ndarray) -> tuple[dict, dict]:
    """``send``, ``recv`` of a halo plan (neighbour rank -> local indices, ascending = global
    order): what each neighbour holds of ours as halo, and our halo by owner."""
    i_of = np.repeat(np.arange(len(owned)), np.diff(row_ptr))
    j_of = nbr.astype(np.int64)
    a = np.concatenate([i_of[owned[i_of] & ~owned[j_of]], j_of[owned[j_of] & ~owned[i_of]]])
    q = np.concatenate([owner[j_of[owned[i_of] & ~owned[j_of]]],
                        owner[i_of[owned[j_of] & ~owned[i_of]]]])
    n = max(len(owned), 1)
    key = _unique(q * n + a)
    send = {int(r): key[key // n == r] % n for r in np.unique(q)}
    halo = np.flatnonzero(~owned)
    recv = {int(r): halo[owner[halo] == r] for r in np.unique(owner[halo])}
    return send, recv


def bond_work(row_ptr: np.ndarray, nbr: np.ndarray, n: int) -> np.ndarray:
    """(n,) int64 bonds of each local particle (intact or broken: the pair loop visits both);
    right for owned particles, whose bonds are all local."""
    i_of = np.repeat(np.arange(n), np.diff(row_ptr))
    return np.bincount(i_of, minlength=n) + np.bincount(nbr, minlength=n)

