"""The per-step history groups of a results file as post-processing sees them.

Histories are named ``<kind>/<name>``: ``loads/<structure>`` (ice force on a structure),
``loads/<body>.<region>`` (reaction of an ice body's fixed or prescribed region: the force the
support or driver exerts on the ice; ``force`` only, no ``contacts``),
``loads/<structure>.<patch>`` (ice force on a load patch of a structure's contact surface:
``force`` and the patch's ``area``), ``contacts/<pair>`` (ice
force in a contact pair), ``monitors/<probe>``, ``structures/<name>`` (reactions, energies),
and ``energy``. :func:`histories_of` picks one kind, :func:`split_loads` tells the two kinds of
``loads`` apart; ``AXES`` names the components of a (K, 3) column.
"""

from __future__ import annotations

AXES = ("x", "y", "z")
"""Names of the components of a vector, in order."""


def histories_of(hist: dict, kind: str, key: str) -> dict[str, dict]:
    """The histories ``<kind>/<name>`` that have the column ``key``, by name, sorted.

    Parameters
    ----------
    hist
        ``results["histories"]`` of :func:`pdfem.post.load.load_results`.
    kind
        ``"loads"``, ``"contacts"`` or ``"monitors"``.
    key
        A column they must have, e.g. ``"force"`` or ``"u"``.

    Returns
    -------
    dict
        ``{name: history}``, e.g. ``{"panel": hist["loads/panel"]}``.
    """
    prefix = kind + "/"
    return {g[len(prefix):]: h for g, h in sorted(hist.items())
            if g.startswith(prefix) and key in h}


def split_loads(hist: dict) -> tuple[dict[str, dict], dict[str, dict]]:
    """The force histories of ``loads/``: ``(structure loads, region reactions)``, by name.

    A structure's load has the column ``contacts``; the reaction of an ice region
    (``loads/<body>.<region>``) has ``force`` only; load patches (:func:`patch_loads`) are
    neither.
    """
    loads = histories_of(hist, "loads", "force")
    return ({n: h for n, h in loads.items() if "contacts" in h},
            {n: h for n, h in loads.items() if "contacts" not in h and "area" not in h})


def patch_loads(hist: dict) -> dict[str, dict]:
    """The load patches' force histories ``loads/<structure>.<patch>`` (columns ``force``, N,
    and ``area``, m^2), by name."""
    return {n: h for n, h in histories_of(hist, "loads", "force").items() if "area" in h}
