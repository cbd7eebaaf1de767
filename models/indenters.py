"""Rigid indenters as closed triangulated surfaces: cylinder, sphere and a ship-bow wedge.

A rigid body in pdfem needs only its surface, so these models write SURFACE meshes (first-order
triangles, no volume) with one physical group ``contact`` (2-D) covering the whole closed
surface. The triangles are oriented consistently with their normals pointing out of the body
(checked: every edge is shared by exactly two triangles that traverse it in opposite
directions, and the enclosed volume is positive).

Shapes (``shape`` parameter; SI: m, rad):

* ``cylinder`` -- radius ``radius``, length ``length``, axis ``axis`` (x, y or z), centred at
  (center_x, center_y, center_z); closed by flat end caps.
* ``sphere`` -- radius ``radius``, centred at (center_x, center_y, center_z).
* ``wedge`` -- the fore body of an icebreaking bow, moving toward +x. The waterline is the
  plane z = center_z, the stem meets it at (center_x, center_y, center_z). The stem is a
  straight line inclined at ``stem_angle`` from the horizontal, running aft as it goes down;
  the waterline widens linearly from the stem to ``waterline_half_breadth`` at the aft end
  x = center_x - ``bow_length``, where the section's sides lean out by ``flare_angle`` from the
  vertical. The body reaches from ``depth`` below to ``freeboard`` above the waterline and is
  closed by flat top, bottom and aft faces. Each side is a ruled surface between the stem line
  and the aft section, so every horizontal section is a triangle with vertices
  (z / tan(stem_angle), 0) and (-bow_length, +-(waterline_half_breadth + z tan(flare_angle)))
  (relative to the stem point, z up).
"""

from __future__ import annotations

import math
from pathlib import Path

from pdfem.meshing import (MeshReport, ModelParameterError, check_parameters, finish_mesh, generate_mesh,
                           gmsh_session, require, require_choice, require_element_budget, require_positive,
                           require_range, set_mesh_size)

SHAPES = ("cylinder", "sphere", "wedge")

#: name -> (default, unit, description)
PARAMETERS: dict[str, tuple] = {
    "shape": ("sphere", "-", "indenter shape: cylinder, sphere or wedge"),
    "center_x": (0.0, "m", "x of the centre (cylinder, sphere) or of the stem at the waterline (wedge)"),
    "center_y": (0.0, "m", "y of the centre or stem point"),
    "center_z": (0.0, "m", "z of the centre or of the waterline (wedge)"),
    "radius": (0.5, "m", "radius (cylinder, sphere)"),
    "length": (1.0, "m", "length along the axis (cylinder)"),
    "axis": ("z", "-", "axis direction: x, y or z (cylinder)"),
    "stem_angle": (math.radians(25.0), "rad", "stem inclination from the horizontal (wedge), (0, pi/2]"),
    "flare_angle": (math.radians(30.0), "rad", "side flare from the vertical at the aft end (wedge), [0, pi/2)"),
    "waterline_half_breadth": (1.0, "m", "half breadth of the waterline at the aft end (wedge)"),
    "depth": (1.0, "m", "extent below the waterline (wedge)"),
    "freeboard": (0.5, "m", "extent above the waterline (wedge)"),
    "bow_length": (3.0, "m", "length from the stem at the waterline to the aft end (wedge)"),
    "element_size": (0.05, "m", "target triangle edge length"),
}

_COMMON = ("shape", "center_x", "center_y", "center_z", "element_size")
_SHAPE_PARAMETERS = {
    "cylinder": ("radius", "length", "axis"),
    "sphere": ("radius",),
    "wedge": ("stem_angle", "flare_angle", "waterline_half_breadth", "depth", "freeboard", "bow_length"),
}


def surface_area(**params) -> float:
    """Analytic area (m^2) of the indenter's surface (cylinder and sphere only; wedge: NaN)."""
    return _area(_checked(params))


def _area(p: dict) -> float:
    r = p["radius"]
    if p["shape"] == "sphere":
        return 4.0 * math.pi * r * r
    if p["shape"] == "cylinder":
        return 2.0 * math.pi * r * (r + p["length"])
    return float("nan")


