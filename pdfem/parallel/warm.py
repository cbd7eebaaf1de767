"""Compile (or load) every numba kernel of a run once, before several MPI ranks start.

numba caches compiled kernels on disk; several processes compiling the same kernel at once may
write the cache at the same time, which can fail. Under mpiexec, rank 0 runs :func:`warm_up`
(a tiny coupled problem through every kernel a run uses, on one process) while the other ranks
wait; then all ranks load the kernels from the cache.
"""

from __future__ import annotations

import numpy as np

from ..coupling.contact import SurfaceContact
from ..coupling.coupler import ContactPair, Coupler
from ..fem.rigid import RigidBody
from ..pd.body import IceBody
from ..pd.material import IceMaterial
from ..shapes import Box
from .comm import SerialComm
from .distributed import DistributedIce
from .partition import choose_partition


def warm_up() -> None:
    """Run two steps of a tiny ice cube pressed by a rigid plate, split over one 'rank'."""
    mat = IceMaterial(density=900.0, youngs_modulus=4e9, poisson_ratio=0.3, fracture_energy=1.0)
    body = IceBody.from_shape("warm", Box((0, 0, 0), (0.05, 0.05, 0.05)), mat, 0.01, 0.03015)
    owner, _ = choose_partition(body.x0, body.row_ptr, body.nbr, 1)
    ice = DistributedIce(body, owner, SerialComm())
    plate = RigidBody(np.array([[-1, -1, 0.0501], [1, -1, 0.0501], [1, 1, 0.0501],
                                [-1, 1, 0.0501]]), np.array([[0, 1, 2], [0, 2, 3]]),
                      velocity=(0, 0, -1.0))
    pair = ContactPair("warm", ice, plate, SurfaceContact(plate, 0.005))
    c = Coupler([ice], [plate], [pair], 1e-6, comm=SerialComm())
    c.start()
    for _ in range(2):
        c.step()
    ice.kinetic_energy()
    ice.strain_energy()
    ice.gather(ice.damage())


def warm_before_ranks(comm) -> None:
    """Under MPI: rank 0 warms the kernel cache while the others wait."""
    if comm.size == 1:
        return
    if comm.rank == 0:
        warm_up()
    comm.bcast(True)
