"""Pressure–area curves of the contact pressure on a structure's surface, per frame and envelope.

The local-pressure format of ISO 19906:2019 (A.8.2.5.3, local ice pressures) and of the ice
class rules (e.g. IACS UR I2, the design load patch) states the highest mean pressure over a
loaded area of a given size, ``p(A)``, which falls as ``A`` grows (the "spatial" pressure–area
relation; Jordaan, "Mechanics of ice–structure interaction", Eng. Fract. Mech. 68, 2001;
Frederking, "The local pressure–area relation in ship impact with ice", POAC 1999, takes it
from sub-areas of a measuring panel). Here it comes from the per-facet contact pressure of
each frame (``/structure/<name>.contact/contact_pressure``, :mod:`pdfem.coupling.facet_loads`):

1. the facets in contact (``p > 0``) are taken as one connected patch grown from the facet of
   highest pressure: at each step the neighbouring facet (sharing a node with the patch) of
   highest pressure joins it; when no neighbour in contact is left the patch continues from
   the highest facet not yet taken (separate contact zones);
2. after each facet the patch's area ``A_k`` and mean pressure ``p_k = sum p A / sum A`` are
   recorded: a curve from the peak facet (the smallest area the mesh resolves) to the full
   contact area, where ``p`` is the total normal contact force over the contact area;
3. the curves of all frames are sampled at a common set of areas (``AREAS`` log-spaced from
   the smallest facet to the largest contact area; piecewise constant: ``p`` of the largest
   patch not larger than ``A``, and the peak facet's pressure below its area, as a facet's
   pressure is uniform over it) and their envelope over the run is the largest ``p`` at each
   area, with the frame it came from.

Growing the patch greedily gives, at each size, a high-pressure connected area around the
peak, the "design patch" of the rules; it is not guaranteed to be the highest over every
connected set of that size (an NP-hard search), but it equals it at the smallest area (the
peak facet) and at the full contact area. Units: m^2, Pa, s.
"""

from __future__ import annotations

import heapq

import numpy as np

from pdfem.meshing.quality import triangle_areas

AREAS = 40
"""Number of areas at which the curves and their envelope are sampled."""


def facet_neighbours(triangles: np.ndarray) -> list[np.ndarray]:
    """For each triangle, the triangles that share at least one node with it."""
    n_nodes = int(triangles.max()) + 1 if len(triangles) else 0
    tri_of_node: list[list[int]] = [[] for _ in range(n_nodes)]
    for t, nodes in enumerate(triangles):
        for v in nodes:
            tri_of_node[v].append(t)
    return [np.unique(np.concatenate([tri_of_node[v] for v in nodes])) for nodes in triangles]


def pressure_area_curve(pressure: np.ndarray, area: np.ndarray,
                        neighbours: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The pressure–area curve of one frame by patch growth (module docstring).

    Parameters
    ----------
    pressure
        (F,) contact pressure per facet, Pa.
    area
        (F,) facet areas, m^2.
    neighbours
        :func:`facet_neighbours` of the facets.

    Returns
    -------
    area, pressure
        (C,) cumulative patch areas (m^2) and the patch's mean pressure there (Pa), for the C
        facets in contact (empty if none).
    """
    loaded = pressure > 0.0
    order: list[int] = []
    taken = np.zeros(len(pressure), dtype=bool)
    rest = sorted(np.flatnonzero(loaded), key=lambda f: -pressure[f])
    heap: list[tuple[float, int]] = []
    r = 0
    while len(order) < len(rest):
        if not heap:  # start (again) from the highest facet not taken
            while taken[rest[r]]:
                r += 1
            heap.append((-pressure[rest[r]], rest[r]))
        _, f = heapq.heappop(heap)
        if taken[f]:
            continue
        taken[f] = True
        order.append(f)
        for g in neighbours[f]:
            if loaded[g] and not taken[g]:
                heapq.heappush(heap, (-pressure[g], int(g)))
    idx = np.array(order, dtype=np.int64)
    a = np.cumsum(area[idx])
    return a, np.cumsum(pressure[idx] * area[idx]) / a if len(idx) else a


def sample_curve(curve_area: np.ndarray, curve_pressure: np.ndarray,
                 areas: np.ndarray) -> np.ndarray:
    """``p`` of the largest patch not larger than each of ``areas`` (m^2): below the first
    (peak) facet's area its pressure (uniform over the facet, so over any part of it), and NaN
    above the full contact area (no patch that large)."""
    out = np.full(len(areas), np.nan)
    if len(curve_area) == 0:
        return out
    k = np.searchsorted(curve_area, areas * (1 + 1e-12), side="right") - 1
    inside = areas <= curve_area[-1] * (1 + 1e-12)
    out[inside] = curve_pressure[np.maximum(k[inside], 0)]
    return out


def pressure_area(time: np.ndarray, surface: dict, n_areas: int = AREAS) -> dict:
    """The pressure–area curves of every frame and their envelope over the run.

    Parameters
    ----------
    time
        (F,) frame times, s.
    surface
        A contact surface of :func:`pdfem.output.read_results`: ``points`` (m), ``cells``
        (T, 3) and ``contact_pressure`` (F, T) (Pa).
    n_areas
        Number of sample areas.

    Returns
    -------
    dict
        ``area`` (n,) sample areas (m^2); ``curves`` (F, n) each frame's curve (Pa, NaN above
        its contact area); ``envelope`` (n,) the largest over the frames (Pa) and
        ``envelope_frame`` (n,) the frame it came from (-1: no contact that large);
        ``contact_area`` (F,) and ``contact_force`` (F,) each frame's area in contact (m^2)
        and total normal contact force (N).
    """
    tri = np.asarray(surface["cells"], dtype=np.int64)
    area = triangle_areas(np.asarray(surface["points"], dtype=np.float64), tri)
    p = np.asarray(surface["contact_pressure"])
    contact_area = (area * (p > 0)).sum(axis=1)
    hi = max(float(contact_area.max()) if len(p) else 0.0, float(area.min()))
    areas = np.geomspace(float(area.min()), hi, n_areas)
    neighbours = facet_neighbours(tri)
    curves = np.array([sample_curve(*pressure_area_curve(pf, area, neighbours), areas)
                       for pf in p]).reshape(len(p), n_areas)
    filled = np.where(np.isnan(curves), -np.inf, curves)
    frame = np.argmax(filled, axis=0) if len(p) else np.zeros(n_areas, dtype=np.int64)
    envelope = filled[frame, np.arange(n_areas)] if len(p) else np.full(n_areas, -np.inf)
    none = ~np.isfinite(envelope)
    return {"area": areas, "curves": curves, "envelope": np.where(none, np.nan, envelope),
            "envelope_frame": np.where(none, -1, frame), "contact_area": contact_area,
            "contact_force": (p * area).sum(axis=1), "time": np.asarray(time)}
