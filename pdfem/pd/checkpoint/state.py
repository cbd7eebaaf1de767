"""Checkpoint state of an ice body: which arrays and scalars a restart needs, bit for bit.

Functions of an :class:`~pdfem.pd.body.IceBody` (whole, or a rank's part: the arrays are the
local ones, the two energy counters this process's parts). A checkpoint stores each process's
owned particles and counted bonds under their global numbers (:mod:`pdfem.pd.checkpoint.parts`,
written by :mod:`pdfem.run.checkpoint`), so a restart on any number of ranks gives each rank the
state of its local particles and bonds. SI units: m, m/s, N/m^3, J, s.
"""

from __future__ import annotations

import numpy as np

from pdfem.pd.checkpoint.parts import PartLayout

STATE_ARRAYS = ("y", "v", "f", "broken", "theta")
"""Per-particle (and per-bond: ``broken``) state arrays of an ice body, for checkpoints."""

STATE_SCALARS = ("time", "external_work", "fracture_dissipated")
"""Scalar state of an ice body (s, J, J; the energies this process's parts), for checkpoints."""

_LOCAL = {"external_work": "local_external_work",
          "fracture_dissipated": "local_fracture_dissipated", "time": "time"}


def checkpoint_state(body) -> dict:
    """Copies of the state a restart needs: arrays :data:`STATE_ARRAYS` (``y`` m, ``v`` m/s,
    ``f`` N/m^3, ``broken`` uint8 per bond, ``theta``), scalars :data:`STATE_SCALARS` (``time``
    s, and this process's parts of ``external_work`` and ``fracture_dissipated`` J) and, for a
    body whose broken bonds push, ``rest`` (float32 per bond) and, with friction, their shear
    springs' ``slip`` ((P, 3) float32, m), and for a rate-dependent law ``rate_theta`` and
    ``rate_factors`` (per particle)."""
    out = {k: np.array(getattr(body, k)) for k in STATE_ARRAYS}
    out.update({k: float(getattr(body, _LOCAL[k])) for k in STATE_SCALARS})
    if body.rest is not None:
        out["rest"] = body.rest.copy()
    if body.shear is not None:
        out["slip"] = body.shear.slip.copy()
    if body.rates is not None and body.rates.theta is not None:
        out["rate_theta"] = body.rates.theta.copy()
        if body.rates.factors is not None:
            out["rate_factors"] = body.rates.factors.copy()
    return out


def restore_state(body, state: dict) -> None:
    """Put a state from :func:`checkpoint_state` back into ``body``, in place and bit for bit
    (collective: the halo's weighted volumes of the intact bonds come from their owners).

    Raises
    ------
    ValueError
        If an array's shape differs from the body's.
    """
    for k in STATE_ARRAYS:
        value = np.asarray(state[k])
        target = getattr(body, k)
        if value.shape != target.shape:
            raise ValueError(f"ice body '{body.name}': {k} has shape {value.shape} in the "
                             f"checkpoint, {target.shape} in the case")
        if k == "broken":
            body.broken = value.astype(np.uint8)  # kept in the signed weights
        else:
            target[...] = value
    body.workspace.lengths_current = False  # other positions and bonds than its last pass
    for k in STATE_SCALARS:
        setattr(body, _LOCAL[k], float(state[k]))
    if body.rest is not None:
        body.rest[:] = np.asarray(state["rest"], dtype=np.float32)
    if body.shear is not None:
        body.shear.slip[:] = np.asarray(state["slip"], dtype=np.float32)
    if body.rates is not None:
        body.rates.theta = (np.array(state["rate_theta"], dtype=np.float64)
                            if "rate_theta" in state else None)
        body.rates.factors = (np.array(state["rate_factors"], dtype=np.float64)
                              if "rate_factors" in state else None)


def part_layout(body) -> PartLayout:
    """Global numbers of the local particles, which are owned, which bonds this process counts
    (the owned particles' rows) and the local bond list: the layout now (particles may move
    between ranks during a run)."""
    lay = body.layout
    return PartLayout(lay.gid, lay.owned, body.counted_bonds(), body.row_ptr, body.nbr,
                      int(lay.n_global))
