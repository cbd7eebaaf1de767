"""Before anything is built: the particles, bonds and memory a case needs, refused if too much."""

from __future__ import annotations

from pdfem.case.schema import Case
from pdfem.errors import InputError
from pdfem.run.estimates import (FIXED_BYTES, BodyEstimate, available_memory, estimate_body,
                                 format_bytes)


def estimate_case(case: Case) -> list[BodyEstimate]:
    """Particles, pairs and memory of every ice body of a case, before building
    (:func:`pdfem.run.estimates.estimate_body`)."""
    return [estimate_body(c.name, c.shape, c.dx, c.horizon) for c in case.ice]


def check_memory(case: Case, estimates: list[BodyEstimate], available: int | None) -> int:
    """The estimated memory (bytes) of the run; refuse it if it exceeds ``available`` bytes.

    Raises
    ------
    InputError
        Naming the body that needs most, with the estimate and what is available.
    """
    need = FIXED_BYTES + sum(e.bytes for e in estimates)
    if available is not None and estimates and need > available:
        big = max(range(len(estimates)), key=lambda k: estimates[k].bytes)
        e = estimates[big]
        raise InputError(case.file, f"{case.ice[big].field}.dx",
                         f"the run needs about {format_bytes(need)} of memory but "
                         f"{format_bytes(available)} is available; ice body '{e.name}' alone has "
                         f"about {e.particles:,} particles and {e.pairs:,} bonds "
                         f"({format_bytes(e.bytes)}); choose a larger dx, a smaller body, or a "
                         "machine with more memory", case.ice[big].dx)
    return need


def preflight(case: Case) -> list[str]:
    """Estimate the ice of ``case`` and refuse a run that cannot fit; the report lines.

    Raises
    ------
    InputError
        From :func:`check_memory`.
    """
    estimates = estimate_case(case)
    available = available_memory()
    need = check_memory(case, estimates, available)
    lines = [f"  estimate for ice '{e.name}': {e.particles:,} particles, {e.pairs:,} bonds "
             f"({e.pairs_per_interior_particle} per interior particle"
             f"{'' if e.exact else ', an upper bound'}), {format_bytes(e.bytes)}"
             for e in estimates]
    if estimates:
        lines.append(f"  estimated memory {format_bytes(need)} of "
                     f"{format_bytes(available) if available else 'unknown'} available")
    return lines
