"""The failure-law interface: which bonds of an ice body break, given its state.

The bond loop itself is a numba kernel (:func:`pdfem.pd.bonds.kernels.dilatation_and_forces` and the
full-family reference), which breaks a bond for good when its stretch ``s = e / |xi|`` leaves
the interval [s_min, s_max] and neither end is a no-fail particle. The bounds are linear in the
bond's mean dilatation theta = (theta_i + theta_j) / 2 (the volumetric strain of its ends, which
the step has just computed)::

    s_max = t0 + t1 theta,      s_min = min(c0 + c1 theta, d0 + d1 theta)

so a law can bound the bond's normal stress sigma_n = lambda theta + 2 mu s from above
(tension) and below (compression, with a pressure dependence), not just its stretch. A failure
law is the object that supplies (t0, t1, c0, c1, d0, d1): the kernels stay plain functions over flat
arrays, the law decides what they compare the stretch with, and the ice body
(:class:`pdfem.pd.body.IceBody`) holds one law and hands its :meth:`FailureLaw.stretch_limits`
to the kernel every step. Every rank of a distributed body evaluates a bond from the same
positions and exchanged dilatations, so the decisions agree on all ranks.

Adding a law
------------
Write one new file in :mod:`pdfem.pd.failure` with a class implementing :class:`FailureLaw`
(its ``from_material(material, delta)`` builds it from the ice material and horizon) and add one
line to :data:`pdfem.pd.failure.FAILURE_LAWS`. A law that needs more than these bounds (e.g. a
per-bond limit array, or a history variable) brings its kernel variant along and says so in its
``stretch_limits`` docstring.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable


@runtime_checkable
class FailureLaw(Protocol):
    """What an ice body needs from a failure law (SI units)."""

    name: str
    """Registry name of the law (:data:`pdfem.pd.failure.FAILURE_LAWS`)."""

    broken_bonds_push: bool
    """True if a broken bond keeps pushing its ends apart when compressed below the length it
    broke at (crushed ice: :func:`pdfem.pd.bonds.lps_law.crushed_bond`); False: broken bonds
    carry nothing."""

    crush_yield: float
    """The yield compression (stretch) of those pushing bonds (:func:`pdfem.pd.bonds.lps_law.
    crushed_bond`); ``inf`` if they do not push."""

    crush_friction: float
    """The friction coefficient between the ends of a pushing bond (:func:`pdfem.pd.bonds.lps_law.
    crushed_friction`, -); 0 if they do not push."""

    rate_dependent: bool
    """True if the compressive strength depends on the strain rate (:meth:`strength_factor`,
    rates from :mod:`pdfem.pd.failure.strain_rate`)."""

    def strength_factor(self, rate):
        """Factors (-) on the compressive strength for strain rates ``rate`` (1/s, array)."""
        ...

    def stretch_limits(self) -> tuple[float, ...]:
        """(t0, t1, c0, c1, d0, d1): a bond breaks when its stretch (dimensionless) is above
        t0 + t1 theta or below min(c0 + c1 theta, d0 + d1 theta) (module doc); ``inf`` /
        ``-inf``: never."""
        ...

    def describe(self) -> str:
        """One line for the run log: the law and its thresholds (SI)."""
        ...
