"""Axis-aligned box meshes for the validation cases: beams, blocks and walls.

The box spans ``origin`` to ``origin + (length_x, length_y, length_z)`` (m). Its six faces are
named by axis and end: ``x0`` is the face x = origin_x, ``x1`` the face x = origin_x +
length_x, and so on. Faces are gathered into three surface groups by the parameters
``fixed_faces``, ``loaded_faces`` and ``contact_faces`` (comma-separated face names, ``all`` for
every face, empty for none; a face belongs to at most one group); the volume is the group
``solid``.

Meshes:

* ``divisions_x, _y, _z > 0``: first-order hexahedra, that many along each axis (transfinite
  meshing and recombination). Fully integrated trilinear hexahedra bend much better than
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
    origin = (p["origin_x"], p["origin_y"], p["origin_z"])
    extent = (p["length_x"], p["length_y"], p["length_z"])
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
        if not hexa:
            set_mesh_size(p["element_size"])
            dim = 2 if p["surface_only"] else 3
            generate_mesh(dim)
            return finish_mesh(path, "box", p, dim, closed_surface=p["surface_only"])
        for _, c in gmsh.model.getEntities(1):
            a, b = gmsh.model.getBoundary([(1, c)], oriented=False)
            pa, pb = gmsh.model.getValue(0, a[1], []), gmsh.model.getValue(0, b[1], [])
            axis = int(np.argmax(np.abs(np.subtract(pa, pb))))
            gmsh.model.mesh.setTransfiniteCurve(c, divisions[axis] + 1)
        for _, s in gmsh.model.getEntities(2):
            gmsh.model.mesh.setTransfiniteSurface(s)
            gmsh.model.mesh.setRecombine(2, s)
        gmsh.model.mesh.setTransfiniteVolume(vol)
        generate_mesh(3)
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        gmsh.write(str(path))
    n_hex = int(np.prod(divisions))
    volume = float(np.prod(extent))
    h = min(e / d for e, d in zip(extent, divisions))
    return MeshReport(path=path, model="box", parameters=dict(p), dim=3,
                      nodes=int(np.prod(np.add(divisions, 1))), elements={"hexahedron": n_hex},
                      groups={"solid": 3} | {g: 2 for g in groups}, min_volume=volume / n_hex,
                      max_volume=volume / n_hex, total_volume=volume, min_angle=90.0,
                      min_sicn=1.0, min_gamma=1.0, min_inradius=0.5 * h)
