"""Finite-element meshes from gmsh files: volume elements for scikit-fem plus named groups.

:func:`load_mesh` reads a gmsh MSH file (format 4.1 or 2.2) with meshio and builds a scikit-fem
mesh of first-order tetrahedra (:class:`skfem.MeshTet1`) or first-order hexahedra
(:class:`skfem.MeshHex1`). Every gmsh *physical group* with a name becomes a named group of the
returned :class:`FEMesh`:

- node set: every mesh node that an element of the group touches (any dimension);
- facet set (surface groups of a volume mesh): the group's boundary triangles (tetrahedral mesh)
  or quadrilaterals (hexahedral mesh) as rows of node indices, ordered so that the right-hand
  normal points out of the adjacent element, and as scikit-fem facet indices;
- element set (volume groups): indices of the volume elements.

Nodes that no volume element uses (gmsh writes, e.g., geometry points of a physical point) are
dropped and the rest renumbered, so that every node has mass. Elements that a MSH 2.2 file lists
twice (once per volume group) are kept once. Element orientation is checked: simply inverted
elements (all corner Jacobians negative) are renumbered to positive orientation; degenerate or
partly inverted elements are refused with a message naming the element and its corner nodes.

Coordinates are taken as they are in the file (SI: metres).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import meshio
import numpy as np
import skfem
from skfem.io.meshio import INV_HEX_MAPPING

from pdfem.fem.mesh_orientation import check_orientation
from pdfem.fem.mesh_second_order import CORNERS, corners, isoparametric_tet

# meshio cell types and their topological dimension (first- and higher-order).
_CELL_DIM = {
    "vertex": 0,
    "line": 1, "line3": 1, "line4": 1,
    "triangle": 2, "triangle6": 2, "triangle10": 2, "quad": 2, "quad8": 2, "quad9": 2,
    "tetra": 3, "tetra10": 3, "tetra20": 3, "hexahedron": 3, "hexahedron20": 3,
    "hexahedron27": 3, "wedge": 3, "wedge15": 3, "wedge18": 3, "pyramid": 3, "pyramid13": 3,
    "pyramid14": 3,
}

SUPPORTED = ("tetrahedra (gmsh element types 4 and 11: tetra, tetra10) or hexahedra (types 5, 17 "
             "and 12: hexahedron, hexahedron20, hexahedron27), one kind per mesh")



@dataclass
class MshGroups:
    """Raw content of a gmsh file: points and, per named physical group, its cells.

    Attributes
    ----------
    path
        The file read.
    points
        (N, 3) node coordinates as written in the file (m).
    volume_cells
        ``{meshio cell type: (n, k) int64 connectivity}`` of every 3-D element in the file.
    groups
        ``{name: (dim, [(meshio cell type, (n, k) int64 connectivity), ...])}``.
    """

    path: str
    points: np.ndarray
    volume_cells: dict[str, np.ndarray]
    groups: dict[str, tuple[int, list[tuple[str, np.ndarray]]]]


def read_msh_groups(path: str | os.PathLike) -> MshGroups:
    """Read a gmsh MSH file (4.1 or 2.2) into points and named physical groups.

    Parameters
    ----------
    path
        The ``.msh`` file.

    Returns
    -------
    MshGroups
        Points, all volume cells, and the cells of every named physical group.

    Raises
    ------
    ValueError
        If the file cannot be read as a gmsh mesh.
    """
    path = os.fspath(path)
    try:
        m = meshio.read(path, file_format="gmsh")
    except Exception as exc:  # meshio raises many kinds; say which file and why
        raise ValueError(f"cannot read gmsh mesh {path}: {exc}") from exc
    points = np.ascontiguousarray(m.points, dtype=np.float64)
    if points.shape[1] == 2:
        points = np.hstack([points, np.zeros((len(points), 1))])
    phys = m.cell_data.get("gmsh:physical")
    volume: dict[str, list[np.ndarray]] = {}
    for block in m.cells:
        if _CELL_DIM.get(block.type) == 3:
            volume.setdefault(block.type, []).append(np.asarray(block.data, dtype=np.int64))
    groups: dict[str, tuple[int, list[tuple[str, np.ndarray]]]] = {}
    for name, (tag, dim) in m.field_data.items():
        if name.startswith("gmsh:"):
            continue
        sets = m.cell_sets.get(name)
        members: list[tuple[str, np.ndarray]] = []
        for k, block in enumerate(m.cells):
            if _CELL_DIM.get(block.type) != int(dim):
                continue
            sel = np.zeros(len(block.data), dtype=bool)
            if phys is not None and phys[k] is not None:
                sel |= np.asarray(phys[k]) == int(tag)
            if sets is not None and sets[k] is not None and len(sets[k]) > 0:
                sel[np.asarray(sets[k], dtype=np.int64)] = True
            if sel.any():
                members.append((block.type, np.asarray(block.data, dtype=np.int64)[sel]))
        groups[name] = (int(dim), members)
    return MshGroups(path, points,
                     {k: np.vstack(v) for k, v in volume.items()}, groups)


def _unique_rows(conn: np.ndarray) -> np.ndarray:
    """Indices of the first occurrence of each element (rows equal as node sets)."""
    key = np.sort(conn, axis=1)
    _, first = np.unique(key, axis=0, return_index=True)
    return np.sort(first)


def _row_lookup(table: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """Index in ``table`` of each row of ``rows`` (compared as sorted node sets); -1 if absent."""
    if len(rows) == 0:
        return np.zeros(0, dtype=np.int64)
    a = np.sort(table, axis=1)
    b = np.sort(rows, axis=1)
    both = np.vstack([a, b])
    _, inv = np.unique(both, axis=0, return_inverse=True)
    inv = inv.ravel()
    where = np.full(inv.max() + 1, -1, dtype=np.int64)
    where[inv[: len(a)]] = np.arange(len(a))
    return where[inv[len(a):]]


@dataclass
class FEMesh:
    """A scikit-fem volume mesh with the named groups of the gmsh file it came from.

    Attributes
    ----------
    mesh
        :class:`skfem.MeshTet1` or :class:`skfem.MeshHex1`; ``mesh.p`` is (3, Nn) in metres.
    path
        The file it was read from.
    kind
        ``"tet"`` or ``"hex"``.
    node_sets
        ``{group: (n,) int32 node indices}`` for every named group.
    facet_sets
        ``{surface group: (F, 3 or 4) int32 node indices}``, outward oriented (right-hand rule).
    facet_indices
        ``{surface group: (F,) int32 scikit-fem facet indices}``, row for row with ``facet_sets``.
    element_sets
        ``{volume group: (n,) int32 element indices}``.
    line_sets
        ``{line group: (n, 2) int32 corner node pairs}`` (the group's mesh edges).
    file_order
        Order of the elements in the file (1, or 2 for tetra10 / hexahedron20 / hexahedron27).
    isoparametric
        True for a tetra10 file: ``mesh`` is a :class:`skfem.MeshTet2` keeping the file's
        midside node positions (curved elements); hexahedron20 / 27 files keep their corners only.
    """

    mesh: skfem.Mesh
    path: str
    kind: str
    node_sets: dict[str, np.ndarray] = field(default_factory=dict)
    facet_sets: dict[str, np.ndarray] = field(default_factory=dict)
    facet_indices: dict[str, np.ndarray] = field(default_factory=dict)
    element_sets: dict[str, np.ndarray] = field(default_factory=dict)
    line_sets: dict[str, np.ndarray] = field(default_factory=dict)
    file_order: int = 1
    isoparametric: bool = False

    @property
    def points(self) -> np.ndarray:
        """(Nn, 3) reference node coordinates (m)."""
        return np.ascontiguousarray(self.mesh.p[:, :self.mesh.nvertices].T)

    @property
    def n_nodes(self) -> int:
        """Number of nodes."""
        return int(self.mesh.nvertices)

    @property
    def n_elements(self) -> int:
        """Number of volume elements."""
        return int(self.mesh.t.shape[1])

    @property
    def group_names(self) -> list[str]:
        """Names of all groups in the file, sorted."""
        return sorted(self.node_sets)

    def _missing(self, name: str, table: dict, what: str) -> ValueError:
        have = ", ".join(sorted(table)) or "(none)"
        extra = ""
        if name in self.node_sets:
            extra = f" ('{name}' exists but is not a {what} group)"
        kinds = "groups" if what == "named" else f"{what} groups"
        return ValueError(f"group '{name}' not in {self.path}{extra}; the file has {kinds}: {have}")

    def group_nodes(self, name: str) -> np.ndarray:
        """Node indices (int32, sorted) of the named group.

        Raises
        ------
        ValueError
            If the file has no group of that name (the message lists the groups it has).
        """
        if name not in self.node_sets:
            raise self._missing(name, self.node_sets, "named")
        return self.node_sets[name]

    def group_facets(self, name: str) -> np.ndarray:
        """Boundary faces (F, 3) or (F, 4) of a surface group as outward-oriented node indices.

        Raises
        ------
        ValueError
            If there is no surface group of that name.
        """
        if name not in self.facet_sets:
            raise self._missing(name, self.facet_sets, "surface")
        return self.facet_sets[name]

    def group_facet_indices(self, name: str) -> np.ndarray:
        """scikit-fem facet indices (int32) of a surface group, row by row as :meth:`group_facets`.

        Raises
        ------
        ValueError
            If there is no surface group of that name.
        """
        if name not in self.facet_indices:
            raise self._missing(name, self.facet_indices, "surface")
        return self.facet_indices[name]

    def group_elements(self, name: str) -> np.ndarray:
        """Element indices (int32) of a volume group.

        Raises
        ------
        ValueError
            If there is no volume group of that name.
        """
        if name not in self.element_sets:
            raise self._missing(name, self.element_sets, "volume")
        return self.element_sets[name]


def _outward_faces(p: np.ndarray, faces: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """Reorder each face so its right-hand normal points away from its element's centre."""
    x = p[faces]
    n = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    if faces.shape[1] == 4:  # quads: the area vector from the diagonals is robust to warping
        n = np.cross(x[:, 2] - x[:, 0], x[:, 3] - x[:, 1])
    inward = np.einsum("ij,ij->i", n, x.mean(axis=1) - centres) < 0
    out = faces.copy()
    out[inward] = out[inward][:, ::-1]
    return out


def load_mesh(path: str | os.PathLike) -> FEMesh:
    """Load a gmsh volume mesh into scikit-fem with its named groups.

    Parameters
    ----------
    path
        A gmsh ``.msh`` file (format 4.1 or 2.2) holding tetrahedra or hexahedra, first or second
        order (tetra10, hexahedron20, hexahedron27 with triangle6 / quad8 / quad9 faces), with
        named physical groups (coordinates in metres). tetra10 elements are kept isoparametric
        (:class:`skfem.MeshTet2` with the file's midside node positions, curved geometry);
        hexahedron20 / 27 elements are read by their corner nodes (the structure adds
        straight-sided midside nodes again, so a curved boundary becomes flat faces).

    Returns
    -------
    FEMesh
        The scikit-fem mesh (positively oriented elements, unused nodes dropped) and its groups.

    Raises
    ------
    ValueError
        If the file has no volume elements, mixes element kinds or has other elements (the
        message says what is supported), if a surface group has faces that are not faces of
        the volume mesh, or if an element is degenerate or tangled.
    """
    raw = read_msh_groups(path)
    path = raw.path
    kinds = sorted(raw.volume_cells)
    if not kinds:
        raise ValueError(f"{path} has no volume elements; pdfem needs a 3-D mesh of {SUPPORTED} "
                         "in a named volume physical group")
    if len(kinds) > 1 or kinds[0] not in CORNERS:
        raise ValueError(f"{path} has volume elements of type(s) {', '.join(kinds)}; "
                         f"supported are {SUPPORTED}")
    file_type = kinds[0]
    kind, nc = CORNERS[file_type]
    cell_type = "tetra" if kind == "tet" else "hexahedron"
    full = raw.volume_cells[file_type]
    full = full[_unique_rows(full[:, :nc])]
    conn = full[:, :nc]

    used = np.unique(conn)
    renum = np.full(len(raw.points), -1, dtype=np.int64)
    renum[used] = np.arange(len(used))
    p = raw.points[used]
    t = check_orientation(path, p, renum[conn], kind)

    t_sk = t if kind == "tet" else t[:, INV_HEX_MAPPING[:8]]
    mesh_type = skfem.MeshTet1 if kind == "tet" else skfem.MeshHex1
    mesh = mesh_type(np.ascontiguousarray(p.T), np.ascontiguousarray(t_sk.T, dtype=np.int32))

    face_type = "triangle" if kind == "tet" else "quad"
    if file_type == "tetra10":
        mesh = isoparametric_tet(mesh, raw.points, renum, full)
    femesh = FEMesh(mesh=mesh, path=path, kind=kind, file_order=1 if nc == full.shape[1] else 2,
                    isoparametric=file_type == "tetra10")
    members_of = {name: (dim, [corners(ct, c) for ct, c in members])
                  for name, (dim, members) in raw.groups.items()}
    centres = p[t].mean(axis=1)
    mesh_facets = np.ascontiguousarray(mesh.facets.T)
    for name, (dim, members) in members_of.items():
        nodes = [renum[c].ravel() for _, c in members]
        nodes = np.concatenate(nodes) if nodes else np.zeros(0, dtype=np.int64)
        femesh.node_sets[name] = np.unique(nodes[nodes >= 0]).astype(np.int32)
        if dim == 3:
            cells = [c for ct, c in members if ct == kind]
            cells = np.vstack(cells) if cells else np.zeros((0, t.shape[1]), dtype=np.int64)
            idx = _row_lookup(t, renum[cells])
            femesh.element_sets[name] = np.unique(idx[idx >= 0]).astype(np.int32)
        elif dim == 2:
            others = sorted({ct for ct, _ in members if ct != ("tri" if kind == "tet" else "quad")})
            if others:
                raise ValueError(f"{path}: surface group '{name}' has {', '.join(others)} "
                                 f"elements, but faces of a {cell_type} mesh are {face_type}s")
            faces = [c for _, c in members]
            nf = 3 if kind == "tet" else 4
            faces = renum[np.vstack(faces)] if faces else np.zeros((0, nf), dtype=np.int64)
            faces = faces[_unique_rows(faces)] if len(faces) else faces
            if (faces < 0).any():
                raise ValueError(f"{path}: surface group '{name}' has faces whose nodes belong "
                                 "to no volume element")
            fidx = _row_lookup(mesh_facets, faces)
            if (fidx < 0).any():
                k = int(np.flatnonzero(fidx < 0)[0])
                raise ValueError(f"{path}: surface group '{name}' has {int((fidx < 0).sum())} "
                                 f"face(s) that are not faces of the volume mesh, e.g. nodes at "
                                 f"{np.round(p[faces[k]], 9).tolist()}; the surface and volume "
                                 "meshes must be conforming")
            elem = mesh.f2t[0, fidx]
            femesh.facet_sets[name] = _outward_faces(p, faces, centres[elem]).astype(np.int32)
            femesh.facet_indices[name] = fidx.astype(np.int32)
        elif dim == 1:
            lines = [renum[c] for ct, c in members if ct == "line"]
            lines = np.vstack(lines) if lines else np.zeros((0, 2), dtype=np.int64)
            femesh.line_sets[name] = lines[(lines >= 0).all(axis=1)].astype(np.int32)
    return femesh
