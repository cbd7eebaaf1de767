"""gmsh meshes of an axis-aligned box with named groups, for the structure tests.

The FE and rigid-body tests all need small box meshes with named groups on chosen faces. The
``gmsh_box`` fixture writes one: tetrahedra of a given size, or first-order hexahedra by
transfinite meshing and recombination with a given number of elements along each axis. Faces
are named by the axis and the end they lie at: ``"x0"`` is the face x = 0, ``"x1"`` the face
x = extent[0], and so on (lengths in m).
"""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np
from pdfem.meshing import gmsh_session

FACES = ("x0", "x1", "y0", "y1", "z0", "z1")


def write_box(path: Path, extent: Sequence[float], *, volume_groups: Sequence[str] = ("solid",),
              face_groups: dict[str, Sequence[str]] | None = None,
              divisions: Sequence[int] | None = None, size: float | None = None,
              msh_version: float = 4.1, order: int = 1) -> Path:
    """Mesh the box [0, extent[0]] x [0, extent[1]] x [0, extent[2]] (m) with gmsh and write it.

    Parameters
    ----------
    path
        Output ``.msh`` file.
    extent
        Box edge lengths along x, y, z (m).
    volume_groups
        Names of 3-D physical groups, each holding the whole box (more than one name puts every
        element in several volume groups).
    face_groups
        Surface group name -> faces (``"x0"``, ``"x1"``, ..., ``"z1"``) it holds.
    divisions
        (nx, ny, nz) elements along each axis: transfinite hexahedra. ``None``: tetrahedra.
    size
        Tetrahedron size (m): gmsh's minimum and maximum mesh size. Ignored for hexahedra.
    msh_version
        MSH file format version (4.1 or 2.2).
    order
        Element order (2 gives second-order elements, to test their refusal).

    Returns
    -------
    Path
        ``path``.
    """
    with gmsh_session("box") as gmsh:
        occ = gmsh.model.occ
        vol = occ.addBox(0, 0, 0, *extent)
        occ.synchronize()
        if divisions is not None:
            for _, c in gmsh.model.getEntities(1):
                a, b = gmsh.model.getBoundary([(1, c)], oriented=False)
                pa, pb = gmsh.model.getValue(0, a[1], []), gmsh.model.getValue(0, b[1], [])
                axis = int(np.argmax(np.abs(np.subtract(pa, pb))))
                gmsh.model.mesh.setTransfiniteCurve(c, divisions[axis] + 1)
            for _, s in gmsh.model.getEntities(2):
                gmsh.model.mesh.setTransfiniteSurface(s)
                gmsh.model.mesh.setRecombine(2, s)
            gmsh.model.mesh.setTransfiniteVolume(vol)
        elif size is not None:
            gmsh.option.setNumber("Mesh.MeshSizeMin", size)
            gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        face_of = {}
        for _, s in gmsh.model.getEntities(2):
            centre = occ.getCenterOfMass(2, s)
            for axis in range(3):
                for end, at in ((0, 0.0), (1, extent[axis])):
                    if abs(centre[axis] - at) < 1e-9 * max(extent):
                        face_of["xyz"[axis] + str(end)] = s
        for name in volume_groups:
            gmsh.model.addPhysicalGroup(3, [vol], name=name)
        for name, faces in (face_groups or {}).items():
            unknown = set(faces) - set(FACES)
            if unknown:
                raise ValueError(f"unknown faces {sorted(unknown)}; faces are {', '.join(FACES)}")
            gmsh.model.addPhysicalGroup(2, [face_of[f] for f in faces], name=name)
        gmsh.model.mesh.generate(3)
        if order > 1:
            gmsh.model.mesh.setOrder(order)
        gmsh.option.setNumber("Mesh.MshFileVersion", msh_version)
        gmsh.write(str(path))
    return Path(path)

