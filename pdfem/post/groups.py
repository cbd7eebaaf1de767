"""The per-step history groups of a results file as post-processing sees them.

Histories are named ``<kind>/<name>``: ``loads/<structure>`` (ice force on a structure),
``contacts/<pair>`` (ice force in a contact pair), ``monitors/<probe>``,
``structures/<name>`` (reactions, energies), and ``energy``. :func:`histories_of` picks one
kind; ``AXES`` names the components of a (K, 3) column.
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
