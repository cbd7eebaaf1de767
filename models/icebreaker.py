"""Parametric icebreaker hull: a closed triangulated surface for a rigid or free-floating hull.

Geometry (SI: m, rad). x points forward, y to port, z up; the design waterline is z = 0, the
keel z = -draught, the deck z = depth - draught. Every horizontal section is symmetric about
y = 0 with the half breadth::

    h(x, z) = max(0, min(b(z), tan(entrance_angle) (x_stem(z) - x), b(z) (x + length/2) / L_run))
    b(z)      = beam/2 + z tan(flare_angle)             (sides lean out by the flare going up)
    x_stem(z) = length/2 + z / tan(stem_angle)           (the stem runs aft going down)
    L_entr    = (beam/2) / tan(entrance_angle),   L_run = length - parallel_middle_body - L_entr

so the waterline (z = 0) is ``length`` long from the stern (x = -length/2, a vertical knuckle)
to the stem (x = length/2); it narrows to the stem at the half angle ``entrance_angle`` over
L_entr (the bow), is parallel over ``parallel_middle_body`` and narrows linearly to the stern
over L_run. The hull is closed by a flat bottom (keel plane) and a flat deck.

Named surface groups (2-D, triangles, outward normals), by the x of each triangle's centroid
with x_F = length/2 - L_entr the fore end and x_A = -length/2 + L_run the aft end of the
parallel middle body at the waterline: ``stern`` (x < x_A), ``midship`` (x_A .. x_F - L_entr/2),
``shoulder`` (x_F - L_entr/2 .. x_F + L_entr/2), ``bow`` (x >= x_F + L_entr/2), ``bow_panel``
(the triangles of the bow's port side within ``bow_panel_length`` x ``bow_panel_height`` centred
at x_F + 0.75 L_entr on the waterline; also in ``bow``) and ``contact`` (all).

The mesh is a structured triangulation built here: nodes on every waterline (z = 0 included) at
the section's break points (stern, x_A, the bow's start x_stem(z) - b(z)/tan(entrance_angle),
stem), so the mesh is exact on the waterplane and differs from the parametric surface only by
the bilinear sides between levels. :func:`hydrostatic_properties` integrates the parametric
surface independently of the mesh (exact in x, fine midpoint rule in z): submerged volume,
centre of buoyancy, waterplane area and its moments (the references of the ship validation).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from pdfem.meshing import (MeshReport, check_parameters, finish_mesh, gmsh_session, require,
                           require_positive, require_range)

#: name -> (default, unit, description)
PARAMETERS: dict[str, tuple] = {
    "length": (3.0, "m", "waterline length, stern to stem"),
    "beam": (0.6, "m", "breadth at the waterline"),
    "draught": (0.2, "m", "keel below the waterline"),
    "depth": (0.35, "m", "keel to deck"),
    "stem_angle": (math.radians(25.0), "rad", "stem inclination from the horizontal, (0, pi/2]"),
    "flare_angle": (math.radians(10.0), "rad", "side flare from the vertical, [0, pi/2)"),
    "entrance_angle": (math.radians(30.0), "rad", "waterline half angle at the stem, (0, pi/2)"),
    "parallel_middle_body": (1.2, "m", "length of the parallel middle body at the waterline"),
    "bow_panel_length": (0.2, "m", "length of the bow panel patch (port side)"),
    "bow_panel_height": (0.12, "m", "height of the bow panel patch, centred on the waterline"),
    "element_size": (0.05, "m", "target triangle edge length"),
}


def _checked(params: dict) -> dict:
    p = check_parameters(PARAMETERS, params)
    require_positive(p, "length", "beam", "draught", "depth", "element_size",
                     "bow_panel_length", "bow_panel_height")
    require_range(p, "parallel_middle_body", 0.0, unit="m")
    require_range(p, "stem_angle", 0.0, math.pi / 2, low_open=True, unit="rad")
    require_range(p, "flare_angle", 0.0, math.pi / 2, high_open=True, unit="rad")
    require_range(p, "entrance_angle", 0.0, math.pi / 2, low_open=True, high_open=True, unit="rad")
    require(p["depth"] > p["draught"], "depth", p["depth"], f"must exceed the draught "
            f"({p['draught']:g} m): the deck is above the waterline")
    T, tf = p["draught"], math.tan(p["flare_angle"])
    require(p["beam"] / 2 - T * tf > 0, "flare_angle", p["flare_angle"], "too large: the sides "
            "meet above the keel (beam/2 - draught tan(flare_angle) <= 0)")
    entr, run = _lengths(p)
    require(run > 0, "parallel_middle_body", p["parallel_middle_body"], f"too long: no run "
            f"left aft (length - parallel_middle_body - entrance length {entr:.4g} m <= 0; the "
            "entrance length is (beam/2) / tan(entrance_angle))")
    for z in (-T, p["depth"] - T):
        require(_x_bow(p, z) - (-p["length"] / 2 + run) > 0, "stem_angle", p["stem_angle"],
                f"the bow reaches the run at z = {z:g} m (a shallower stem or flare, or a longer "
                "parallel_middle_body, is needed)")
    require(p["element_size"] <= min(p["draught"], p["depth"] - p["draught"], p["beam"] / 4),
            "element_size", p["element_size"], "must not exceed the draught, the freeboard or "
            "beam/4")
    return p


def _lengths(p: dict) -> tuple[float, float]:
    """Entrance and run lengths at the waterline (m)."""
    entr = 0.5 * p["beam"] / math.tan(p["entrance_angle"])
    return entr, p["length"] - p["parallel_middle_body"] - entr


def _b(p: dict, z):
    return 0.5 * p["beam"] + z * math.tan(p["flare_angle"])


def _x_stem(p: dict, z):
    return 0.5 * p["length"] + z / math.tan(p["stem_angle"])


def _x_bow(p: dict, z):
    """x where the bow's taper starts at height z (m)."""
    return _x_stem(p, z) - _b(p, z) / math.tan(p["entrance_angle"])