def enclosed_volume(**params) -> float:
    """Analytic volume (m^3) enclosed by the indenter's surface.

    sphere 4/3 pi r^3; cylinder pi r^2 L; wedge the integral over the height of the triangular
    horizontal sections, int_{-depth}^{freeboard} (b + z tan(flare)) (bow_length + z / tan(stem)) dz.
    """
    p = _checked(params)
    r = p["radius"]
    if p["shape"] == "sphere":
        return 4.0 / 3.0 * math.pi * r**3
    if p["shape"] == "cylinder":
        return math.pi * r * r * p["length"]
    b, L = p["waterline_half_breadth"], p["bow_length"]
    tf, cs = math.tan(p["flare_angle"]), 1.0 / math.tan(p["stem_angle"])

    def primitive(z: float) -> float:                  # int (b + z tf)(L + z cs) dz
        return b * L * z + (b * cs + L * tf) * z * z / 2 + tf * cs * z**3 / 3

    return primitive(p["freeboard"]) - primitive(-p["depth"])


def _checked(params: dict) -> dict:
    p = check_parameters(PARAMETERS, params)
    require_choice(p, "shape", SHAPES)
    shape = p["shape"]
    for key in params:
        if key not in _COMMON and key not in _SHAPE_PARAMETERS[shape]:
            raise ModelParameterError(key, params[key], f"does not apply to shape '{shape}' (its parameters are: "
                                      + ", ".join(_COMMON + _SHAPE_PARAMETERS[shape]) + ")")
    require_positive(p, "element_size")
    h = p["element_size"]
    if shape in ("cylinder", "sphere"):
        require_positive(p, "radius")
        require(h <= p["radius"], "element_size", h, f"must not exceed the radius ({p['radius']:g} m)")
    if shape == "cylinder":
        require_positive(p, "length")
        require_choice(p, "axis", ("x", "y", "z"))
    if shape == "wedge":
        require_positive(p, "waterline_half_breadth", "depth", "bow_length")
        require_range(p, "freeboard", 0.0, unit="m")
        require_range(p, "stem_angle", 0.0, math.pi / 2, low_open=True, unit="rad")
        require_range(p, "flare_angle", 0.0, math.pi / 2, high_open=True, unit="rad")
        require(p["depth"] / math.tan(p["stem_angle"]) < p["bow_length"], "stem_angle", p["stem_angle"],
                f"too shallow: the stem reaches the aft end above the bottom (depth / tan(stem_angle) = "
                f"{p['depth'] / math.tan(p['stem_angle']):.3g} m >= bow_length {p['bow_length']:g} m)")
        require(p["depth"] * math.tan(p["flare_angle"]) < p["waterline_half_breadth"], "flare_angle",
                p["flare_angle"], "too large: the sides meet above the bottom (depth * tan(flare_angle) >= "
                "waterline_half_breadth)")
        require(h <= min(p["depth"] + p["freeboard"], p["waterline_half_breadth"]), "element_size", h,
                "must not exceed the wedge's height or half breadth")
    if shape != "wedge":
        area = _area(p)
    else:
        b = p["waterline_half_breadth"] + p["freeboard"] * math.tan(p["flare_angle"])
        height = p["depth"] + p["freeboard"]
        area = 2 * b * p["bow_length"] + 2 * height * (b + p["bow_length"] + height / math.tan(p["stem_angle"]))
    require_element_budget(area, h, "this indenter")
    return p


def _wedge(occ, p: dict) -> int:
    cx, cy, cz = p["center_x"], p["center_y"], p["center_z"]
    cs, tf = 1.0 / math.tan(p["stem_angle"]), math.tan(p["flare_angle"])
    L, b = p["bow_length"], p["waterline_half_breadth"]
    wires = []
    for z in (-p["depth"], p["freeboard"]):
        stem = occ.addPoint(cx + z * cs, cy, cz + z)
        port = occ.addPoint(cx - L, cy + b + z * tf, cz + z)
        starboard = occ.addPoint(cx - L, cy - b - z * tf, cz + z)
        lines = [occ.addLine(stem, port), occ.addLine(port, starboard), occ.addLine(starboard, stem)]
        wires.append(occ.addCurveLoop(lines))
    out = occ.addThruSections(wires, makeSolid=True, makeRuled=True)
    return [t for d, t in out if d == 3][0]


