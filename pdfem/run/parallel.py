"""What a run needs to go parallel, in a few calls the driver makes without knowing MPI.

* :func:`build_structures`: rank 0 meshes the structure models into the output directory, then
  every rank reads the same meshes (the structures are small and replicated on every rank).
* :func:`report_partitions`: how each ice body is split over the ranks (the ice bodies are built
  split from the start: :meth:`pdfem.pd.body.IceBody.from_shape`);
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
from pdfem.geometry.cell_hash import in_box
from pdfem.run.build_structures import build_all
from pdfem.motion.rigid import RigidBody
from pdfem.pd.body import IceBody
from pdfem.pd.materials.lps import IceMaterial
from pdfem.geometry.shapes import Box
from pdfem.pd.layout.split import split_body
from pdfem.parallel.partition import BYTES_PER_HALO_PARTICLE, choose_partition


MAX_RANKS_LISTED = 16
"""Up to this many ranks the start-up report lists every rank's particles, halo and neighbours."""


def build_structures(configs, out: Path, file: str, comm) -> list:
    """The case's structures on every rank, meshed once (by rank 0), each sharing its own work
    over the ranks (:meth:`pdfem.fem.base.Structure.distribute`)."""
    if comm.size == 1:
        built = build_all(configs, out, file)
    else:
        # rank 0 meshes; if it fails, run_guarded aborts the job while the others wait in bcast
        first = build_all(configs, out, file) if comm.rank == 0 else None
        comm.bcast(True)
        built = first if comm.rank == 0 else build_all(configs, out, file, remesh=False)
    for s in built:
        s.distribute(comm)
    return built


def report_partitions(bodies: list, comm, say=lambda s: None) -> None:
    """Report how each body is split over the ranks (nothing on one rank; collective)."""
    if comm.size == 1:
        return
    for b in bodies:
        lay = b.layout
        figures = comm.allgather((int(lay.owned.sum()), int((~lay.owned).sum()),
                                  len(lay.plan.recv)))
        owned, halo, nbrs = (np.array(v) for v in zip(*figures))
        _say_split(say, b.name, lay.partition, owned, halo, nbrs,
                   halo.sum() * BYTES_PER_HALO_PARTICLE / 1e6, comm.size)


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


def warm_up() -> None:
    """Run two steps of a tiny ice cube pressed by a rigid plate (with short-range contact),
    split over one 'rank', and set up a tiny body the distributed way."""
    mat = IceMaterial(density=900.0, youngs_modulus=4e9, poisson_ratio=0.3, fracture_energy=1.0)
    body = IceBody.from_shape("warm", Box((0, 0, 0), (0.05, 0.05, 0.05)), mat, 0.01, 0.03015)
    owner, _ = choose_partition(body.x0, body.row_ptr, body.nbr, 1)
    ice = split_body(body, owner, SerialComm())
    plate = RigidBody(np.array([[-1, -1, 0.0501], [1, -1, 0.0501], [1, 1, 0.0501],
                                [-1, 1, 0.0501]]), np.array([[0, 1, 2], [0, 2, 3]]),
                      velocity=(0, 0, -1.0))
    pair = ContactPair("warm", ice, plate, SurfaceContact(plate, 0.005))
    c = Coupler([ice], [plate], [pair], 1e-6, forces=[ShortRangeContact([ice])],
                comm=SerialComm())
    c.start()
    for _ in range(2):
        c.step()
    lone = np.zeros((2, 3))  # the refresh's kernel too
    in_box(lone, lone[0], lone[1])
    ice.kinetic_energy()
    ice.strain_energy()
    ice.gather(ice.damage())
    body.stable_time_step()


def warm_before_ranks(comm) -> None:
    """Under MPI: rank 0 warms the kernel cache while the others wait."""
    if comm.size == 1:
        return
    if comm.rank == 0:
        warm_up()
    comm.bcast(True)