def half_breadth(p: dict, x, z):
    """Half breadth h(x, z) (m) of the parametric hull (checked parameters ``p``)."""
    _, run = _lengths(p)
    b = _b(p, z)
    h = np.minimum(np.minimum(b, math.tan(p["entrance_angle"]) * (_x_stem(p, z) - x)),
                   b * (np.asarray(x) + 0.5 * p["length"]) / run)
    return np.maximum(h, 0.0)


def _stations(p: dict, z) -> np.ndarray:
    """Break points in x of the section at height z (m; or an array of heights): stern, aft
    and fore ends of the parallel body, stem (m), along the last axis ((..., 4))."""
    _, run = _lengths(p)
    z = np.asarray(z, dtype=np.float64)
    return np.stack(np.broadcast_arrays(-0.5 * p["length"], -0.5 * p["length"] + run,
                                        _x_bow(p, z), _x_stem(p, z)), axis=-1)


def _x_integrals(p: dict, zs, f) -> np.ndarray:
    """int f(x, h(x, z)) dx over the section at each height of ``zs`` ((n,) m), exact for f of
    degree <= 3 (Simpson on the linear pieces): (n,), all levels in one array pass."""
    z = np.asarray(zs, dtype=np.float64)[:, None]
    xs = _stations(p, z[:, 0])
    a, b = xs[:, :-1], xs[:, 1:]
    m = 0.5 * (a + b)
    return np.sum((b - a) / 6 * (f(a, half_breadth(p, a, z)) + 4 * f(m, half_breadth(p, m, z))
                                 + f(b, half_breadth(p, b, z))), axis=1)


def _x_integral(p: dict, z: float, f) -> float:
    """:func:`_x_integrals` at one height z (m)."""
    return float(_x_integrals(p, [z], f)[0])


