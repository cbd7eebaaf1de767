"""Geometric regions: the shapes that ice bodies are filled from and that select boundary regions.

Every shape is a frozen dataclass with two methods:

``contains(x)``
    (N,3) points (m) -> (N,) bool, vectorised.
``bounds()``
    the axis-aligned bounding box ``(lo, hi)``, two (3,) float64 arrays (m).

:class:`Box`, :class:`Cylinder` and :class:`Sphere` are inclusive with a tolerance of 1e-9 times
the shape's diagonal (diameter for a sphere), so lattice points that lie exactly on a face count as
inside. :class:`ClosedSurface` is a closed triangle mesh (from gmsh, STL, OBJ or anything meshio
reads); its point-in-solid test is a vertical ray-parity test whose edge and vertex hits are
resolved by a consistent symbolic perturbation, so every point gets a definite answer.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from os import PathLike

import numba
import numpy as np

__all__ = ["Box", "Cylinder", "Sphere", "ClosedSurface"]

#: relative tolerance of the inclusive analytic shapes (times the diagonal or diameter)
REL_TOL = 1e-9


def _vec3(value, name: str, what: str) -> tuple[float, float, float]:
    arr = np.asarray(value, dtype=np.float64).reshape(-1)
    if arr.shape != (3,):
        raise ValueError(f"the {what}'s {name} must have 3 components, got {arr.shape[0]}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"the {what}'s {name} must be finite, got {arr.tolist()}")
    return (float(arr[0]), float(arr[1]), float(arr[2]))


def _points(x) -> np.ndarray:
    x = np.asarray(x, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != 3:
        raise ValueError(f"points must be an (N, 3) array, got shape {x.shape}")
    return x


@dataclass(frozen=True)
class Box:
    """Axis-aligned box ``min <= x <= max`` (m), inclusive up to 1e-9 times the diagonal.

    Parameters
    ----------
    min, max
        Opposite corners, m; every component of ``max`` must exceed that of ``min``.
    """

    min: tuple[float, float, float]
    max: tuple[float, float, float]

    def __post_init__(self):
        lo = _vec3(self.min, "min", "box")
        hi = _vec3(self.max, "max", "box")
        bad = [ax for ax, a, b in zip("xyz", lo, hi) if not b > a]
        if bad:
            raise ValueError(f"the box's max must be larger than its min in every direction "
                             f"(not in {', '.join(bad)}: min = {list(lo)}, max = {list(hi)})")
        object.__setattr__(self, "min", lo)
        object.__setattr__(self, "max", hi)

    @property
    def tolerance(self) -> float:
        """Inclusion tolerance, m (1e-9 times the diagonal)."""
        return REL_TOL * math.dist(self.min, self.max)

    def contains(self, x: np.ndarray) -> np.ndarray:
        """Whether each point of ``x`` (N,3), m, lies in the box (faces included)."""
        x = _points(x)
        t = self.tolerance
        lo = np.asarray(self.min) - t
        hi = np.asarray(self.max) + t
        return np.all((x >= lo) & (x <= hi), axis=1)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Axis-aligned bounding box ``(lo, hi)``, m."""
        return np.array(self.min), np.array(self.max)


