"""A solid bounded by a closed triangle mesh (gmsh, STL, OBJ or anything meshio reads).

Its point-in-solid test is a vertical ray-parity test whose edge and vertex hits are resolved by
a consistent symbolic perturbation, so every point gets a definite answer
(:mod:`pdfem.geometry.ray_parity_kernels`). Like the analytic shapes of
:mod:`pdfem.geometry.shapes` it has ``contains(x)`` and ``bounds()``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar
from os import PathLike

import numpy as np

from pdfem.geometry.points import as_points
from pdfem.geometry.ray_parity_kernels import bin_triangles, contains_kernel

__all__ = ["ClosedSurface"]



@dataclass(frozen=True, eq=False)
class ClosedSurface:
    """Solid bounded by a closed triangle mesh (m).

    Vertices with identical coordinates are merged and degenerate triangles (two equal corners)
    dropped; then every edge must be shared by exactly two triangles, otherwise ``ValueError``.
    The orientation of the triangles does not matter.

    ``contains`` counts the triangles crossed by the upward vertical ray from each point (odd:
    inside), looking only at the triangles binned into the point's column of a 2-D grid. Rays
    through edges or vertices are decided by a symbolic perturbation of the point, with every
    edge evaluated the same way for both of its triangles, so each ray crosses a consistent set.

    Parameters
    ----------
    vertices
        (V,3) float64 vertex coordinates, m.
    triangles
        (T,3) int32 vertex indices.
    """

    vertices: np.ndarray
    triangles: np.ndarray
    _grid: tuple = field(init=False, repr=False)

    def __post_init__(self):
        v = np.asarray(self.vertices, dtype=np.float64)
        t = np.asarray(self.triangles)
        if v.ndim != 2 or v.shape[1] != 3:
            raise ValueError(f"the surface's vertices must be a (V, 3) array, got shape {v.shape}")
        if t.ndim != 2 or t.shape[1] != 3:
            raise ValueError(f"the surface's triangles must be a (T, 3) array, got shape {t.shape}")
        if t.shape[0] == 0:
            raise ValueError("the surface has no triangles; a closed surface is needed to fill it "
                             "with particles")
        if not np.issubdtype(t.dtype, np.integer):
            raise ValueError(f"the surface's triangles must hold integer vertex indices, got {t.dtype}")
        if t.min() < 0 or t.max() >= v.shape[0]:
            bad = int(t.min()) if t.min() < 0 else int(t.max())
            raise ValueError(f"the surface's triangles refer to vertex {bad} but there are only "
                             f"{v.shape[0]} vertices (valid: 0 to {v.shape[0] - 1})")
        if not np.all(np.isfinite(v)):
            raise ValueError("the surface's vertices must have finite coordinates")
        v, t = _merge_vertices(v, t.astype(np.int64))
        _check_closed(t)
        v = np.ascontiguousarray(v)
        t = np.ascontiguousarray(t, dtype=np.int32)
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "triangles", t)
        object.__setattr__(self, "_grid", _build_column_grid(v, t))

    @classmethod
    def from_file(cls, path: str | PathLike, group: str | None = None) -> "ClosedSurface":
        """Read a closed surface from a mesh file (.msh, .stl, .obj, anything meshio reads).

        Parameters
        ----------
        path
            Mesh file. Its triangle cells are used; if it has none, the boundary faces of its
            tetrahedra.
        group
            Name of a physical group (gmsh) to take the cells from; ``None`` takes all cells.

        Raises
        ------
        ValueError
            If the file cannot be read, the group does not exist, there are no triangles or
            tetrahedra, or the surface is not closed.
        """
        import meshio

        try:
            with np.errstate(over="ignore"):  # meshio's binary-STL size probe overflows on ASCII files
                mesh = meshio.read(str(path))
        except Exception as exc:  # meshio raises many kinds; report them as bad input
            raise ValueError(f"cannot read the mesh file {str(path)!r}: {exc}") from None
        tri = _cells_of(mesh, ("triangle", "triangle6", "triangle7"), group, path)
        if tri.shape[0] == 0:
            tet = _cells_of(mesh, ("tetra", "tetra10"), group, path)
            if tet.shape[0] == 0:
                where = f" in the physical group {group!r}" if group is not None else ""
                raise ValueError(f"the mesh file {str(path)!r} has no triangles or tetrahedra{where}; "
                                 "a closed triangle surface (or a tetrahedral volume) is needed")
            tri = _tetra_boundary(tet)
        pts = np.zeros((mesh.points.shape[0], 3))
        pts[:, :min(3, mesh.points.shape[1])] = mesh.points[:, :3]
        return cls(pts, tri)

    def contains(self, x: np.ndarray) -> np.ndarray:
        """Whether each point of ``x`` (N,3), m, lies inside the closed surface.

        Points on the surface itself may go either way.
        """
        x = np.ascontiguousarray(as_points(x))
        out = np.zeros(x.shape[0], dtype=np.bool_)
        origin, inv_h, shape, cell_ptr, cell_tri = self._grid
        lo, hi = self.bounds()
        contains_kernel(x, self.vertices, self.triangles, origin, inv_h, shape[0], shape[1],
                         cell_ptr, cell_tri, lo, hi, out)
        return out

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Axis-aligned bounding box ``(lo, hi)``, m."""
        return self.vertices.min(axis=0), self.vertices.max(axis=0)

    fills_bounds: ClassVar[bool] = False

    def volume_bound(self) -> float:
        """An upper bound of the enclosed volume, m³: the bounding box's (the triangles of a
        user's mesh need not be consistently oriented, so no signed-volume sum is trusted)."""
        lo, hi = self.bounds()
        return float(np.prod(hi - lo))


