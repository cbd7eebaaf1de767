"""What a run needs to go parallel, in three calls the driver makes without knowing MPI.

* :func:`build_structures`: rank 0 meshes the structure models into the output directory, then
  every rank reads the same meshes (the structures are small and replicated on every rank).
* :func:`distribute`: split each ice body over the ranks (the partition is reported), or leave
  it whole on a single rank.
* :func:`gather_frame`: the per-particle fields of a frame assembled on rank 0.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..fem.build import build_structure
from .distributed import DistributedIce
from .partition import choose_partition


def build_structures(configs, out: Path, file: str, comm) -> list:
    """The case's structures on every rank, meshed once (by rank 0)."""
    if comm.size == 1:
        return [build_structure(cfg, out, file) for cfg in configs]
    # rank 0 meshes; if it fails, run_guarded aborts the job while the others wait in bcast
    first = [build_structure(cfg, out, file) for cfg in configs] if comm.rank == 0 else None
    comm.bcast(True)
    if comm.rank == 0:
        return first
    return [build_structure(cfg, out, file, remesh=False) for cfg in configs]


def distribute(bodies: list, comm, say=lambda s: None) -> list:
    """Each body split over the ranks by :func:`~pdfem.parallel.partition.choose_partition`
    (the bodies themselves when there is one rank); the partition is reported with ``say``."""
    if comm.size == 1:
        return bodies
    out = []
    for b in bodies:
        owner, st = choose_partition(b.x0, b.row_ptr, b.nbr, comm.size)
        say(f"  partition of '{b.name}' over {comm.size} ranks: {st.name}; particles per rank "
            f"{int(st.owned.min()):,}-{int(st.owned.max()):,} (imbalance {st.imbalance:.1e}), "
            f"halo up to {int(st.halo.max()):,}, up to {int(st.neighbours.max())} neighbours")
        out.append(DistributedIce(b, owner, comm))
    return out


def gather_frame(body) -> dict | None:
    """``{"u", "v", "damage"}`` of a body in global order on rank 0 (``None`` elsewhere)."""
    if not isinstance(body, DistributedIce):
        return {"u": body.displacement(), "v": body.v, "damage": body.damage()}
    u = body.gather(body.body.displacement())
    v = body.gather(body.body.v)
    d = body.gather(body.damage())
    return None if u is None else {"u": u, "v": v, "damage": d}


def any_rank(flag: bool, comm) -> bool:
    """True on every rank if ``flag`` is true on any."""
    return bool(comm.allreduce_sum(np.int64(bool(flag))))
