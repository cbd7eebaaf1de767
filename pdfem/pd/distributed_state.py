"""Checkpoints of an ice body split over MPI ranks: the whole body's state in global order on
rank 0, and each rank's part of it back on restart (on any number of ranks).

:class:`DistributedCheckpoint` is mixed into :class:`pdfem.pd.distributed.DistributedIce`;
SI units as the serial body's (:mod:`pdfem.pd.body_state`).
"""

from __future__ import annotations

import numpy as np


class DistributedCheckpoint:
    """``checkpoint_state`` / ``restore_state`` of a distributed ice body (collective)."""

    def checkpoint_state(self) -> dict | None:
        """The state of the whole body in global order on rank 0, as the serial body's
        :meth:`~pdfem.pd.body.IceBody.checkpoint_state` (``None`` on the other ranks; every
        rank must call it). ``external_work`` and ``fracture_dissipated`` are sums over ranks;
        ``<key>_ranks`` keeps each rank's part, so a restart on as many ranks continues bit for
        bit."""
        b = self.body
        arrays = {k: self.gather(getattr(b, k)) for k in ("y", "v", "f", "theta")}
        counted = self._counted
        rest = b.rest[counted] if b.rest is not None else None
        slip = b.shear.slip[counted] if b.shear is not None else None
        rate_parts = {k: self.gather(v) for k, v in self._rate_arrays().items()}
        bonds = self.comm.gather((self._bond_numbers()[counted], b.broken[counted], rest, slip))
        work = self.comm.gather(float(b.external_work))
        frac = self.comm.gather(float(b.fracture_dissipated))
        if bonds is None:
            return None
        broken = np.zeros(self.global_bonds, dtype=np.uint8)
        rests = np.full(self.global_bonds, np.nan, dtype=np.float32)
        slips = np.zeros((self.global_bonds, 3), dtype=np.float32)
        for idx, flags, rest, slip in bonds:
            broken[idx] = flags
            if rest is not None:
                rests[idx] = rest
            if slip is not None:
                slips[idx] = slip
        extra = {} if b.rest is None else {"rest": rests}
        if b.shear is not None:
            extra["slip"] = slips
        extra.update(rate_parts)
        return {**arrays, **extra, "broken": broken, "time": float(b.time),
                "external_work": _rank_sum(work), "external_work_ranks": np.array(work),
                "fracture_dissipated": _rank_sum(frac), "fracture_dissipated_ranks": np.array(frac)}

    def restore_state(self, state: dict) -> None:
        """Take this rank's part of a whole-body state (from a checkpoint written on any number
        of ranks, or by a serial run).

        Raises
        ------
        ValueError
            If the state's sizes are not those of the body.
        """
        n, p = self.global_n, self.global_bonds
        for k, size in (("y", n), ("v", n), ("f", n), ("theta", n), ("broken", p)):
            if len(state[k]) != size:
                raise ValueError(f"ice body '{self.name}': {k} has {len(state[k])} entries in "
                                 f"the checkpoint, {size} in the case")
        loc = self.plan.local
        self.body.restore_state({"y": state["y"][loc], "v": state["v"][loc],
                                 "f": state["f"][loc], "theta": state["theta"][loc],
                                 "broken": self._local_bonds(state["broken"]),
                                 "time": state["time"],
                                 "external_work": self._rank_part(state, "external_work"),
                                 "fracture_dissipated":
                                     self._rank_part(state, "fracture_dissipated"),
                                 **({} if self.body.rest is None
                                    else {"rest": self._local_bonds(state["rest"])}),
                                 **({} if self.body.shear is None
                                    else {"slip": self._local_bonds(state["slip"])}),
                                 **{k: state[k][loc] for k in ("rate_theta", "rate_factors")
                                    if k in state}})
        self._counted_broken = self._broken_count()
        self.update_intact_volume()  # the halo's from their owners

    def _bond_numbers(self) -> np.ndarray:
        """Global number of each local bond (that of the global pair list); right for the
        bonds whose lower end is owned here (all of them for the global set-up). A body from
        the distributed set-up (``plan.pairs`` None) finds them here: each rank's forward bond
        counts of its owned particles, summed over ranks into a global count per particle
        (the one global-sized array of the distributed set-up, made only when a checkpoint is
        written or read, which holds the global state anyway), give each row's first number."""
        if self.plan.pairs is not None:
            return self.plan.pairs
        b, own = self.body, self.plan.owned
        rows = np.diff(b.row_ptr)
        count = np.zeros(self.global_n, dtype=np.int64)
        count[self.plan.local[own]] = rows[own]
        count = self.comm.allreduce_sum(count)
        first = np.cumsum(count) - count
        del count
        i_of = np.repeat(np.arange(b.n), rows)
        out = first[self.plan.local[i_of]] + (np.arange(len(b.nbr)) - b.row_ptr[i_of])
        out[~self._counted] = -1
        return out

    def _local_bonds(self, values: np.ndarray) -> np.ndarray:
        """The local entries of a per-bond array in global bond order: the owned rows' from
        ``values``, the halo rows' (bonds whose lower end another rank owns) from that rank."""
        if self.plan.pairs is not None:
            return values[self.plan.pairs]
        counted = self._counted
        out = np.empty((len(self.body.nbr),) + values.shape[1:], dtype=values.dtype)
        out[counted] = values[self._bond_numbers()[counted]]
        owner = np.full(self.body.n, self.comm.rank, dtype=np.int64)
        for q, idx in self.plan.recv.items():
            owner[idx] = q
        i_of = np.repeat(np.arange(self.body.n), np.diff(self.body.row_ptr))
        j_of = self.body.nbr
        sends = {q: np.ascontiguousarray(out[counted & (owner[j_of] == q)])
                 for q in self.plan.send}
        want = {q: (~counted) & (owner[i_of] == q) for q in self.plan.recv}
        recvs = {q: ((int(m.sum()),) + values.shape[1:], values.dtype) for q, m in want.items()}
        for q, got in self.comm.exchange(sends, recvs).items():
            out[want[q]] = got
        return out

    def _rate_arrays(self) -> dict[str, np.ndarray]:
        """The per-particle state of a rate-dependent failure law (empty without one)."""
        r = self.body.rates
        if r is None or r.theta is None:
            return {}
        out = {"rate_theta": r.theta}
        if r.factors is not None:
            out["rate_factors"] = r.factors
        return out

    def _rank_part(self, state: dict, key: str) -> float:
        """This rank's part of a counter summed over ranks: its own from ``<key>_ranks`` if the
        checkpoint was written on as many ranks, else the total on rank 0 and 0 elsewhere."""
        ranks = state.get(f"{key}_ranks")
        if ranks is not None and len(ranks) == self.comm.size:
            return float(ranks[self.comm.rank])
        return float(state[key]) if self.comm.rank == 0 else 0.0


def _rank_sum(values) -> float:
    """``values[0] + values[1] + ...`` in rank order, as the counters' allreduce sums them."""
    total = 0.0
    for v in values:
        total = total + v
    return total
