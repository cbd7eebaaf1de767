"""Finishing a model's mesh in the open gmsh session: refuse inverted or zero-volume elements,
orient the named surfaces outward (or a closed surface consistently outward), write MSH 4.1 and
report on it (:func:`finish_mesh`).

Volume meshes are of one element type: first- or second-order tetrahedra or hexahedra (gmsh
types 4, 11, 5, 17, 12; :mod:`pdfem.meshing.elements`), their surface groups of the matching
faces (triangles 2, triangle6 9, quads 3, quad8 16, quad9 10). Surface meshes (closed rigid
surfaces) are of triangles or quadrilaterals of either order. Checks and orientation use the
corner nodes.

Lengths are in m, areas in m^2, volumes in m^3, angles in the report in degrees.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from pdfem.meshing.elements import (FACE_TYPES, HEX_FACES, SURFACE_TYPES, TET_FACES, VOLUME_TYPES,
                                    element_type, meshio_name)
from pdfem.meshing.quality import MeshQualityError, check_cells
from pdfem.meshing.report import MeshReport

def _node_coordinates(gmsh) -> tuple[np.ndarray, np.ndarray]:
    """All nodes: (index of each node tag, coordinates (N,3)); index[tag] -> row."""
    tags, coords, _ = gmsh.model.mesh.getNodes(returnParametricCoord=False)
    tags = np.asarray(tags, dtype=np.int64)
    xyz = np.asarray(coords, dtype=np.float64).reshape(-1, 3)
    index = np.full(int(tags.max()) + 1 if tags.size else 1, -1, dtype=np.int64)
    index[tags] = np.arange(tags.size)
    return index, xyz


def _entity_elements(gmsh, dim: int, tag: int, etype: int, nper: int, index: np.ndarray):
    etags, enodes = gmsh.model.mesh.getElementsByType(etype, tag)
    conn = index[np.asarray(enodes, dtype=np.int64)].reshape(-1, nper)
    return np.asarray(etags, dtype=np.int64), conn


def _groups(gmsh) -> dict[tuple[int, int], tuple[str, list[int]]]:
    out = {}
    for dim, ptag in gmsh.model.getPhysicalGroups():
        name = gmsh.model.getPhysicalName(dim, ptag)
        out[(dim, ptag)] = (name, [int(t) for t in gmsh.model.getEntitiesForPhysicalGroup(dim, ptag)])
    return out


def _face_normals(xyz: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Right-hand-rule normals of triangles (3 corners) or quadrilaterals (4 corners, diagonals)."""
    if faces.shape[1] == 3:
        a, b, c = (xyz[faces[:, k]] for k in range(3))
        return np.cross(b - a, c - a)
    a, b, c, d = (xyz[faces[:, k]] for k in range(4))
    return np.cross(c - a, d - b)


def _orient_outward_from_volume(gmsh, surfaces: list[int], volumes: list[int], vtype: int, index: np.ndarray,
                                xyz: np.ndarray) -> None:
    """Reverse the mesh of every named boundary surface whose faces point into the volume.

    A surface face is matched (by its corner nodes) with the one volume element it bounds;
    it points outward when its normal points away from that element's centroid.
    """
    ve = element_type(vtype)
    cells = np.concatenate([_entity_elements(gmsh, 3, v, vtype, ve.nodes, index)[1] for v in volumes])[:, :ve.corners]
    table = HEX_FACES if ve.corners == 8 else TET_FACES
    faces = cells[:, table].reshape(-1, table.shape[1])
    centre = np.repeat(xyz[cells].mean(axis=1), len(table), axis=0)
    per_surface = []
    for s in surfaces:
        types = [int(t) for t in gmsh.model.mesh.getElements(2, s)[0]]
        if any(t not in FACE_TYPES[vtype] for t in types):
            raise MeshQualityError(f"surface {s} has element types {types}; a mesh of {ve.name} elements needs "
                                   f"{', '.join(meshio_name(t) for t in FACE_TYPES[vtype])} faces")
        conns = [_entity_elements(gmsh, 2, s, t, element_type(t).nodes, index)[1][:, :table.shape[1]] for t in types]
        per_surface.append((s, np.concatenate(conns) if conns else np.zeros((0, table.shape[1]), np.int64)))
    polys = np.concatenate([t for _, t in per_surface]) if per_surface else np.zeros((0, 3), np.int64)
    if len(polys) == 0:
        return
    keys = np.sort(np.concatenate([faces, polys]), axis=1)
    _, inv = np.unique(keys, axis=0, return_inverse=True)
    inv = inv.ravel()
    face_id, poly_id = inv[:len(faces)], inv[len(faces):]
    owner = np.full(inv.max() + 1, -1, dtype=np.int64)
    count = np.bincount(face_id, minlength=owner.size)
    owner[face_id] = np.arange(len(faces))
    if np.any(count[poly_id] != 1):
        raise MeshQualityError("a named boundary surface has faces that are not on the volume's "
                               f"boundary (not exactly one adjacent {ve.name} element)")
    mid = xyz[polys].mean(axis=1)
    outward = np.einsum("ij,ij->i", _face_normals(xyz, polys), mid - centre[owner[poly_id]]) > 0
    start = 0
    flip = []
    for s, t in per_surface:
        o = outward[start:start + len(t)]
        start += len(t)
        if o.all():
            continue
        if not o.any():
            flip.append((2, s))
            continue
        raise MeshQualityError(f"surface {s} has faces of mixed orientation")
    if flip:
        gmsh.model.mesh.reverse(flip)


