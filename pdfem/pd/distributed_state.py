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
        bonds = self.comm.gather((self.plan.pairs[counted], b.broken[counted], rest, slip))
        work = self.comm.gather(float(b.external_work))
        frac = self.comm.gather(float(b.fracture_dissipated))
        if bonds is None:
            return None
        broken = np.zeros(len(self.global_body.nbr), dtype=np.uint8)
        rests = np.full(len(self.global_body.nbr), np.nan, dtype=np.float32)
        slips = np.zeros((len(self.global_body.nbr), 3), dtype=np.float32)
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
        n, p = self.global_n, len(self.global_body.nbr)
        for k, size in (("y", n), ("v", n), ("f", n), ("theta", n), ("broken", p)):
            if len(state[k]) != size:
                raise ValueError(f"ice body '{self.name}': {k} has {len(state[k])} entries in "
                                 f"the checkpoint, {size} in the case")
        loc, pairs = self.plan.local, self.plan.pairs
        self.body.restore_state({"y": state["y"][loc], "v": state["v"][loc],
                                 "f": state["f"][loc], "theta": state["theta"][loc],
                                 "broken": state["broken"][pairs], "time": state["time"],
                                 "external_work": self._rank_part(state, "external_work"),
                                 "fracture_dissipated":
                                     self._rank_part(state, "fracture_dissipated"),
                                 **({} if self.body.rest is None
                                    else {"rest": state["rest"][pairs]}),
                                 **({} if self.body.shear is None
                                    else {"slip": state["slip"][pairs]}),
                                 **{k: state[k][loc] for k in ("rate_theta", "rate_factors")
                                    if k in state}})
        self._counted_broken = self._broken_count()
        self.update_intact_volume()  # the halo's from their owners

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
