"""The critical-stretch failure law: a bond breaks for good when its stretch exceeds s0.

s0 is the material's given critical stretch, or its tensile strength over Young's modulus
(``s0 = sigma_t / E``, the same at every horizon; a flexural strength is turned into sigma_t
when the material is built, docs/ice_strength.md), or follows from its fracture energy G0 and
the horizon delta (:func:`pdfem.pd.materials.lps.critical_stretch`, 3-D OSB-PD); without any
of them the bonds never break (s0 = inf). The numba kernels compare each bond's stretch with
:meth:`CriticalStretch.stretch_limit`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class CriticalStretch:
    """Bonds with stretch ``e / |xi| > s0`` break (no-fail particles excepted, in the kernels).

    Parameters
    ----------
    s0
        The critical stretch (dimensionless, > 0; ``inf``: bonds never break).
    """

    s0: float
    name: str = "critical_stretch"
    broken_bonds_push: bool = False
    crush_yield: float = math.inf
    crush_friction: float = 0.0
    rate_dependent: bool = False

    @classmethod
    def from_material(cls, material, delta: float) -> "CriticalStretch":
        """The law of an ice material (:class:`pdfem.pd.materials.lps.IceMaterial`) at
        horizon ``delta`` (m): ``s0 = material.s0(delta)``."""
        return cls(float(material.s0(delta)))

    def stretch_limit(self) -> float:
        """s0, the stretch above which a bond breaks."""
        return self.s0

    def stretch_limits(self) -> tuple[float, ...]:
        """(s0, 0, -inf, 0, -inf, 0): above s0 at any dilatation, never in compression."""
        return (self.s0, 0.0, -math.inf, 0.0, -math.inf, 0.0)

    def strength_factor(self, rate):
        """1: no compressive strength to scale."""
        return 1.0

    def describe(self) -> str:
        """``critical stretch s0 = ...``."""
        return f"critical stretch s0 = {self.s0:.3e}"