@dataclass(frozen=True)
class Cylinder:
    """Solid circular cylinder (m).

    Parameters
    ----------
    base
        Centre of the bottom disc, m.
    axis
        Direction of the axis (any length > 0; normalised internally).
    radius
        Radius, m (> 0).
    length
        Length along ``axis`` from ``base``, m (> 0).
    """

    base: tuple[float, float, float]
    axis: tuple[float, float, float]
    radius: float
    length: float

    def __post_init__(self):
        base = _vec3(self.base, "base", "cylinder")
        axis = np.array(_vec3(self.axis, "axis", "cylinder"))
        norm = float(np.linalg.norm(axis))
        if norm == 0.0:
            raise ValueError("the cylinder's axis must not be the zero vector")
        axis = axis / norm
        r, ln = float(self.radius), float(self.length)
        if not (math.isfinite(r) and r > 0.0):
            raise ValueError(f"the cylinder's radius must be a positive length in m, got {self.radius!r}")
        if not (math.isfinite(ln) and ln > 0.0):
            raise ValueError(f"the cylinder's length must be a positive length in m, got {self.length!r}")
        object.__setattr__(self, "base", base)
        object.__setattr__(self, "axis", (float(axis[0]), float(axis[1]), float(axis[2])))
        object.__setattr__(self, "radius", r)
        object.__setattr__(self, "length", ln)

    @property
    def tolerance(self) -> float:
        """Inclusion tolerance, m (1e-9 times the diagonal of the axial section)."""
        return REL_TOL * math.hypot(self.length, 2.0 * self.radius)

    def contains(self, x: np.ndarray) -> np.ndarray:
        """Whether each point of ``x`` (N,3), m, lies in the cylinder (surface included)."""
        x = _points(x)
        t = self.tolerance
        d = x - np.asarray(self.base)
        a = np.asarray(self.axis)
        s = d @ a
        radial2 = np.einsum("ij,ij->i", d, d) - s * s
        return (s >= -t) & (s <= self.length + t) & (radial2 <= (self.radius + t) ** 2)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Exact axis-aligned bounding box ``(lo, hi)``, m."""
        a = np.asarray(self.axis)
        b0 = np.asarray(self.base)
        b1 = b0 + self.length * a
        ext = self.radius * np.sqrt(np.clip(1.0 - a * a, 0.0, 1.0))
        return np.minimum(b0, b1) - ext, np.maximum(b0, b1) + ext


@dataclass(frozen=True)
class Sphere:
    """Solid sphere (m), inclusive up to 1e-9 times the diameter.

    Parameters
    ----------
    center
        Centre, m.
    radius
        Radius, m (> 0).
    """

    center: tuple[float, float, float]
    radius: float

    def __post_init__(self):
        c = _vec3(self.center, "center", "sphere")
        r = float(self.radius)
        if not (math.isfinite(r) and r > 0.0):
            raise ValueError(f"the sphere's radius must be a positive length in m, got {self.radius!r}")
        object.__setattr__(self, "center", c)
        object.__setattr__(self, "radius", r)

    @property
    def tolerance(self) -> float:
        """Inclusion tolerance, m (1e-9 times the diameter)."""
        return REL_TOL * 2.0 * self.radius

    def contains(self, x: np.ndarray) -> np.ndarray:
        """Whether each point of ``x`` (N,3), m, lies in the sphere (surface included)."""
        x = _points(x)
        d = x - np.asarray(self.center)
        return np.einsum("ij,ij->i", d, d) <= (self.radius + self.tolerance) ** 2

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Axis-aligned bounding box ``(lo, hi)``, m."""
        c = np.asarray(self.center)
        return c - self.radius, c + self.radius


