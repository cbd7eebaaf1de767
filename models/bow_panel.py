"""The elastic bow panel of the icebreaker: the stiffened plate patch of ``hull_panel`` placed and
oriented on the bow of ``icebreaker`` at its ``bow_panel`` location (docs/icebreaking.md).

Geometry (SI: m, rad). The panel is built in the local axes of :mod:`pdfem.models.hull_panel`
(plating 0 <= x_l <= panel_length, 0 <= y_l <= panel_breadth, -t <= z_l <= 0, the ice-facing
face z_l = 0, stiffeners along x_l, frames along y_l) and moved rigidly onto the bow's
entrance plane of the hull (port side), the plane

    y = tan(entrance_angle) (length/2 + z / tan(stem_angle) - x)

of :mod:`pdfem.models.icebreaker`. Its centre on the plating's inner face (local
``(panel_length/2, panel_breadth/2, -t)``) sits on that plane at the waterline ``z = z_center``
and ``x = x_F + 0.75 L_entr`` (the centre of the hull's ``bow_panel`` group; x_F = length/2 -
L_entr, L_entr = (beam/2) / tan(entrance_angle)). Local x_l runs aft along the waterline on the
plane, z_l along the plane's outward normal, y_l = z_l x x_l up the bow. So the plating lies
just outside the rigid hull's surface (its inner face on it), the frames and stiffeners inside
the hull: the ice meets the elastic plating there, before the rigid hull behind it (the honest
simple variant: the rigid hull keeps its closed surface for contact and hydrostatics).

Groups as for ``hull_panel`` hexahedra: ``hull`` (3-D), ``contact`` (the ice-facing plating),
``fixed`` (the edge faces, where the panel joins the hull), ``bay1``, ``bay2``, ... (frame bays).
The hull parameters must be those of the ``icebreaker`` structure the panel belongs to.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from pdfem.meshing import MeshReport, check_parameters, finish_mesh, gmsh_session, require
from pdfem.meshing.structured import FACE_AXIS, add_discrete_mesh, box_union_hexes, boundary_quads
from pdfem.models import hull_panel

_HULL = ("length", "beam", "stem_angle", "entrance_angle")

#: name -> (default, unit, description)
PARAMETERS: dict[str, tuple] = {
    "length": (3.0, "m", "the hull's waterline length (icebreaker model)"),
    "beam": (0.6, "m", "the hull's breadth at the waterline (icebreaker model)"),
    "stem_angle": (math.radians(25.0), "rad", "the hull's stem inclination (icebreaker model)"),
    "entrance_angle": (math.radians(30.0), "rad", "the hull's waterline half angle (icebreaker)"),
    "z_center": (0.0, "m", "height of the panel's centre (0: on the waterline)"),
    "panel_length": (0.08, "m", "panel length along the waterline (x_l, along the stiffeners)"),
    "panel_breadth": (0.04, "m", "panel breadth up the bow (y_l, along the frames)"),
    "plate_thickness": (0.003, "m", "plating thickness"),
    "stiffener_spacing": (0.04, "m", "spacing of the longitudinal stiffeners (y_l)"),
    "stiffener_height": (0.006, "m", "stiffener height inside the plating"),
    "stiffener_thickness": (0.003, "m", "stiffener thickness"),
    "frame_spacing": (0.04, "m", "spacing of the frames (x_l)"),
    "frame_height": (0.01, "m", "frame web height inside the plating"),
    "frame_thickness": (0.003, "m", "frame web thickness"),
    "element_size": (0.01, "m", "largest in-plane hexahedron size"),
}


def placement(p: dict) -> tuple[np.ndarray, np.ndarray]:
    """``(Q, o)``: the rotation (3, 3; columns: the local axes in the world) and the world point
    (m) of the local origin, for the checked parameters ``p``."""
    ta, ts = math.tan(p["entrance_angle"]), math.tan(p["stem_angle"])
    entr = 0.5 * p["beam"] / ta
    z = p["z_center"]
    x = 0.5 * p["length"] - 0.25 * entr
    y = ta * (0.5 * p["length"] + z / ts - x)
    n = np.array([ta, 1.0, -ta / ts])
    n /= np.linalg.norm(n)
    ex = np.array([-1.0, ta, 0.0]) / math.hypot(1.0, ta)
    ey = np.cross(n, ex)
    Q = np.column_stack([ex, ey, n])
    centre = np.array([x, y, z])
    local = np.array([0.5 * p["panel_length"], 0.5 * p["panel_breadth"], -p["plate_thickness"]])
    return Q, centre - Q @ local


def _check(p: dict) -> tuple[list[float], list[float]]:
    """Check the panel's own parameters (through hull_panel) and that it stays on the bow's
    port entrance plane (off the stem)."""
    local = {k: v for k, v in p.items() if k in hull_panel.PARAMETERS or k in
             ("panel_length", "panel_breadth")}
    local["length"], local["breadth"] = local.pop("panel_length"), local.pop("panel_breadth")
    hp = check_parameters(hull_panel.PARAMETERS, local)
    xs, ys = hull_panel._check(hp)
    Q, o = placement(p)
    corners = np.array([[a, b, 0.0] for a in (0, p["panel_length"]) for b in (0, p["panel_breadth"])])
    world = corners @ Q.T + o
    require(world[:, 1].min() > 0.0, "panel_length", p["panel_length"],
            "the panel would reach across the stem (its plating must stay on the port bow: a "
            "smaller panel_length / panel_breadth or a z_center nearer the waterline)")
    return xs, ys, hp


def build(path: str | Path, **params) -> MeshReport:
    """Mesh the bow panel (first-order hexahedra) on the icebreaker's bow; write MSH 4.1.

    Parameters
    ----------
    path
        Output ``.msh`` file.
    **params
        See :data:`PARAMETERS` (SI: m, rad); the hull's ones must match its ``icebreaker``.

    Returns
    -------
    MeshReport
        Groups ``hull``, ``contact``, ``fixed``, ``bay1``, ...

    Raises
    ------
    ModelParameterError
        A bad parameter (named), or a panel that would not fit on the bow.
    """
    p = check_parameters(PARAMETERS, params)
    xs, ys, hp = _check(p)
    L, B = hp["length"], hp["breadth"]
    nodes, hexes, _ = box_union_hexes(hull_panel.panel_grid(hp, xs, ys),
                                      hull_panel._boxes(hp, xs, ys))
    quads, side = boundary_quads(hexes)
    tol = 1e-9 * max(L, B)
    axis = np.array([FACE_AXIS[k][0] for k in side])
    sign = np.array([FACE_AXIS[k][1] for k in side])
    coord = nodes[quads[:, 0], axis]
    contact = quads[(axis == 2) & (sign > 0) & (np.abs(coord) < tol)]
    at_end = np.where(axis == 0, np.where(sign > 0, np.abs(coord - L), np.abs(coord)),
                      np.where(sign > 0, np.abs(coord - B), np.abs(coord)))
    fixed = quads[(axis < 2) & (at_end < tol)]
    bays = hull_panel.frame_bays(nodes[contact].mean(axis=1)[:, 0], xs, contact)
    groups = {"contact": list(bays.values()), "fixed": [fixed]}
    groups.update({name: [q] for name, q in bays.items()})
    Q, o = placement(p)
    with gmsh_session("bow_panel") as gmsh:
        add_discrete_mesh(gmsh, nodes @ Q.T + o, hexes, "hull", groups)
        report = finish_mesh(path, "bow_panel", p, dim=3)
    centre = o + Q @ np.array([0.5 * L, 0.5 * B, 0.0])
    report.notes.append(f"plating centre (ice side) at {np.round(centre, 5).tolist()} m, outward "
                        f"normal {np.round(Q[:, 2], 4).tolist()}")
    return report
