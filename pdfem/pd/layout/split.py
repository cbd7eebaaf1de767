"""A rank's part of a whole ice body, for any partition: the global set-up.

Every rank builds the same whole body (deterministically), then keeps its part for the
partition ``owner``: its owned particles and their halo, and every bond with an owned end, in
the global order (:func:`pdfem.pd.layout.halo.halo_plan`). Runs build their split bodies
without the whole body (:mod:`pdfem.pd.layout.setup`); this path serves bodies from arbitrary
point clouds, partitions given by hand (tests of 1 against N ranks) and the benchmarks. Memory
per rank does not fall with the rank count here. Units: SI.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from pdfem.pd.bonds.data import Bonds
from pdfem.pd.layout.halo import HaloLayout, halo_plan


def split_body(body, owner: np.ndarray, comm):
    """This rank's part of the whole ``body`` (an :class:`~pdfem.pd.body.IceBody` with its
    state, constraints and fixed set, identical on every rank) under the partition ``owner``
    ((N,) owner rank of each particle); collective.

    Returns
    -------
    IceBody
        The part, with a :class:`~pdfem.pd.layout.halo.HaloLayout`; its constraints keep the
        owned particles only.
    """
    owner = np.asarray(owner)
    plan = halo_plan(owner, body.row_ptr, body.nbr, comm.rank)
    loc, pairs = plan.local, plan.pairs
    g2l = np.full(body.n, -1, dtype=np.int64)
    g2l[loc] = np.arange(len(loc))
    i_of = body.bonds.row_of()[pairs]
    row_ptr = np.zeros(len(loc) + 1, dtype=np.int64)
    np.add.at(row_ptr, g2l[i_of] + 1, 1)
    row_ptr = np.cumsum(row_ptr)
    bonds = Bonds(row_ptr, g2l[body.nbr[pairs]].astype(np.int32), body.xi_len[pairs].copy(),
                  body.weight[pairs].copy())
    constraints = [dataclasses.replace(c, index=g2l[c.index[owner[c.index] == comm.rank]])
                   for c in body.constraints]
    state = {"y": body.y[loc].copy(), "v": body.v[loc].copy(), "constraints": constraints,
             "time": body.time, "gravity": body.gravity}
    if body.rest is not None:
        state["rest"] = body.rest[pairs].copy()
    if body.shear is not None:
        state["shear"] = body.shear.subset(pairs)
    layout = HaloLayout(comm, plan, body.n)
    return type(body)(body.name, body.x0[loc].copy(), body.vol[loc].copy(), body.material,
                      body.dx, body.delta, bonds, body.m[loc].copy(), layout=layout,
                      loop=body.loop, failure=body.failure, influence_gain=body.influence_gain,
                      nofail=body.nofail[loc].copy(), fixed=body.fixed[loc].copy(), state=state,
                      keep_bond_length=body.workspace.keep_bond_length)
