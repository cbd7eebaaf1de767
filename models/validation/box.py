"""Axis-aligned box meshes for the validation cases: beams, blocks and walls.

The box spans ``origin`` to ``origin + (length_x, length_y, length_z)`` (m). Its six faces are
named by axis and end: ``x0`` is the face x = origin_x, ``x1`` the face x = origin_x +
length_x, and so on. Faces are gathered into three surface groups by the parameters
``fixed_faces``, ``loaded_faces`` and ``contact_faces`` (comma-separated face names, ``all`` for
every face, empty for none; a face belongs to at most one group); the volume is the group
``solid``.

Further named groups, for symmetry planes and line supports (e.g. a quarter plate), come from
``groups``: comma-separated ``name:items`` entries, ``items`` joined by ``+``. An item is
either a face name (``x0`` ... ``z1``; the group is then a 2-D group of that face's
quadrilaterals or triangles) or an EDGE LINE, named by the two faces that meet there, e.g.
``x0z0`` is the line x = origin_x, z = origin_z along y (every node with those two
coordinates; a 1-D group of line segments). A group holds faces only or edges only. Example,
a quarter of a simply supported plate (0..a/2)^2 x (0..h) with the plate's edges at x = 0 and
y = 0 and symmetry planes x = a/2, y = a/2, supported on its bottom edge lines::

    groups = "sym_x:x1, sym_y:y1, support:x0z0+y0z0, edge_x:x0, edge_y:y0"

(clamped: fix ``edge_x`` and ``edge_y`` in all components; simply supported: fix ``support``
in z; symmetry: fix ``sym_x`` in x and ``sym_y`` in y). A face or edge may be in several
``groups`` and in one of the three groups above. Groups are not available with
``surface_only``.

Meshes:
Meshes:

* ``divisions_x, _y, _z > 0``: first-order hexahedra, that many along each axis (a structured
  grid, :mod:`pdfem.meshing.structured`); groups are quadrilaterals and line segments. Fully integrated trilinear hexahedra bend much better than
  linear tetrahedra, which is why the cantilever case uses them.
* ``divisions_x = 0``: linear tetrahedra of ``element_size``.
* ``surface_only = true``: a closed triangulated surface of ``element_size`` (all six faces in
  ``contact``), for a rigid body such as a wall.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pdfem.meshing import (MeshReport, check_parameters, finish_mesh, generate_mesh, gmsh_session,
                           require, require_positive, set_mesh_size)
from pdfem.meshing.structured import FACE_AXIS, add_discrete_mesh, box_union_hexes, boundary_quads

FACES = ("x0", "x1", "y0", "y1", "z0", "z1")

#: name -> (default, unit, description)
PARAMETERS: dict[str, tuple] = {
    "length_x": (1.0, "m", "edge length along x"),
    "length_y": (0.1, "m", "edge length along y"),
    "length_z": (0.1, "m", "edge length along z"),
    "origin_x": (0.0, "m", "x of the corner with the smallest coordinates"),
    "origin_y": (0.0, "m", "y of that corner"),
    "origin_z": (0.0, "m", "z of that corner"),
    "divisions_x": (0, "-", "hexahedra along x (0: tetrahedra of element_size)"),
    "divisions_y": (1, "-", "hexahedra along y"),
    "divisions_z": (1, "-", "hexahedra along z"),
    "element_size": (0.05, "m", "tetrahedron / triangle edge length (without divisions)"),
    "surface_only": (False, "-", "write only the closed triangulated surface (a rigid body)"),
    "fixed_faces": ("", "-", "faces of the group 'fixed', e.g. \"x0\""),
    "loaded_faces": ("", "-", "faces of the group 'loaded'"),
    "contact_faces": ("all", "-", "faces of the group 'contact' (all: every face)"),
    "groups": ("", "-", "further groups 'name:item+item, ...'; items: faces (x0) or edge lines (x0z0)"),
}


def _faces(p: dict, key: str) -> list[str]:
    text = p[key].strip()
    if text == "all":
        return list(FACES)
    names = [f.strip() for f in text.split(",") if f.strip()]
    bad = [f for f in names if f not in FACES]
    require(not bad, key, p[key], f"unknown face(s) {bad}; faces are {', '.join(FACES)} or 'all'")
    return names


def _groups(p: dict) -> dict[str, list[str]]:
    groups = {g: _faces(p, f"{g}_faces") for g in ("fixed", "loaded", "contact")}
    if p["surface_only"]:
        groups = {"contact": list(FACES)}
    seen: dict[str, str] = {}
    for g, faces in groups.items():
        for f in faces:
            require(f not in seen, f"{g}_faces", p[f"{g}_faces"],
                    f"face {f} is already in group '{seen.get(f)}'; a face belongs to one group")
            seen[f] = g
    return {g: faces for g, faces in groups.items() if faces}


def _named_groups(p: dict) -> dict[str, list[str]]:
    """``groups`` parsed: name -> faces (``x0``) or edges (``x0z0``, normalised to axis order)."""
    out: dict[str, list[str]] = {}
    for entry in (e.strip() for e in p["groups"].split(",") if e.strip()):
        name, sep, items = entry.partition(":")
        name = name.strip()
        require(bool(sep and name), "groups", p["groups"], f"entry '{entry}' is not 'name:items'")
        require(name not in out and name not in ("solid", "fixed", "loaded", "contact"), "groups", p["groups"],
                f"group name '{name}' is used twice or is one of solid, fixed, loaded, contact")
        parsed = []
        for item in (i.strip() for i in items.split("+")):
            pair = sorted([item[:2], item[2:]]) if len(item) == 4 else [item]
            ok = all(f in FACES for f in pair) and (len(pair) == 1 or pair[0][0] != pair[1][0])
            require(ok, "groups", p["groups"], f"'{item}' in group '{name}' is neither a face ({', '.join(FACES)}) "
                    "nor an edge line named by two faces of different axes (e.g. x0z0)")
            parsed.append("".join(pair))
        require(len({len(i) for i in parsed}) == 1, "groups", p["groups"],
                f"group '{name}' mixes faces and edge lines")
        out[name] = parsed
    require(not (out and p["surface_only"]), "groups", p["groups"], "groups need a volume mesh (surface_only = false)")
    return out


def _edge_axes(edge: str, origin, extent) -> tuple[list[tuple[int, float]], int]:
    """The two (axis, coordinate) of an edge line like ``x0z0`` and the axis it runs along."""
    fixed = [("xyz".index(edge[k]), origin["xyz".index(edge[k])] + int(edge[k + 1]) * extent["xyz".index(edge[k])])
             for k in (0, 2)]
    return fixed, 3 - fixed[0][0] - fixed[1][0]


def build(path: str | Path, **params) -> MeshReport:
    """Mesh the box and write it as MSH 4.1.

    Parameters
    ----------
    path
        Output ``.msh`` file.
    **params
        See ``PARAMETERS`` (lengths in m).

    Returns
    -------
    MeshReport
        With the groups ``solid`` (3-D; not for ``surface_only``), ``fixed``, ``loaded`` and
        ``contact`` (2-D; those given faces).

    Raises
    ------
    ModelParameterError
        A bad parameter (named).
    """
    p = check_parameters(PARAMETERS, params)
    require_positive(p, "length_x", "length_y", "length_z", "element_size")
    divisions = (p["divisions_x"], p["divisions_y"], p["divisions_z"])
    hexa = divisions[0] > 0 and not p["surface_only"]
    if hexa:
        require(min(divisions) > 0, "divisions_y", divisions[1], "hexahedra need divisions >= 1 along every axis")
    groups = _groups(p)
    named = _named_groups(p)
    origin = (p["origin_x"], p["origin_y"], p["origin_z"])
    extent = (p["length_x"], p["length_y"], p["length_z"])
    if hexa:
        return _build_hex(path, p, groups, named, origin, extent, divisions)
    with gmsh_session("box") as gmsh:
        occ = gmsh.model.occ
        vol = occ.addBox(*origin, *extent)
        occ.synchronize()
        face_of = {}
        for _, s in gmsh.model.getEntities(2):
            centre = occ.getCenterOfMass(2, s)
            for axis in range(3):
                for end in (0, 1):
                    if abs(centre[axis] - origin[axis] - end * extent[axis]) < 1e-9 * max(extent):
                        face_of["xyz"[axis] + str(end)] = s
        if not p["surface_only"]:
            gmsh.model.addPhysicalGroup(3, [vol], name="solid")
        for name, faces in groups.items():
            gmsh.model.addPhysicalGroup(2, [face_of[f] for f in faces], name=name)
        for name, items in named.items():
            if len(items[0]) == 2:
                gmsh.model.addPhysicalGroup(2, [face_of[f] for f in items], name=name)
                continue
            curves = []
            for edge in items:
                fixed, _ = _edge_axes(edge, origin, extent)
                for _, c in gmsh.model.getEntities(1):
                    box = gmsh.model.getBoundingBox(1, c)
                    if all(abs(box[a] - v) < 1e-6 * max(extent) and abs(box[a + 3] - v) < 1e-6 * max(extent)
                           for a, v in fixed):
                        curves.append(c)
            gmsh.model.addPhysicalGroup(1, curves, name=name)
        set_mesh_size(p["element_size"])
        dim = 2 if p["surface_only"] else 3
        generate_mesh(dim)
        return finish_mesh(path, "box", p, dim, closed_surface=p["surface_only"])


def _build_hex(path, p, groups, named, origin, extent, divisions) -> MeshReport:
    """The structured hexahedral box with its face and edge-line groups."""
    axes = tuple(np.linspace(o, o + e, n + 1) for o, e, n in zip(origin, extent, divisions))
    nodes, hexes, _ = box_union_hexes(axes, [sum(((o, o + e) for o, e in zip(origin, extent)), ())])
    quads, side = boundary_quads(hexes)
    names = np.array(["xyz"[FACE_AXIS[k][0]] + ("1" if FACE_AXIS[k][1] > 0 else "0") for k in side])
    face = {f: quads[names == f] for f in FACES}
    surfaces = {g: [face[f] for f in faces] for g, faces in groups.items()}
    lines = {}
    tol = 1e-9 * max(extent)
    edge_cache: dict[str, np.ndarray] = {}
    for name, items in named.items():
        if len(items[0]) == 2:
            surfaces[name] = [face[f] for f in items]
            continue
        for edge in items:
            if edge not in edge_cache:
                fixed, along = _edge_axes(edge, origin, extent)
                on = np.flatnonzero(np.all([np.abs(nodes[:, a] - v) < tol for a, v in fixed], axis=0))
                on = on[np.argsort(nodes[on, along])]
                edge_cache[edge] = np.column_stack([on[:-1], on[1:]])
        lines[name] = [edge_cache[e] for e in items]
    with gmsh_session("box") as gmsh:
        add_discrete_mesh(gmsh, nodes, hexes, "solid", surfaces, lines)
        return finish_mesh(path, "box", p, 3)
