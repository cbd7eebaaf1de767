"""A rank's part of an ice body's checkpoint, keyed by global particle numbers (no global array).

A checkpoint part holds the state of the particles one rank owns, each with its global number
(``gid``), and the state of the bonds it counts (those in its owned particles' rows) that differ
from a fresh bond: broken, crushed (``rest`` not NaN) or with a stretched shear spring
(``slip``), each named by its two ends' global numbers ``(bond_i, bond_j)``. Bonds not listed
are intact (``broken`` 0, ``rest`` NaN, ``slip`` 0). Neither side needs the other's partition:
a restart on any number of ranks picks, from every part, the particles and bonds it holds
(:class:`PartPicker`), chunk by chunk, so no rank ever holds a global array. Units: SI, as the
body's own state (:mod:`pdfem.pd.checkpoint.state`: m, m/s, N/m^3, J, s).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

PARTICLE_KEYS = ("y", "v", "f", "theta", "rate_theta", "rate_factors")
"""Per-particle state arrays of a body (those of them the body has)."""

BOND_KEYS = ("broken", "rest", "slip")
"""Per-bond state arrays of a body (those of them the body has)."""

BOND_BLOCK = 1 << 15
"""Listed bonds matched at a time (each expands to its first end's row, ~100 entries)."""

SCALAR_KEYS = ("time", "external_work", "fracture_dissipated")
"""Scalar state of a body: the time (s, the same in every part) and each rank's part of the
two energy counters (J)."""


@dataclass
class PartLayout:
    """Which particles and bonds a rank holds of a body.

    Attributes
    ----------
    gid
        (n_local,) ascending global numbers of the local (owned and halo) particles.
    owned
        (n_local,) bool, owned by this rank.
    counted
        (P_local,) bool, the bonds in the owned particles' rows (each bond on one rank).
    row_ptr, nbr
        The local bond list (rows of local particles, local neighbour numbers).
    n_global
        Number of particles of the whole body.
    """

    gid: np.ndarray
    owned: np.ndarray
    counted: np.ndarray
    row_ptr: np.ndarray
    nbr: np.ndarray
    n_global: int

    def bond_ends(self) -> tuple[np.ndarray, np.ndarray]:
        """Global numbers (i, j) of both ends of every local bond."""
        i_of = np.repeat(np.arange(len(self.gid)), np.diff(self.row_ptr))
        return self.gid[i_of], self.gid[np.asarray(self.nbr, dtype=np.int64)]


def owned_part(layout: PartLayout, state: dict) -> tuple[dict, dict, dict]:
    """This rank's part of a body's local state (``checkpoint_state()`` of its local body).

    Returns
    -------
    particles, bonds, scalars
        ``{"gid", "y", ...}`` over the owned particles; ``{"bond_i", "bond_j", "broken", ...}``
        over the counted bonds whose state is not a fresh bond's; the scalars.
    """
    own = layout.owned
    particles = {"gid": layout.gid[own]}
    particles.update({k: state[k][own] for k in PARTICLE_KEYS if k in state})
    keep = layout.counted & (np.asarray(state["broken"]) != 0)
    if "rest" in state:
        keep |= layout.counted & ~np.isnan(state["rest"])
    if "slip" in state:
        keep |= layout.counted & np.any(state["slip"] != 0, axis=1)
    edges = np.flatnonzero(keep)
    rows = np.searchsorted(layout.row_ptr, edges, side="right") - 1
    bonds = {"bond_i": layout.gid[rows],
             "bond_j": layout.gid[np.asarray(layout.nbr[edges], dtype=np.int64)]}
    bonds.update({k: np.asarray(state[k])[edges] for k in BOND_KEYS if k in state})
    return particles, bonds, {k: float(state[k]) for k in SCALAR_KEYS}


class PartPicker:
    """Collects a rank's local state from the parts of a checkpoint written on any number of
    ranks: feed it chunks of every part's particles and bonds, then take :meth:`state`.

    Parameters
    ----------
    layout
        The rank's :class:`PartLayout` of the body.
    template
        The local body's own ``checkpoint_state()`` (a copy): its arrays are filled in place
        and returned by :meth:`state` (bonds start fresh: ``broken`` 0, ``rest`` NaN, ``slip``
        0), so a restore needs no second copy of the local state.
    """

    def __init__(self, layout: PartLayout, template: dict) -> None:
        self.layout = layout
        self.arrays = {k: template[k] for k in PARTICLE_KEYS if k in template}
        self.found = np.zeros(len(layout.gid), dtype=np.int64)
        self.bonds = {k: template[k] for k in BOND_KEYS if k in template}
        self.bonds["broken"][:] = 0
        if "rest" in self.bonds:
            self.bonds["rest"][:] = np.nan
        if "slip" in self.bonds:
            self.bonds["slip"][:] = 0
        self.unmatched = 0  # bonds of owned rows in the parts that are not local bonds

    def wanted(self, gid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(hit, local position) of global particle numbers ``gid`` among the local ones."""
        return locate(self.layout.gid, gid)

    def take_particles(self, hit: np.ndarray, pos: np.ndarray, values: dict) -> None:
        """Put the hit rows of a chunk of a part's particle arrays ``values`` in place."""
        where = pos[hit]
        self.found[where] += 1
        for k, a in self.arrays.items():
            if k not in values:
                raise ValueError(f"'{k}' is missing from a part of the checkpoint")
            a[where] = values[k][hit]

    def take_bonds(self, values: dict) -> None:
        """Put a chunk of a part's listed bonds (``bond_i``, ``bond_j``, states) in place: each
        is looked for in the local row of its first end (no bond-sized temporary)."""
        for a in range(0, len(values["bond_i"]), BOND_BLOCK):
            block = {k: v[a:a + BOND_BLOCK] for k, v in values.items()}
            hit, where = self._find_bonds(block["bond_i"], block["bond_j"])
            for k, arr in self.bonds.items():
                if k not in block:
                    raise ValueError(f"'{k}' is missing from a part of the checkpoint")
                arr[where] = block[k][hit]

    def _find_bonds(self, bi: np.ndarray, bj: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(hit, local bond number of the hits) of bonds named by their ends' global numbers;
        counts in :attr:`unmatched` the bonds of owned rows that are not local bonds."""
        lay = self.layout
        hit_i, li = locate(lay.gid, bi)
        hit_j, lj = locate(lay.gid, bj)
        start = lay.row_ptr[li]
        length = np.where(hit_i & hit_j, lay.row_ptr[li + 1] - start, 0)
        owner = np.repeat(np.arange(len(bi)), length)
        edge = np.repeat(start - np.cumsum(length) + length, length) + np.arange(length.sum())
        match = np.asarray(lay.nbr)[edge] == lj[owner]
        hit = np.zeros(len(bi), dtype=bool)
        where = np.zeros(len(bi), dtype=np.int64)
        hit[owner[match]] = True
        where[owner[match]] = edge[match]
        owned_row = hit_i & lay.owned[li]
        self.unmatched += int(np.count_nonzero(owned_row & ~hit))
        return hit, where[hit]

    def state(self, scalars: dict, name: str) -> dict:
        """The local state for the local body's ``restore_state`` (scalars given).

        Raises
        ------
        ValueError
            If a local particle is missing from the parts or held twice, or a bond of an owned
            particle in the parts is not one of the body's.
        """
        bad = np.flatnonzero(self.found != 1)
        if len(bad):
            g = int(self.layout.gid[bad[0]])
            raise ValueError(f"ice body '{name}': particle {g} appears {int(self.found[bad[0]])} "
                             f"times in the checkpoint's parts ({len(bad)} such particles)")
        if self.unmatched:
            raise ValueError(f"ice body '{name}': {self.unmatched} bonds of the checkpoint are "
                             "not bonds of the case's body")
        return {**self.arrays, **self.bonds, **scalars}


def locate(local: np.ndarray, gid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(hit, position) of global numbers ``gid`` in the ascending global numbers ``local``
    (``position`` is meaningful where ``hit``)."""
    if len(local) == 0:
        return np.zeros(len(gid), dtype=bool), np.zeros(len(gid), dtype=np.int64)
    pos = np.minimum(np.searchsorted(local, gid), len(local) - 1)
    return local[pos] == gid, pos


def rank_scalars(parts: list[dict], rank: int, size: int) -> dict:
    """The scalars a rank restores from the parts' scalars (in rank order): its own part's when
    the checkpoint was written on as many ranks (bit for bit), else the totals, summed in rank
    order as the counters' allreduce sums them, on rank 0 and 0 on the others."""
    if len(parts) == size:
        return dict(parts[rank])
    out = {"time": parts[0]["time"]}
    for k in SCALAR_KEYS[1:]:
        total = 0.0
        for p in parts:
            total = total + p[k]
        out[k] = total if rank == 0 else 0.0
    return out
