"""The failure-law interface: which bonds of an ice body break, given its state.

The bond loop itself is a numba kernel (:func:`pdfem.pd.kernels.dilatation_and_forces` and the
full-family reference), which breaks a bond for good when its stretch ``e / |xi|`` exceeds a
threshold and neither end is a no-fail particle. A failure law is the object that supplies that
threshold: the kernels stay plain functions over flat arrays, the law decides what they compare
the stretch with, and the ice body (:class:`pdfem.pd.body.IceBody`) holds one law and hands its
:meth:`FailureLaw.stretch_limit` to the kernel every step.

Adding a law
------------
Write one new file in :mod:`pdfem.pd.failure` with a class implementing :class:`FailureLaw`
(its ``from_material(material, delta)`` builds it from the ice material and horizon) and add one
line to :data:`pdfem.pd.failure.FAILURE_LAWS`. A law that needs more than a scalar stretch limit
(e.g. a per-bond limit array, or a criterion on the dilatation) brings its kernel variant along
and says so in its ``stretch_limit`` docstring.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable


@runtime_checkable
class FailureLaw(Protocol):
    """What an ice body needs from a failure law (SI units)."""

    name: str
    """Registry name of the law (:data:`pdfem.pd.failure.FAILURE_LAWS`)."""

    def stretch_limit(self) -> float:
        """The stretch (dimensionless) above which the kernels break a bond; ``inf``: never."""
        ...
