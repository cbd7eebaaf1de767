"""Failure laws of ice bonds (:mod:`pdfem.pd.failure.base`) and their registry.

:data:`FAILURE_LAWS` maps a law's name to its builder ``(material, delta) -> law``; a new law is
one new file in this package and one line here.
"""

from __future__ import annotations

from collections.abc import Callable

from pdfem.pd.failure.base import FailureLaw
from pdfem.pd.failure.critical_stretch import CriticalStretch
from pdfem.pd.failure.ice import IceFailure

FAILURE_LAWS: dict[str, Callable[..., FailureLaw]] = {
    "critical_stretch": CriticalStretch.from_material,
    "ice": IceFailure.from_material,
}
"""Failure-law name -> builder ``(material, delta) -> FailureLaw``."""

DEFAULT_FAILURE_LAW = "critical_stretch"


def failure_law(name: str, material, delta: float) -> FailureLaw:
    """Build the failure law ``name`` for an ice material and horizon ``delta`` (m).

    Raises
    ------
    ValueError
        For an unknown name (the message lists the known ones).
    """
    try:
        build = FAILURE_LAWS[name]
    except KeyError:
        raise ValueError(f"unknown failure law {name!r}; valid: "
                         f"{', '.join(repr(k) for k in FAILURE_LAWS)}") from None
    return build(material, delta)


__all__ = ["DEFAULT_FAILURE_LAW", "FAILURE_LAWS", "CriticalStretch", "FailureLaw", "IceFailure",
           "failure_law"]