def _orient_closed_surface(gmsh, surfaces: list[int], stype: int, index: np.ndarray, xyz: np.ndarray) -> None:
    """Orient a closed surface made of several gmsh surfaces consistently and outward.

    Every edge (between two corners) must be shared by exactly two faces; the entities are
    flipped so that the two faces at each edge traverse it in opposite directions, then all
    together so that the enclosed volume (divergence theorem) is positive.
    """
    se = element_type(stype)
    per = [_entity_elements(gmsh, 2, s, stype, se.nodes, index)[1][:, :se.corners] for s in surfaces]
    polys = np.concatenate(per)
    n = se.corners
    ent = np.concatenate([np.full(len(t), k) for k, t in enumerate(per)])
    edges = np.concatenate([polys[:, [k, (k + 1) % n]] for k in range(n)])
    eent = np.tile(ent, n)
    forward = edges[:, 0] < edges[:, 1]
    _, inv, counts = np.unique(np.sort(edges, axis=1), axis=0, return_inverse=True, return_counts=True)
    inv = inv.ravel()
    if np.any(counts != 2):
        raise MeshQualityError(f"the surface is not closed: {int(np.sum(counts == 1))} edges belong to one "
                               f"face only and {int(np.sum(counts > 2))} to more than two")
    order = np.argsort(inv, kind="stable")
    first, second = order[0::2], order[1::2]
    e1, e2 = eent[first], eent[second]
    same = forward[first] == forward[second]          # same direction: the two sides disagree
    rel = np.unique(np.c_[e1, e2, same.astype(np.int64)], axis=0)
    flip = np.full(len(surfaces), -1, dtype=np.int64)
    flip[0] = 0
    changed = True
    while changed:
        changed = False
        for a, b, s in rel:
            if a == b:
                if s:
                    raise MeshQualityError(f"surface {surfaces[a]} is not consistently oriented")
                continue
            for u, v in ((a, b), (b, a)):
                if flip[u] >= 0:
                    want = flip[u] ^ s
                    if flip[v] < 0:
                        flip[v] = want
                        changed = True
                    elif flip[v] != want:
                        raise MeshQualityError("the closed surface cannot be oriented consistently")
        if not changed and np.any(flip < 0):
            flip[np.argmax(flip < 0)] = 0              # a separate closed component
            changed = True
    signs = np.where(flip[ent] == 1, -1.0, 1.0)
    volume = 0.0
    for k in range(1, n - 1):                         # fan of triangles (0, k, k+1)
        a, b, c = (xyz[polys[:, j]] for j in (0, k, k + 1))
        volume += np.sum(signs * np.einsum("ij,ij->i", a, np.cross(b, c))) / 6.0
    if volume < 0:
        flip ^= 1
    targets = [(2, surfaces[k]) for k in range(len(surfaces)) if flip[k] == 1]
    if targets:
        gmsh.model.mesh.reverse(targets)


def _mesh_type(gmsh, dim: int, top: list[int]) -> int:
    """The one element type of the ``dim``-D entities; refuse others and mixtures."""
    allowed = VOLUME_TYPES if dim == 3 else SURFACE_TYPES
    found = sorted({int(x) for t in top for x in gmsh.model.mesh.getElements(dim, t)[0]})
    if len(found) != 1 or found[0] not in allowed:
        names = ", ".join(meshio_name(t) for t in found) or "none"
        raise MeshQualityError(f"the {dim}-D mesh has element types {found} ({names}); expected one of "
                               f"{', '.join(f'{meshio_name(t)} ({t})' for t in allowed)}, one type per mesh")
    return found[0]


