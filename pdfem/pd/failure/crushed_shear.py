"""The shear springs of crushed bonds: their per-bond state and what the force kernel reads.

Crushed ice (:mod:`pdfem.pd.failure.ice`) is granular and frictional. Besides its normal,
compression-only spring (:func:`pdfem.pd.bonds.lps_law.crushed_bond`), each crushed bond carries a
tangential spring with Coulomb slip (Cundall & Strack 1979, the usual discrete-element contact):
stiffness k_t = kappa k (k = b w V_i V_j the normal spring's), stretch ``slip`` (m, the sliding
of one end past the other since the bond was crushed, less what has slipped), force capped at
mu times the normal force (:func:`pdfem.pd.bonds.lps_law.crushed_shear`). A crushed layer therefore
resists being squeezed out of a contact zone in proportion to the pressure that confines it,
as a granular material with the friction angle of the intact ice's Coulomb envelope does.

The stretch advances once per time step by the step's change of the bond vector, so the state
needs the positions at the step's start (:meth:`CrushedShear.begin_step`); a force evaluation
without a step under way (set-up, restart) reads the stored stretch and changes nothing, so a
restart continues bit for bit. Its stored energy is part of the ice's strain energy and the
energy lost by slipping part of the dissipation. Units: SI.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

STIFFNESS_RATIO = 0.5
"""kappa = k_t / k_n of a crushed bond's shear spring (-). Discrete-element models of granular
media use 2/7 to 1 (Cundall & Strack 1979; Thornton 2015); the slip limit, not kappa, sets the
resistance of a flowing crushed layer."""

_NO_SLIP = np.zeros(0, dtype=np.float32)  # "no shear springs" (read-only by convention)
_NO_START = np.zeros((0, 3))  # "no step under way" (read-only by convention)


@dataclass
class CrushedShear:
    """The shear springs of a body's bonds (only crushed ones are ever non-zero).

    Attributes
    ----------
    slip
        (P, 3) float32, the springs' stretch (m), per bond in the body's bond order.
    friction
        mu = tan(phi) of the crushed ice (-).
    stiffness_ratio
        kappa = k_t / k_n (-).
    """

    slip: np.ndarray
    friction: float
    stiffness_ratio: float = STIFFNESS_RATIO
    _start: np.ndarray = field(default_factory=lambda: _NO_START, repr=False)
    _advance: bool = field(default=False, repr=False)

    @classmethod
    def for_bonds(cls, n_bonds: int, friction: float) -> CrushedShear:
        """Unstretched springs for ``n_bonds`` bonds with friction coefficient ``friction``."""
        return cls(np.zeros((n_bonds, 3), dtype=np.float32), float(friction))

    def subset(self, pairs: np.ndarray) -> CrushedShear:
        """The springs of the bonds ``pairs`` (an MPI rank's local bonds), copied."""
        return CrushedShear(self.slip[pairs].copy(), self.friction, self.stiffness_ratio)

    def begin_step(self, y: np.ndarray) -> None:
        """Remember the positions ``y`` (N, 3) (m) at the start of a step: the next force
        evaluation advances the springs by the step's change of each bond vector."""
        if self._start.shape != y.shape:
            self._start = np.empty_like(y)
        np.copyto(self._start, y)
        self._advance = True

    def kernel_args(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(flat slip, start positions, (mu, kappa, advance)) for the force kernel; the step's
        advance is used up by this call."""
        params = np.array([self.friction, self.stiffness_ratio, 1.0 if self._advance else 0.0])
        self._advance = False
        return self.slip.reshape(-1), self._start, params


def shear_kernel_args(shear: CrushedShear | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:meth:`CrushedShear.kernel_args`, or empty arrays for a body without shear springs."""
    if shear is None:
        return _NO_SLIP, _NO_START, np.zeros(3)
    return shear.kernel_args()


def shear_energy_args(shear: CrushedShear | None) -> dict:
    """The ``slip`` and ``kappa`` keywords of :func:`pdfem.pd.bonds.pair_sums.contact_bond_energy`
    (none for a body without shear springs)."""
    if shear is None:
        return {}
    return {"slip": shear.slip, "kappa": shear.stiffness_ratio}