def hydrostatic_properties(n_z: int = 4000, **params) -> dict[str, float]:
    """Hydrostatics of the parametric hull at its design waterline, from the parametric surface
    (exact in x, midpoint rule with ``n_z`` levels in z), independent of any mesh (SI).

    Returns ``volume`` (submerged, m^3), ``x_b``, ``z_b`` (centre of buoyancy, m),
    ``waterplane_area`` (m^2), ``x_f`` (centre of flotation, m), ``i_t`` and ``i_l`` (second
    moments of the waterplane about its centreline and about the transverse axis through x_f,
    m^4) and ``enclosed_volume`` (the whole closed hull, m^3).
    """
    p = _checked(params)
    T, D = p["draught"], p["depth"]

    def levels(lo, hi):
        zz = lo + (np.arange(n_z) + 0.5) * (hi - lo) / n_z
        return zz, (hi - lo) / n_z
    zz, dz = levels(-T, 0.0)
    area = _x_integrals(p, zz, lambda x, h: 2 * h)
    mx = _x_integrals(p, zz, lambda x, h: 2 * h * x)
    volume = float(area.sum() * dz)
    za, dza = levels(0.0, D - T)
    above = float(np.sum(_x_integrals(p, za, lambda x, h: 2 * h)) * dza)
    awp = _x_integral(p, 0.0, lambda x, h: 2 * h)
    x_f = _x_integral(p, 0.0, lambda x, h: 2 * h * x) / awp
    return {"volume": volume, "x_b": float(mx.sum() * dz / volume),
            "z_b": float((area * zz).sum() * dz / volume), "waterplane_area": awp, "x_f": x_f,
            "i_t": _x_integral(p, 0.0, lambda x, h: 2 * h**3 / 3),
            "i_l": _x_integral(p, 0.0, lambda x, h: 2 * h * (x - x_f) ** 2),
            "enclosed_volume": volume + above}


def _counts(p: dict) -> list[int]:
    """Node intervals along each piece (run, parallel body, bow): the longest over z / size."""
    zs = (-p["draught"], p["depth"] - p["draught"])
    longest = np.max([np.diff(_stations(p, z)) for z in zs], axis=0)
    return [max(2, math.ceil(n / p["element_size"])) for n in longest]


def _levels(p: dict) -> np.ndarray:
    T, F, h = p["draught"], p["depth"] - p["draught"], p["element_size"]
    return np.concatenate([np.linspace(-T, 0.0, max(2, math.ceil(T / h)) + 1)[:-1],
                           np.linspace(0.0, F, max(2, math.ceil(F / h)) + 1)])


def _triangulate(p: dict):
    """Nodes (N, 3) and triangles (T, 3) of the closed hull (outward by construction: checked
    again by :func:`finish_mesh`)."""
    zs, counts = _levels(p), _counts(p)
    rows = []                                               # x of the nodes on each level
    for z in zs:
        st = _stations(p, z)
        pieces = [np.linspace(st[k], st[k + 1], counts[k] + 1)[:-1] for k in range(3)]
        rows.append(np.concatenate(pieces + [st[3:]]))
    X = np.array(rows)                                      # (nz, nu + 1)
    Z = np.repeat(zs[:, None], X.shape[1], axis=1)
    H = half_breadth(p, X, Z)
    H[:, 0] = H[:, -1] = 0.0
    nz, nu = X.shape[0], X.shape[1] - 1
    nodes, tris = [], []
    index: dict[tuple, int] = {}

    def node(x, y, z) -> int:
        key = (round(x, 12), round(y, 12), round(z, 12))
        if key not in index:
            index[key] = len(nodes)
            nodes.append((x, y, z))
        return index[key]

    for sign in (-1.0, 1.0):                                # starboard, port sides
        ids = [[node(X[j, i], sign * H[j, i], Z[j, i]) for i in range(nu + 1)] for j in range(nz)]
        for j in range(nz - 1):
            for i in range(nu):
                a, b, c, d = ids[j][i], ids[j][i + 1], ids[j + 1][i + 1], ids[j + 1][i]
                quad = [(a, b, c), (a, c, d)] if sign < 0 else [(a, c, b), (a, d, c)]
                tris += quad
    for j, up in ((0, False), (nz - 1, True)):             # bottom (normal -z) and deck (+z)
        cols = []
        for i in range(nu + 1):                             # node chains across, ~element_size
            n = 0 if H[j, i] == 0.0 else max(1, math.ceil(2 * H[j, i] / p["element_size"]))
            eta = np.linspace(-1.0, 1.0, n + 1) if n else np.zeros(1)
            cols.append((eta, [node(X[j, i], e * H[j, i], zs[j]) for e in eta]))
        for i in range(nu):
            new = _zip(*cols[i], *cols[i + 1])
            tris += [(a, c, b) for a, b, c in new] if up else new
    return np.array(nodes), np.array(tris, dtype=np.int64)


