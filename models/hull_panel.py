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
* All parts are fused into one conforming first-order tetrahedral mesh (OCC boolean
  fragments), group ``hull``.

Mesh size: one ``element_size`` everywhere. First-order tetrahedra across a plate only one
element thick are too stiff in bending (they lock), so displacements and stresses of the
plating are underestimated unless ``element_size`` approaches the plate thickness; the defaults
are a modest mesh (a few thousand nodes) for coupled ice runs and demonstrations, not a
converged stress analysis. Refine ``element_size`` for that.
"""

from __future__ import annotations

import math
from pathlib import Path

from pdfem.meshing import (MeshReport, check_parameters, finish_mesh, generate_mesh, gmsh_session, require,
                           require_element_budget, require_positive, set_mesh_size)

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
    "element_size": (0.05, "m", "target edge length of the tetrahedra"),
}

def _positions(extent: float, spacing: float) -> list[float]:
    """Evenly spaced positions strictly inside (0, extent), centred, ``spacing`` apart."""
    n = max(math.ceil(extent / spacing - 1e-9) - 1, 0)
    return [0.5 * extent + (k - 0.5 * (n - 1)) * spacing for k in range(n)]


def _check(p: dict) -> tuple[list[float], list[float]]:
    require_positive(p, *(k for k in PARAMETERS if k != "frame_flange_width"))
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
        Target tetrahedron edge length, m.

    Returns
    -------
    MeshReport
        With physical groups ``hull`` (3-D), ``contact`` (2-D, the ice-facing plating surface
        z = 0) and ``fixed`` (2-D, the panel's edge faces).

    Raises
    ------
    ModelParameterError
        A bad parameter (named).
    MeshQualityError
        Inverted or zero-volume tetrahedra.
    """
    p = check_parameters(PARAMETERS, params)
    xs, ys = _check(p)
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
        report = finish_mesh(path, "hull_panel", p, dim=3)
    stiffeners = f"stiffeners at y = {', '.join(f'{y:g}' for y in ys)} m" if ys else "no stiffeners"
    frames = f"frames at x = {', '.join(f'{x:g}' for x in xs)} m" if xs else "no frames"
    report.notes.append(f"{stiffeners}; {frames}; the ice-facing plating surface is z = 0")
    return report
