"""Parametric stiffened hull panel: shell plating with longitudinal stiffeners and transverse frames.

Geometry (SI, metres)::

        z
        ^   ice side (outside the hull)
        |
    0  -+=========================================  <- ice-facing shell plating surface: "contact"
   -t  -+-----------------------------------------     plating, thickness t
        |     |stiffener|           |frame web|
        |     |  (along x)          | (along y)
        |                           |_________|     <- optional frame flange (T frame)

* The shell plating occupies 0 <= x <= length, 0 <= y <= breadth, -t <= z <= 0. Its face
  z = 0 is the OUTER shell, the surface the ice touches (physical group ``contact``; its mesh
  normals point to +z, out of the steel). The ice comes from z > 0.
* Longitudinal stiffeners (flat bars) run along x over the whole length, on the inside
  (z < -t), evenly spaced in y and centred on the panel: ``ceil(breadth / spacing) - 1`` of
  them at ``stiffener_spacing`` apart (none if the spacing is >= the breadth).
* Transverse frames run along y over the whole breadth, on the inside, placed the same way in
  x with ``frame_spacing``. A frame is a flat-bar web of ``frame_height`` below the plating,
  plus, if ``frame_flange_width > 0``, a flange of that width and ``frame_flange_thickness``
  under the web (a T frame). Stiffeners are lower than the frame webs and pass through them
  (the solids are united where they cross).
* The panel ends where it joins the surrounding structure: the four edge faces of the
  plating and the end faces of the stiffeners (x = 0, length) and frames (y = 0, breadth)
  form the group ``fixed``.
* With hexahedra the contact surface is also split at the frames (at the frame webs' centre
  planes) into frame bays, groups ``bay1``, ``bay2``, ... from x = 0: each is a load patch
  whose force history the run writes (``loads/<structure>.bay1``), the load per frame
  spacing that ice-class rules size frames for.
* Every part is an axis-aligned box, so by default (``element_type = "hex"``) the whole panel is
  one structured, conforming mesh of first-order hexahedra (gmsh type 5) on the tensor grid of
  all the parts' break points in x, y and z (:mod:`pdfem.meshing.structured`): in-plane cells
  at most ``element_size``, ``layers`` hexahedra through the plating, through each stiffener
  and frame web and through each flange, cells of at most ``element_size`` along a web's
  height. Group ``hull``; ``contact`` and ``fixed`` are quadrilaterals. The structure solver
  raises these hexahedra to 20-node serendipity elements on load (its field
  ``element_order``, default 2): one layer of them at <= 25 mm in-plane is within 0.5 % of
  plate theory on plate frequency and deflection (docs/structures_convergence.md), whereas
  first-order tetrahedra across a 12 mm plate lock (two to three times too stiff).
* ``element_type = "tet"`` gives the former mesh: all parts fused (OCC boolean fragments)
  into one conforming first-order tetrahedral mesh of ``element_size``.

Mesh size and cost (``python benchmarks/hull_panel_modes.py 0.1 0.08 0.05 0.04 0.025``: the
default panel clamped on ``fixed``, 20-node hexahedra, first five frequencies in Hz):

=============  =========================  ===============================================
element_size   gmsh file (nodes / hexes)  frequencies (Hz); quadratic DOFs
=============  =========================  ===============================================
0.10 m         940 / 430                  242.9 245.7 300.0 318.7 323.5;   9 624
0.08 m         1 360 / 631                239.9 242.6 293.0 313.3 318.2;  13 980
0.05 m         3 072 / 1 462              236.4 239.3 278.4 306.5 311.4;  31 806
0.04 m         4 760 / 2 288              235.6 238.4 273.8 304.7 309.7;  49 422
0.025 m        11 508 / 5 610             234.6 237.5 269.4 302.8 307.8; 119 964
=============  =========================  ===============================================

The third mode (the frame web and stiffeners bending with the plating) converges slowest, about
as h^1.3 (the re-entrant web-to-plate corners): at 0.05 m it is 3.3 % above the mesh refined
once (0.025 m) and, extrapolated, about 5 % above the mesh refined twice (0.0125 m); the other
four are within 1.2 %. At 0.08 m the third mode is 7 % above the 0.04 m mesh. So the default
``element_size`` is 0.05 m; refine it for stresses at the stiffener and frame roots.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from pdfem.meshing import (MeshReport, check_parameters, finish_mesh, generate_mesh, gmsh_session, require,
                           require_choice, require_element_budget, require_positive, require_range,
                           set_mesh_size)
from pdfem.meshing.structured import (FACE_AXIS, add_discrete_mesh, box_union_hexes, boundary_quads, grid_axis,
                                      merge_breaks)

#: name -> (default, unit, description)
PARAMETERS: dict[str, tuple] = {
    "length": (2.0, "m", "panel length along x (along the stiffeners)"),
    "breadth": (1.2, "m", "panel breadth along y (along the frames)"),
    "plate_thickness": (0.012, "m", "shell plating thickness t (plating from z = -t to the ice side z = 0)"),
    "stiffener_spacing": (0.4, "m", "spacing of the longitudinal stiffeners in y"),
    "stiffener_height": (0.15, "m", "height of the longitudinal flat-bar stiffeners below the plating"),
    "stiffener_thickness": (0.012, "m", "thickness of the stiffeners"),
    "frame_spacing": (1.0, "m", "spacing of the transverse frames in x"),
    "frame_height": (0.30, "m", "height of the frame webs below the plating"),
    "frame_thickness": (0.012, "m", "thickness of the frame webs"),
    "frame_flange_width": (0.0, "m", "width of the frame flanges (0: flat-bar frames, > 0: T frames)"),
    "frame_flange_thickness": (0.015, "m", "thickness of the frame flanges (used for T frames)"),
    "element_size": (0.05, "m", "largest in-plane cell size (hexahedra) or target edge length (tetrahedra)"),
    "element_type": ("hex", "-", "hex: structured first-order hexahedra; tet: first-order tetrahedra"),
    "layers": (1, "-", "hexahedra through the plating, stiffener, web and flange thicknesses (hex only)"),
}

def _positions(extent: float, spacing: float) -> list[float]:
    """Evenly spaced positions strictly inside (0, extent), centred, ``spacing`` apart."""
    n = max(math.ceil(extent / spacing - 1e-9) - 1, 0)
    return [0.5 * extent + (k - 0.5 * (n - 1)) * spacing for k in range(n)]


def _check(p: dict) -> tuple[list[float], list[float]]:
    require_positive(p, *(k for k in PARAMETERS if k not in ("frame_flange_width", "element_type", "layers")))
    require_choice(p, "element_type", ("hex", "tet"))
    require_range(p, "layers", 1, 8)
    require(p["frame_flange_width"] >= 0, "frame_flange_width", p["frame_flange_width"],
            "must be >= 0 (0 for flat-bar frames)")
    ys = _positions(p["breadth"], p["stiffener_spacing"])
    xs = _positions(p["length"], p["frame_spacing"])
    if ys:
        require(p["stiffener_thickness"] < p["stiffener_spacing"], "stiffener_thickness", p["stiffener_thickness"],
                f"must be less than stiffener_spacing ({p['stiffener_spacing']:g} m)")
        edge = min(ys[0], p["breadth"] - ys[-1])
        require(p["stiffener_thickness"] < 2 * edge, "stiffener_thickness", p["stiffener_thickness"],
                f"the outer stiffeners (at {edge:g} m from the panel edge) would stick out of the panel")
    if xs:
        flange = p["frame_flange_width"]
        width = max(p["frame_thickness"], flange)
        require(width < p["frame_spacing"], "frame_thickness" if flange == 0 else "frame_flange_width",
                width, f"frames must be narrower than frame_spacing ({p['frame_spacing']:g} m)")
        edge = min(xs[0], p["length"] - xs[-1])
        require(width < 2 * edge, "frame_thickness" if flange == 0 else "frame_flange_width", width,
                f"the outer frames (at {edge:g} m from the panel end) would stick out of the panel")
        require(flange == 0 or flange >= p["frame_thickness"], "frame_flange_width", flange,
                f"must be 0 or at least the web thickness ({p['frame_thickness']:g} m)")
        if ys:
            require(p["stiffener_height"] < p["frame_height"], "stiffener_height", p["stiffener_height"],
                    f"must be less than frame_height ({p['frame_height']:g} m): stiffeners pass through the frame webs")
    h = p["element_size"]
    require(h <= 0.5 * min(p["length"], p["breadth"]), "element_size", h,
            "must be at most half the smaller of length and breadth")
    area = 2 * p["length"] * p["breadth"] + 2 * len(ys) * p["length"] * p["stiffener_height"] \
        + 2 * len(xs) * p["breadth"] * (p["frame_height"] + p["frame_flange_width"])
    require_element_budget(area, h, "this panel")
    return xs, ys


def hull_volume(**params) -> float:
    """Analytic steel volume (m^3) of the panel: plating + stiffeners + frames - their overlaps.

    Parameters
    ----------
    **params
        Any of :data:`PARAMETERS` (SI); the others take their defaults.
    """
    p = check_parameters(PARAMETERS, params)
    xs, ys = _check(p)
    L, B = p["length"], p["breadth"]
    frame = B * (p["frame_thickness"] * p["frame_height"] + p["frame_flange_width"] * p["frame_flange_thickness"])
    overlap = p["stiffener_thickness"] * p["frame_thickness"] * p["stiffener_height"]
    return (L * B * p["plate_thickness"] + len(ys) * L * p["stiffener_thickness"] * p["stiffener_height"]
            + len(xs) * frame - len(xs) * len(ys) * overlap)


def build(path: str | Path, **params) -> MeshReport:
    """Mesh the stiffened panel and write it as MSH 4.1.

    Parameters
    ----------
    path
        Output ``.msh`` file.
    length : float, default 2.0
        Panel length along x, m.
    breadth : float, default 1.2
        Panel breadth along y, m.
    plate_thickness : float, default 0.012
        Shell plating thickness, m; the plating spans -t <= z <= 0 and z = 0 faces the ice.
    stiffener_spacing : float, default 0.4
        Spacing of the longitudinal stiffeners (y), m.
    stiffener_height : float, default 0.15
        Stiffener height below the plating, m; less than ``frame_height``.
    stiffener_thickness : float, default 0.012
        Stiffener thickness, m.
    frame_spacing : float, default 1.0
        Spacing of the transverse frames (x), m.
    frame_height : float, default 0.30
        Frame web height below the plating, m.
    frame_thickness : float, default 0.012
        Frame web thickness, m.
    frame_flange_width : float, default 0.0
        Frame flange width, m (0: flat-bar frames).
    frame_flange_thickness : float, default 0.015
        Frame flange thickness, m (T frames only).
    element_size : float, default 0.05
        Largest in-plane hexahedron size (hex), or target tetrahedron edge length (tet), m.
    element_type : str, default "hex"
        ``"hex"``: structured conforming first-order hexahedra (raised to 20-node elements by
        the structure on load); ``"tet"``: first-order tetrahedra.
    layers : int, default 1
        Hexahedra through each plate, stiffener, web and flange thickness (hex only), 1..8.

    Returns
    -------
    MeshReport
        With physical groups ``hull`` (3-D), ``contact`` (2-D, the ice-facing plating surface
        z = 0, normals +z), ``fixed`` (2-D, the panel's edge faces) and, for hexahedra, the
        contact surface split at the frames into frame bays ``bay1``, ``bay2``, ... (x
        upwards): the panel's load patches.

    Raises
    ------
    ModelParameterError
        A bad parameter (named).
    MeshQualityError
        Inverted or zero-volume elements.
    """
    p = check_parameters(PARAMETERS, params)
    xs, ys = _check(p)
    report = (_build_hex if p["element_type"] == "hex" else _build_tet)(path, p, xs, ys)
    stiffeners = f"stiffeners at y = {', '.join(f'{y:g}' for y in ys)} m" if ys else "no stiffeners"
    frames = f"frames at x = {', '.join(f'{x:g}' for x in xs)} m" if xs else "no frames"
    report.notes.append(f"{stiffeners}; {frames}; the ice-facing plating surface is z = 0")
    return report


def _boxes(p: dict, xs: list[float], ys: list[float]) -> list[tuple[float, ...]]:
    """(xmin, xmax, ymin, ymax, zmin, zmax) of the plating, stiffeners, frame webs and flanges."""
    L, B, t = p["length"], p["breadth"], p["plate_thickness"]
    hs, ts, hf, tf = p["stiffener_height"], p["stiffener_thickness"], p["frame_height"], p["frame_thickness"]
    bf, tfl = p["frame_flange_width"], p["frame_flange_thickness"]
    boxes = [(0.0, L, 0.0, B, -t, 0.0)]
    boxes += [(0.0, L, y - ts / 2, y + ts / 2, -t - hs, -t) for y in ys]
    boxes += [(x - tf / 2, x + tf / 2, 0.0, B, -t - hf, -t) for x in xs]
    if bf > 0:
        boxes += [(x - bf / 2, x + bf / 2, 0.0, B, -t - hf - tfl, -t - hf) for x in xs]
    return boxes


def panel_grid(p: dict, xs: list[float], ys: list[float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Grid coordinates (m) along x, y, z of the hexahedral panel mesh.

    Break points are the faces of all parts; an interval inside a web, stiffener, plate or
    flange thickness gets ``layers`` cells, every other one ceil(length / element_size).
    """
    boxes = _boxes(p, xs, ys)
    h, n, tol = p["element_size"], p["layers"], 1e-9 * max(p["length"], p["breadth"])
    t, hf = p["plate_thickness"], p["frame_height"]
    thin = ([[(x - p["frame_thickness"] / 2, x + p["frame_thickness"] / 2) for x in xs],
             [(y - p["stiffener_thickness"] / 2, y + p["stiffener_thickness"] / 2) for y in ys],
             [(-t, 0.0), (-t - hf - p["frame_flange_thickness"], -t - hf)]])
    axes = []
    for d in range(3):
        br = merge_breaks([v for b in boxes for v in b[2 * d:2 * d + 2]], tol)
        div = []
        for a, b in zip(br[:-1], br[1:]):
            inside = any(lo - tol <= a and b <= hi + tol for lo, hi in thin[d])
            div.append(n if inside else max(1, int(np.ceil((b - a) / h - 1e-9))))
        axes.append(grid_axis(br, div))
    return axes[0], axes[1], axes[2]


def _build_hex(path: str | Path, p: dict, xs: list[float], ys: list[float]) -> MeshReport:
    """The structured conforming hexahedral mesh (see the module docstring)."""
    L, B = p["length"], p["breadth"]
    nodes, hexes, _ = box_union_hexes(panel_grid(p, xs, ys), _boxes(p, xs, ys))
    quads, side = boundary_quads(hexes)
    tol = 1e-9 * max(L, B)
    axis = np.array([FACE_AXIS[k][0] for k in side])
    sign = np.array([FACE_AXIS[k][1] for k in side])
    coord = nodes[quads[:, 0], axis]
    contact = quads[(axis == 2) & (sign > 0) & (np.abs(coord) < tol)]
    at_end = np.where(axis == 0, np.where(sign > 0, np.abs(coord - L), np.abs(coord)),
                      np.where(sign > 0, np.abs(coord - B), np.abs(coord)))
    fixed = quads[(axis < 2) & (at_end < tol)]
    bays = frame_bays(nodes[contact].mean(axis=1)[:, 0], xs, contact)
    groups = {"contact": list(bays.values()), "fixed": [fixed]}
    groups.update({name: [quads_] for name, quads_ in bays.items()})
    with gmsh_session("hull_panel") as gmsh:
        add_discrete_mesh(gmsh, nodes, hexes, "hull", groups)
        return finish_mesh(path, "hull_panel", p, dim=3)


def frame_bays(x: np.ndarray, xs: list[float], quads: np.ndarray) -> dict[str, np.ndarray]:
    """The contact quadrilaterals split at the frames: ``{"bay1": ..., "bay2": ...}`` from
    x = 0 upwards, by each quadrilateral's centre ``x`` (m); one bay ``bay1`` without frames."""
    bay = np.searchsorted(np.asarray(xs, dtype=np.float64), x)
    return {f"bay{k + 1}": quads[bay == k] for k in range(len(xs) + 1) if np.any(bay == k)}


def _build_tet(path: str | Path, p: dict, xs: list[float], ys: list[float]) -> MeshReport:
    """The fused OCC parts meshed with first-order tetrahedra."""
    L, B, t = p["length"], p["breadth"], p["plate_thickness"]
    with gmsh_session("hull_panel") as gmsh:
        occ = gmsh.model.occ
        parts = [(3, occ.addBox(0, 0, -t, L, B, t))]
        hs, ts = p["stiffener_height"], p["stiffener_thickness"]
        for y in ys:
            parts.append((3, occ.addBox(0, y - ts / 2, -t - hs, L, ts, hs)))
        hf, tf = p["frame_height"], p["frame_thickness"]
        bf, tfl = p["frame_flange_width"], p["frame_flange_thickness"]
        for x in xs:
            parts.append((3, occ.addBox(x - tf / 2, 0, -t - hf, tf, B, hf)))
            if bf > 0:
                parts.append((3, occ.addBox(x - bf / 2, 0, -t - hf - tfl, bf, B, tfl)))
        if len(parts) > 1:
            occ.fragment(parts[:1], parts[1:])
        occ.synchronize()

        tol = 1e-6 * max(L, B)
        contact, fixed = [], []
        for _, s in gmsh.model.getEntities(2):
            x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(2, s)
            if abs(z0) < tol and abs(z1) < tol:
                contact.append(s)
            elif any(abs(a) < tol and abs(b) < tol for a, b in ((x0, x1), (y0, y1))) or \
                    abs(x0 - L) < tol and abs(x1 - L) < tol or abs(y0 - B) < tol and abs(y1 - B) < tol:
                fixed.append(s)
        volumes = [v for _, v in gmsh.model.getEntities(3)]
        gmsh.model.addPhysicalGroup(3, volumes, name="hull")
        gmsh.model.addPhysicalGroup(2, contact, name="contact")
        gmsh.model.addPhysicalGroup(2, fixed, name="fixed")

        set_mesh_size(p["element_size"])
        # Delaunay, then gmsh's and Netgen's optimisers: the thin plating gives slivers otherwise.
        # (HXT is faster at fine sizes but its optimiser can take minutes on coarse meshes of
        # thin plates.)
        gmsh.option.setNumber("Mesh.Algorithm3D", 1)
        gmsh.option.setNumber("Mesh.Optimize", 1)
        gmsh.option.setNumber("Mesh.OptimizeNetgen", 1)
        generate_mesh(3)
        return finish_mesh(path, "hull_panel", p, dim=3)