def _zip(eta_l: np.ndarray, left: list, eta_r: np.ndarray, right: list) -> list[tuple]:
    """Triangles between two node chains across the hull (parameters ``eta`` from -1 to 1),
    advancing on the chain whose next node comes first, so that chains of different lengths
    meet without slivers."""
    i = k = 0
    out = []
    while i < len(left) - 1 or k < len(right) - 1:
        if k == len(right) - 1 or (i < len(left) - 1 and eta_l[i + 1] <= eta_r[k + 1]):
            out.append((left[i], left[i + 1], right[k]))
            i += 1
        else:
            out.append((left[i], right[k + 1], right[k]))
            k += 1
    return out


def groups(p: dict, nodes: np.ndarray, tris: np.ndarray) -> dict[str, np.ndarray]:
    """Boolean mask per named group (except ``contact``) of the triangles, by their centroids."""
    entr, run = _lengths(p)
    c = nodes[tris].mean(axis=1)
    x_a, x_f = -0.5 * p["length"] + run, 0.5 * p["length"] - entr
    stern = c[:, 0] < x_a
    bow = c[:, 0] >= x_f + 0.5 * entr
    shoulder = ~bow & (c[:, 0] >= x_f - 0.5 * entr)
    normal = np.cross(nodes[tris[:, 1]] - nodes[tris[:, 0]], nodes[tris[:, 2]] - nodes[tris[:, 0]])
    side = np.abs(normal[:, 2]) < 0.999 * np.linalg.norm(normal, axis=1)
    panel = (bow & side & (c[:, 1] > 0) & (np.abs(c[:, 0] - (x_f + 0.75 * entr))
                                           <= 0.5 * p["bow_panel_length"])
             & (np.abs(c[:, 2]) <= 0.5 * p["bow_panel_height"]))
    return {"stern": stern, "midship": ~stern & ~shoulder & ~bow, "shoulder": shoulder,
            "bow": bow, "bow_panel": panel}


def build(path: str | Path, **params) -> MeshReport:
    """Mesh the closed hull surface and write it as MSH 4.1 (first-order triangles).

    Parameters
    ----------
    path
        Output ``.msh`` file.
    **params
        See :data:`PARAMETERS` (SI: m, rad) and the module docstring.

    Returns
    -------
    MeshReport
        A surface mesh with the groups bow, shoulder, midship, stern, bow_panel and contact.

    Raises
    ------
    ModelParameterError
        A bad parameter (named), or a group that would be empty.
    MeshQualityError
        Zero-area triangles, or a surface that is not closed.
    """
    p = _checked(params)
    nodes, tris = _triangulate(p)
    masks = groups(p, nodes, tris)
    for name, mask in masks.items():
        require(mask.any(), "element_size" if name == "bow_panel" else "parallel_middle_body",
                p["element_size"] if name == "bow_panel" else p["parallel_middle_body"],
                f"the hull's group '{name}' would have no triangles")
    # entities: bow_panel, the rest of the bow, shoulder, midship, stern
    parts = {"bow_panel": masks["bow_panel"], "bow_rest": masks["bow"] & ~masks["bow_panel"],
             "shoulder": masks["shoulder"], "midship": masks["midship"], "stern": masks["stern"]}
    with gmsh_session("icebreaker") as gmsh:
        tags = {}
        for k, (name, mask) in enumerate(parts.items()):
            tag = gmsh.model.addDiscreteEntity(2)
            if k == 0:
                gmsh.model.mesh.addNodes(2, tag, np.arange(1, len(nodes) + 1), nodes.ravel())
            if mask.any():
                gmsh.model.mesh.addElementsByType(tag, 2, [], (tris[mask] + 1).ravel())
            tags[name] = tag
        for name, members in (("bow", ["bow_panel", "bow_rest"]), ("bow_panel", ["bow_panel"]),
                              ("shoulder", ["shoulder"]), ("midship", ["midship"]),
                              ("stern", ["stern"]), ("contact", list(parts))):
            gmsh.model.addPhysicalGroup(2, [tags[m] for m in members if parts[m].any()],
                                        name=name)
        report = finish_mesh(path, "icebreaker", p, dim=2, closed_surface=True)
    props = hydrostatic_properties(**params)
    report.notes.append(f"parametric enclosed volume {props['enclosed_volume']:.6g} m^3, "
                        f"displacement volume at the design draught {props['volume']:.6g} m^3")
    return report
