"""What a run needs to go parallel, in three calls the driver makes without knowing MPI.

* :func:`build_structures`: rank 0 meshes the structure models into the output directory, then
  every rank reads the same meshes (the structures are small and replicated on every rank).
* :func:`setup_comm`: whether the ice bodies are built split over the ranks from the start (the
  distributed set-up, :mod:`pdfem.pd.layout.setup`; the default under MPI where it
  applies) or whole on every rank and split afterwards;
* :func:`distribute`: split each whole ice body over the ranks (the partition is reported), or
  leave it whole on a single rank.
* :func:`warm_before_ranks`: rank 0 fills numba's kernel cache before the other ranks start.

Gathering a frame to rank 0 (or keeping each rank's particles) is the ice bodies' own business
(:class:`pdfem.pd.ice_interface.IceParticles`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pdfem.parallel.comm import SerialComm
from pdfem.coupling.contact import SurfaceContact
from pdfem.coupling.coupler import ContactPair, Coupler
from pdfem.forces.short_range import ShortRangeContact
from pdfem.forces.short_range_kernels import in_box, sparse_table
from pdfem.run.build_structures import build_all
from pdfem.fem.rigid import RigidBody
from pdfem.pd.body import IceBody
from pdfem.pd.materials.lps import IceMaterial
from pdfem.geometry.shapes import Box
from pdfem.pd.layout.halo import DistributedIce
from pdfem.pd.layout.setup import distributed_body, distributed_ice
from pdfem.parallel.partition import BYTES_PER_HALO_PARTICLE, choose_partition


MAX_RANKS_LISTED = 16
"""Up to this many ranks the start-up report lists every rank's particles, halo and neighbours."""


def build_structures(configs, out: Path, file: str, comm) -> list:
    """The case's structures on every rank, meshed once (by rank 0)."""
    if comm.size == 1:
        return build_all(configs, out, file)
    # rank 0 meshes; if it fails, run_guarded aborts the job while the others wait in bcast
    first = build_all(configs, out, file) if comm.rank == 0 else None
    comm.bcast(True)
    if comm.rank == 0:
        return first
    return build_all(configs, out, file, remesh=False)


def splits_bodies(case) -> bool:
    """Whether an MPI run of ``case`` builds its ice bodies split over the ranks by the
    distributed set-up (:mod:`pdfem.pd.layout.setup`: no rank holds a whole body).

    The global set-up (every rank builds each whole body, then keeps its part) stays only for
    the full-family PD loop (the per-particle reference loop). Every shape is generated per
    rank: the analytic ones and closed surface meshes alike answer the same point test for a
    rank's box as for the whole body (each rank holds the surface mesh, not the particles).
    Water acts per owned particle and checkpoints per rank, so it needs no whole body either.
    Short-range contact (on, or implied by a crushing failure law) needs no whole body: each
    rank searches its own particles and a contact halo (:mod:`pdfem.forces.short_range_halo`),
    and a crushing law's bond state (rest lengths, shear springs) is per bond, built for the
    local bonds."""
    return case.run.pd_loop == "pairs"


def setup_comm(case, comm):
    """``comm`` if the case's ice bodies are built split over its ranks (:func:`splits_bodies`,
    more than one rank), else None."""
    return comm if comm.size > 1 and splits_bodies(case) else None


def body_counts(b) -> tuple[int, int, int]:
    """Particles, bonds and broken bonds of a whole body or of a split one (collective)."""
    if b.distributed:
        return b.counts()
    return b.n, b.n_bonds, int(b.broken.sum())


def reference(b) -> tuple:
    """``(x0 m, vol m^3)`` of the whole body in global order (on rank 0 only for a body from
    the distributed set-up, ``(None, None)`` elsewhere; collective)."""
    if not b.distributed:
        return b.x0, b.vol
    return b.gather(b.x0), b.gather(b.vol)


