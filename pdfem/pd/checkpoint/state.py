"""Checkpoint state of an ice body: which arrays and scalars a restart needs, bit for bit.

:class:`BodyCheckpoint` is mixed into :class:`pdfem.pd.body.IceBody`; the arrays it names are
the body's attributes (SI: m, m/s, N/m^3, J, s).
"""

from __future__ import annotations

import numpy as np


class BodyCheckpoint:
    """``checkpoint_state`` / ``restore_state`` of an ice body (whole, one rank)."""

    def checkpoint_state(self) -> dict:
        """Copies of the state that a restart needs: arrays :data:`STATE_ARRAYS` (``y`` m,
        ``v`` m/s, ``f`` N/m^3, ``broken`` uint8 per bond, ``theta``), scalars
        :data:`STATE_SCALARS` (``time`` s, ``external_work`` J, ``fracture_dissipated`` J) and,
        for a body whose broken bonds push, ``rest`` (float32 per bond) and, with friction, their
        shear springs' ``slip`` ((P, 3) float32, m), and for a rate-dependent
        law ``rate_theta`` and ``rate_factors`` (per particle)."""
        out = {k: np.array(getattr(self, k)) for k in STATE_ARRAYS}
        out.update({k: float(getattr(self, k)) for k in STATE_SCALARS})
        if self.rest is not None:
            out["rest"] = self.rest.copy()
        if self.shear is not None:
            out["slip"] = self.shear.slip.copy()
        if self.rates is not None and self.rates.theta is not None:
            out["rate_theta"] = self.rates.theta.copy()
            if self.rates.factors is not None:
                out["rate_factors"] = self.rates.factors.copy()
        return out

    def restore_state(self, state: dict) -> None:
        """Put a state from :meth:`checkpoint_state` back, in place and bit for bit.

        Raises
        ------
        ValueError
            If an array's shape differs from the body's.
        """
        for k in STATE_ARRAYS:
            value = np.asarray(state[k])
            target = getattr(self, k)
            if value.shape != target.shape:
                raise ValueError(f"ice body '{self.name}': {k} has shape {value.shape} in the "
                                 f"checkpoint, {target.shape} in the case")
            if k == "broken":
                self.broken = value.astype(np.uint8)  # kept in the signed weights or the flags
            else:
                target[...] = value
        for k in STATE_SCALARS:
            setattr(self, k, float(state[k]))
        if self.rest is not None:
            self.rest[:] = np.asarray(state["rest"], dtype=np.float32)
        if self.shear is not None:
            self.shear.slip[:] = np.asarray(state["slip"], dtype=np.float32)
        if self.rates is not None:
            self.rates.theta = (np.array(state["rate_theta"], dtype=np.float64)
                                if "rate_theta" in state else None)
            self.rates.factors = (np.array(state["rate_factors"], dtype=np.float64)
                                  if "rate_factors" in state else None)


STATE_ARRAYS = ("y", "v", "f", "broken", "theta")
"""Per-particle (and per-bond: ``broken``) state arrays of an ice body, for checkpoints."""

STATE_SCALARS = ("time", "external_work", "fracture_dissipated")
"""Scalar state of an ice body (s, J, J), for checkpoints."""