def _cells_of(mesh, types: tuple[str, ...], group: str | None, path) -> np.ndarray:
    """Connectivity (first three or four corners) of the cells of ``types``, optionally in ``group``."""
    ncorner = 3 if types[0] == "triangle" else 4
    blocks = []
    if group is None:
        for block in mesh.cells:
            if block.type in types:
                blocks.append(np.asarray(block.data)[:, :ncorner])
    else:
        names = [n for n in (mesh.cell_sets or {}) if not n.startswith("gmsh:")]
        if group in (mesh.cell_sets or {}):
            for block, idx in zip(mesh.cells, mesh.cell_sets[group]):
                if block.type in types and idx is not None and len(idx):
                    blocks.append(np.asarray(block.data)[np.asarray(idx, dtype=np.int64), :ncorner])
        elif group in (mesh.field_data or {}) and "gmsh:physical" in (mesh.cell_data or {}):
            tag = int(mesh.field_data[group][0])
            for block, phys in zip(mesh.cells, mesh.cell_data["gmsh:physical"]):
                if block.type in types:
                    blocks.append(np.asarray(block.data)[np.asarray(phys) == tag, :ncorner])
        else:
            names = sorted(set(names) | set(mesh.field_data or {}))
            raise ValueError(f"the mesh file {str(path)!r} has no physical group named {group!r}; "
                             f"its groups are: {', '.join(names) if names else '(none)'}")
    if not blocks:
        return np.zeros((0, ncorner), dtype=np.int64)
    return np.concatenate(blocks).astype(np.int64)


def _tetra_boundary(tet: np.ndarray) -> np.ndarray:
    """Faces of the tetrahedra ``tet`` (M,4) that belong to exactly one of them."""
    faces = np.concatenate([tet[:, [0, 1, 2]], tet[:, [0, 1, 3]], tet[:, [0, 2, 3]], tet[:, [1, 2, 3]]])
    key = np.sort(faces, axis=1)
    _, first, counts = np.unique(key, axis=0, return_index=True, return_counts=True)
    return faces[first[counts == 1]]


def _merge_vertices(v: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Merge vertices with identical coordinates, drop unused ones and degenerate triangles."""
    used = np.unique(t)
    uv, inv = np.unique(v[used], axis=0, return_inverse=True)
    remap = np.full(v.shape[0], -1, dtype=np.int64)
    remap[used] = inv.reshape(-1)
    t = remap[t]
    ok = (t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 0] != t[:, 2])
    return uv, t[ok]


def _check_closed(t: np.ndarray) -> None:
    if t.shape[0] == 0:
        raise ValueError("the surface has no non-degenerate triangles; a closed surface is needed "
                         "to fill it with particles")
    edges = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    n_open = int(np.count_nonzero(counts == 1))
    n_multi = int(np.count_nonzero(counts > 2))
    if n_open:
        raise ValueError(f"the surface has {n_open} open edges; a closed surface is needed to fill "
                         "it with particles")
    if n_multi:
        raise ValueError(f"the surface has {n_multi} edges shared by more than two triangles; a closed "
                         "surface without internal or touching faces is needed to fill it with particles")


def _build_column_grid(v: np.ndarray, t: np.ndarray):
    """Bin the triangles into a 2-D grid of vertical columns by their xy bounding boxes.

    Returns ``(origin (2,), inv_h (2,), (nx, ny), cell_ptr int64, cell_tri int32)``.
    """
    lo = v[:, :2].min(axis=0)
    hi = v[:, :2].max(axis=0)
    ext = np.maximum(hi - lo, 1e-300)
    ntri = t.shape[0]
    # about one column per triangle, at most 1024 per direction
    target = max(1.0, math.sqrt(ntri))
    aspect = ext[0] / ext[1]
    nx = int(min(1024, max(1, round(target * math.sqrt(aspect)))))
    ny = int(min(1024, max(1, round(target / math.sqrt(aspect)))))
    inv_h = np.array([nx / ext[0], ny / ext[1]])
    cell_ptr, cell_tri = bin_triangles(v, t.astype(np.int32), lo, inv_h, nx, ny)
    return lo, inv_h, (nx, ny), cell_ptr, cell_tri