def finish_mesh(path: str | Path, model: str, parameters: dict[str, Any], dim: int,
                closed_surface: bool = False) -> MeshReport:
    """Check, orient and write the mesh of the current gmsh model; report on it.

    Call inside :func:`gmsh_session` after ``gmsh.model.mesh.generate(dim)``.

    Parameters
    ----------
    path
        Output file (MSH 4.1, ASCII); parent directories are created.
    model
        Model name for the report.
    parameters
        Parameter values used, for the report.
    dim
        3 for a volume mesh of one element type: first- or second-order tetrahedra or
        hexahedra (gmsh types 4, 11, 5, 17, 12), its surface groups of the matching faces
        (2, 9, 3, 16, 10), oriented outward here; 2 for a surface mesh of triangles or
        quadrilaterals (2, 9, 3, 16, 10).
    closed_surface
        For ``dim == 2``: the named surfaces form one closed surface; check it (each edge in
        exactly two faces) and orient it consistently outward.

    Returns
    -------
    MeshReport

    Raises
    ------
    MeshQualityError
        Inverted or zero-volume (zero-area) elements, or a surface that is not closed or
        cannot be oriented.
    RuntimeError
        Something in the model is not in a named physical group (gmsh would silently drop it).
    """
    path = Path(path)
    try:
        return _finish_mesh(path, model, parameters, dim, closed_surface)
    except MeshQualityError as exc:
        if exc.file is None:
            raise MeshQualityError(exc.message + " (the file was not written)", file=str(path)) from None
        raise


def _finish_mesh(path: Path, model: str, parameters: dict[str, Any], dim: int, closed_surface: bool) -> MeshReport:
    import gmsh

    groups = _groups(gmsh)
    for (gdim, ptag), (name, _) in groups.items():
        if not name:
            raise RuntimeError(f"physical group {ptag} (dimension {gdim}) has no name")
    grouped = {(gd, t) for (gd, _), (_, ents) in groups.items() for t in ents}
    top = [t for d, t in gmsh.model.getEntities(dim)]
    missing = [t for t in top if (dim, t) not in grouped]
    if missing:
        raise RuntimeError(f"{dim}-D entities {missing} are in no physical group and would not be written")

    index, xyz = _node_coordinates(gmsh)
    etype = _mesh_type(gmsh, dim, top)
    et = element_type(etype)
    cells = [_entity_elements(gmsh, dim, t, etype, et.nodes, index) for t in top]
    etags = np.concatenate([c[0] for c in cells])
    conn = np.concatenate([c[1] for c in cells])
    size, angle, inradius = check_cells(xyz, conn[:, :et.corners], dim)

    named_surfaces = sorted({t for (gd, _), (_, ents) in groups.items() if gd == 2 for t in ents})
    if dim == 3 and named_surfaces:
        _orient_outward_from_volume(gmsh, named_surfaces, top, etype, index, xyz)
    elif dim == 2 and closed_surface:
        _orient_closed_surface(gmsh, top, etype, index, xyz)

    sicn = np.asarray(gmsh.model.mesh.getElementQualities(etags, "minSICN"))
    # gmsh's gamma is defined for simplices only (0 for hexahedra): use its isotropy measure there
    simplex = et.corners == dim + 1
    gamma = np.asarray(gmsh.model.mesh.getElementQualities(etags, "gamma" if simplex else "minIsotropy"))
    if dim == 3 and sicn.min() <= 0:
        raise MeshQualityError(f"gmsh reports inverted {et.name} elements (min SICN {sicn.min():.3g})")

    # count what gmsh writes: the elements of entities in physical groups (each entity once)
    elements: dict[str, int] = {}
    for gd, t in sorted(grouped):
        types, tags, _ = gmsh.model.mesh.getElements(gd, t)
        for ty, tg in zip(types, tags):
            name = meshio_name(ty)
            elements[name] = elements.get(name, 0) + len(tg)
    path.parent.mkdir(parents=True, exist_ok=True)
    gmsh.write(str(path))
    used = np.unique(conn)
    notes = []
    if angle.min() < (5.0 if et.name.startswith("tetra") else 10.0 if dim == 2 and et.corners == 3 else 30.0):
        notes.append(f"poor elements (smallest angle {angle.min():.2g} deg): a smaller element_size usually helps")
    return MeshReport(
        path=path, model=model, parameters=dict(parameters), dim=dim, nodes=int(used.size),
        elements=elements, groups={name: gd for (gd, _), (name, _) in sorted(groups.items(), key=lambda kv: (-kv[0][0], kv[0][1]))},
        min_volume=float(size.min()), max_volume=float(size.max()), total_volume=float(size.sum()),
        min_angle=float(angle.min()), min_sicn=float(sicn.min()), min_gamma=float(gamma.min()),
        min_inradius=float(inradius.min()), notes=notes,
    )