# --------------------------------------------------------------------------------------------
# closed triangle meshes


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
        x = np.ascontiguousarray(_points(x))
        out = np.zeros(x.shape[0], dtype=np.bool_)
        origin, inv_h, shape, cell_ptr, cell_tri = self._grid
        lo, hi = self.bounds()
        _contains_kernel(x, self.vertices, self.triangles, origin, inv_h, shape[0], shape[1],
                         cell_ptr, cell_tri, lo, hi, out)
        return out

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Axis-aligned bounding box ``(lo, hi)``, m."""
        return self.vertices.min(axis=0), self.vertices.max(axis=0)


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
    cell_ptr, cell_tri = _bin_triangles(v, t.astype(np.int32), lo, inv_h, nx, ny)
    return lo, inv_h, (nx, ny), cell_ptr, cell_tri


@numba.njit(cache=True)
def _cell_index(p: float, lo: float, inv_h: float, n: int) -> int:
    c = int(math.floor((p - lo) * inv_h))
    if c < 0:
        return 0
    if c >= n:
        return n - 1
    return c


@numba.njit(cache=True)
def _bin_triangles(v, t, lo, inv_h, nx, ny):
    ntri = t.shape[0]
    counts = np.zeros(nx * ny + 1, dtype=np.int64)
    for pass_ in range(2):
        if pass_ == 1:
            for c in range(nx * ny):
                counts[c + 1] += counts[c]
            cell_tri = np.empty(counts[nx * ny], dtype=np.int32)
            fill = counts[:-1].copy()
        for k in range(ntri):
            a, b, c = t[k, 0], t[k, 1], t[k, 2]
            xmin = min(v[a, 0], v[b, 0], v[c, 0])
            xmax = max(v[a, 0], v[b, 0], v[c, 0])
            ymin = min(v[a, 1], v[b, 1], v[c, 1])
            ymax = max(v[a, 1], v[b, 1], v[c, 1])
            i0 = _cell_index(xmin, lo[0], inv_h[0], nx)
            i1 = _cell_index(xmax, lo[0], inv_h[0], nx)
            j0 = _cell_index(ymin, lo[1], inv_h[1], ny)
            j1 = _cell_index(ymax, lo[1], inv_h[1], ny)
            for i in range(i0, i1 + 1):
                for j in range(j0, j1 + 1):
                    cell = i * ny + j
                    if pass_ == 0:
                        counts[cell + 1] += 1
                    else:
                        cell_tri[fill[cell]] = k
                        fill[cell] += 1
    return counts, cell_tri


@numba.njit(cache=True)
def _orient(v, a, b, px, py):
    """orient2d(a, b, p) = (b - a) x (p - anchor) in the xy projection, computed consistently.

    The edge is taken in canonical vertex order (lower index first) and the value negated for the
    reverse edge, and the anchor is whichever end of the edge is nearer to p (a choice that
    depends only on the edge and p), so the two triangles that share an edge see exactly
    opposite values, and near a vertex every edge of its fan is measured from that vertex, where
    p - vertex is exact: the fan's signs agree with each other.
    """
    flip = 1.0
    if a > b:
        a, b = b, a
        flip = -1.0
    ax, ay = v[a, 0], v[a, 1]
    bx, by = v[b, 0], v[b, 1]
    if abs(px - ax) + abs(py - ay) <= abs(px - bx) + abs(py - by):
        w = (bx - ax) * (py - ay) - (by - ay) * (px - ax)
    else:
        w = (bx - ax) * (py - by) - (by - ay) * (px - bx)
    return flip * w


@numba.njit(cache=True)
def _edge_side(v, a, b, px, py):
    """Sign (+1/-1) of :func:`_orient` (a, b, p), never 0 unless a and b coincide in projection.

    A zero is resolved by the symbolic perturbation p -> p + (eps, eps^2), eps -> 0+: the sign of
    d w / d px, else of d w / d py (exact: signs of coordinate differences).
    """
    w = _orient(v, a, b, px, py)
    if w == 0.0:
        w = -(v[b, 1] - v[a, 1])          # d w / d px
        if w == 0.0:
            w = v[b, 0] - v[a, 0]         # d w / d py
    if w > 0.0:
        return 1.0
    if w < 0.0:
        return -1.0
    return 0.0  # a and b coincide in projection: the triangle is degenerate there


@numba.njit(cache=True, parallel=True)
def _contains_kernel(x, v, t, origin, inv_h, nx, ny, cell_ptr, cell_tri, lo, hi, out):
    """Vertical ray parity: count triangles hit by the upward ray from each point."""
    n = x.shape[0]
    for p in numba.prange(n):
        px, py, pz = x[p, 0], x[p, 1], x[p, 2]
        if px < lo[0] or py < lo[1] or pz < lo[2] or px > hi[0] or py > hi[1] or pz > hi[2]:
            out[p] = False
            continue
        i = _cell_index(px, origin[0], inv_h[0], nx)
        j = _cell_index(py, origin[1], inv_h[1], ny)
        cell = i * ny + j
        crossings = 0
        for q in range(cell_ptr[cell], cell_ptr[cell + 1]):
            k = cell_tri[q]
            a, b, c = t[k, 0], t[k, 1], t[k, 2]
            s0 = _edge_side(v, a, b, px, py)
            s1 = _edge_side(v, b, c, px, py)
            s2 = _edge_side(v, c, a, px, py)
            if s0 == 0.0 or s0 != s1 or s1 != s2:
                continue
            # height of the triangle's plane above (px, py) from barycentric weights
            wc = _orient(v, a, b, px, py)
            wa = _orient(v, b, c, px, py)
            wb = _orient(v, c, a, px, py)
            den = wa + wb + wc
            if den == 0.0:
                continue
            z = (wa * v[a, 2] + wb * v[b, 2] + wc * v[c, 2]) / den
            if z > pz:
                crossings += 1
        out[p] = (crossings & 1) == 1