def _say_split(say, name: str, how: str, owned, halo, nbrs, mb: float, ranks: int) -> None:
    """Report a body's partition: its kind, particles and halo per rank, traffic per step."""
    say(f"  partition of '{name}' over {ranks} ranks: {how}; particles per rank "
        f"{int(owned.min()):,}-{int(owned.max()):,} (imbalance "
        f"{owned.max() / owned.mean() - 1:.1e}), halo up to {int(halo.max()):,}, up to "
        f"{int(nbrs.max())} neighbours, {mb:.3g} MB exchanged per step")
    if ranks <= MAX_RANKS_LISTED:
        for r in range(ranks):
            say(f"    rank {r}: {int(owned[r]):,} particles, {int(halo[r]):,} halo, "
                f"{int(nbrs[r])} neighbours")


def _report_split(b, comm, say) -> None:
    """The partition of a body from the distributed set-up, as :func:`distribute` reports."""
    p = b.plan
    figures = comm.allgather((int(p.owned.sum()), int((~p.owned).sum()), len(p.recv)))
    owned, halo, nbrs = (np.array(v) for v in zip(*figures))
    _say_split(say, b.name, f"{b.partition_name} (distributed set-up)", owned, halo, nbrs,
               halo.sum() * BYTES_PER_HALO_PARTICLE / 1e6, comm.size)


def distribute(bodies: list, comm, say=lambda s: None) -> list:
    """Each body split over the ranks by :func:`~pdfem.parallel.partition.choose_partition`
    (the bodies themselves when there is one rank); the partition is reported with ``say``.
    Bodies already split by the distributed set-up are reported and kept."""
    if comm.size == 1:
        return bodies
    out = []
    for b in bodies:
        if b.distributed:
            _report_split(b, comm, say)
            out.append(b)
            continue
        owner, st = choose_partition(b.x0, b.row_ptr, b.nbr, comm.size)
        _say_split(say, b.name, st.name, st.owned, st.halo, st.neighbours,
                   st.bytes_per_step / 1e6, comm.size)
        out.append(DistributedIce(b, owner, comm))
    return out


def any_rank(flag: bool, comm) -> bool:
    """True on every rank if ``flag`` is true on any."""
    return bool(comm.allreduce_sum(np.int64(bool(flag))))


def warm_up() -> None:
    """Run two steps of a tiny ice cube pressed by a rigid plate (with short-range contact),
    split over one 'rank'."""
    mat = IceMaterial(density=900.0, youngs_modulus=4e9, poisson_ratio=0.3, fracture_energy=1.0)
    body = IceBody.from_shape("warm", Box((0, 0, 0), (0.05, 0.05, 0.05)), mat, 0.01, 0.03015)
    owner, _ = choose_partition(body.x0, body.row_ptr, body.nbr, 1)
    ice = DistributedIce(body, owner, SerialComm())
    plate = RigidBody(np.array([[-1, -1, 0.0501], [1, -1, 0.0501], [1, 1, 0.0501],
                                [-1, 1, 0.0501]]), np.array([[0, 1, 2], [0, 2, 3]]),
                      velocity=(0, 0, -1.0))
    pair = ContactPair("warm", ice, plate, SurfaceContact(plate, 0.005))
    c = Coupler([ice], [plate], [pair], 1e-6, forces=[ShortRangeContact([ice])],
                comm=SerialComm())
    c.start()
    for _ in range(2):
        c.step()
    lone = np.zeros((2, 3))  # the refresh's and the sparse table's kernels too
    in_box(lone, lone[0], lone[1])
    sparse_table(np.zeros(2, dtype=np.int64), np.empty(2, dtype=np.int64),
                 np.empty(3, dtype=np.int64))
    ice.kinetic_energy()
    ice.strain_energy()
    ice.gather(ice.damage())
    local, plan, census, _ = distributed_body("warm", Box((0, 0, 0), (0.05, 0.05, 0.05)), mat,
                                              0.01, 0.03015, SerialComm())
    distributed_ice(local, plan, SerialComm(), census.n).stable_time_step()


def warm_before_ranks(comm) -> None:
    """Under MPI: rank 0 warms the kernel cache while the others wait."""
    if comm.size == 1:
        return
    if comm.rank == 0:
        warm_up()
    comm.bcast(True)