def build(path: str | Path, **params) -> MeshReport:
    """Mesh a rigid indenter's closed surface and write it as MSH 4.1.

    Parameters
    ----------
    path
        Output ``.msh`` file.
    shape : str, default "sphere"
        ``cylinder``, ``sphere`` or ``wedge``. Only the parameters of the chosen shape (and the
        centre and element size) may be given.
    center_x, center_y, center_z : float, default 0.0
        Centre of the cylinder or sphere, or the stem point at the waterline of the wedge, m.
    radius : float, default 0.5
        Radius of the cylinder or sphere, m.
    length : float, default 1.0
        Cylinder length, m.
    axis : str, default "z"
        Cylinder axis: ``x``, ``y`` or ``z``.
    stem_angle : float, default 0.436 (25 deg)
        Wedge stem inclination from the horizontal, rad, in (0, pi/2].
    flare_angle : float, default 0.524 (30 deg)
        Wedge side flare from the vertical at the aft end, rad, in [0, pi/2).
    waterline_half_breadth : float, default 1.0
        Wedge waterline half breadth at the aft end, m.
    depth : float, default 1.0
        Wedge extent below the waterline, m.
    freeboard : float, default 0.5
        Wedge extent above the waterline, m (>= 0).
    bow_length : float, default 3.0
        Wedge length from the stem at the waterline to the aft end, m.
    element_size : float, default 0.05
        Target triangle edge length, m.

    Returns
    -------
    MeshReport
        A surface mesh (``dim == 2``) with the group ``contact`` (2-D), outward normals.

    Raises
    ------
    ModelParameterError
        A bad parameter, or one that does not apply to the shape (named).
    MeshQualityError
        Zero-area triangles, or a surface that is not closed and consistently orientable.
    """
    p = _checked(params)
    shape = p["shape"]
    with gmsh_session(f"indenter_{shape}") as gmsh:
        occ = gmsh.model.occ
        c = (p["center_x"], p["center_y"], p["center_z"])
        if shape == "sphere":
            vol = occ.addSphere(*c, p["radius"])
        elif shape == "cylinder":
            axis = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}[p["axis"]]
            half = [0.5 * p["length"] * a for a in axis]
            vol = occ.addCylinder(*(ci - hi for ci, hi in zip(c, half)), *(2 * hi for hi in half), p["radius"])
        else:
            vol = _wedge(occ, p)
        occ.synchronize()
        surfaces = [t for _, t in gmsh.model.getBoundary([(3, vol)], oriented=False)]
        gmsh.model.addPhysicalGroup(2, surfaces, name="contact")
        set_mesh_size(p["element_size"])
        generate_mesh(2)
        report = finish_mesh(path, f"indenters ({shape})", p, dim=2, closed_surface=True)
    if shape in ("cylinder", "sphere"):
        report.notes.append(f"analytic area {surface_area(**params):.6g} m^2, volume {enclosed_volume(**params):.6g} m^3")
    else:
        report.notes.append(f"analytic enclosed volume {enclosed_volume(**params):.6g} m^3")
    return report


def cylinder(path: str | Path, **params) -> MeshReport:
    """``build(path, shape="cylinder", **params)``; see :func:`build`."""
    return build(path, shape="cylinder", **params)


def sphere(path: str | Path, **params) -> MeshReport:
    """``build(path, shape="sphere", **params)``; see :func:`build`."""
    return build(path, shape="sphere", **params)


def wedge(path: str | Path, **params) -> MeshReport:
    """``build(path, shape="wedge", **params)``; see :func:`build`."""
    return build(path, shape="wedge", **params)
