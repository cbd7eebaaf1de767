"""Shared machinery of the parametric gmsh models in ``models/`` and of ``pdfem mesh``.

A model module (``pdfem.models.<name>`` or any ``.py`` file) exposes

    PARAMETERS: dict[str, tuple[default, unit, description]]
    build(path, **params) -> MeshReport

and uses the helpers here to do the common parts the same way:

* :class:`ModelParameterError` -- a bad parameter, named (a :class:`ValueError`, and an
  :class:`~pdfem.errors.InputError` so the command line exits with status 2);
* :func:`check_parameters` and the ``require_*`` checks -- defaults, types, ranges;
* :func:`require_element_budget` -- refuse an element size that would make gmsh run for hours;
* :func:`gmsh_session` -- a headless gmsh session that is always finalised,
  :func:`set_mesh_size` -- one element size everywhere (optionally refined by curvature), and
  :func:`generate_mesh` -- meshing with gmsh's failures turned into clear errors;
* :func:`finish_mesh` -- refuse inverted or zero-volume elements, orient the named surfaces
  outward, write MSH 4.1, and return a :class:`MeshReport` (sizes, groups, quality);
* :func:`resolve_model`, :func:`parse_set` and :func:`mesh_model` -- what ``pdfem mesh MODEL
  [--set key=value ...] [-o FILE.msh]`` does.

The quality measures themselves (volumes, angles, inscribed radii, the inverted-element check)
and :class:`MeshQualityError` live in :mod:`pdfem.meshing.quality`; they are importable from here
too.

Lengths are in m, areas in m^2, volumes in m^3, angles in the reports in degrees (parameters
that are angles are in rad, SI).
"""

from __future__ import annotations

import contextlib
import importlib
import importlib.util
import math
import pkgutil
import sys
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any, Iterator

import numpy as np

from pdfem.errors import InputError
from pdfem.meshing import quality as mesh_quality
from pdfem.meshing.quality import (DEGENERATE, CellQuality, MeshQualityError, check_cells, longest_edges,  # noqa: F401
                           tet_inradii, tet_min_dihedral, tet_volumes, triangle_areas, triangle_inradii,
                           triangle_min_angle)

__all__ = [
    "ModelParameterError",
    "MeshReport",
    "check_parameters",
    "require_positive",
    "require_range",
    "require_choice",
    "require",
    "require_element_budget",
    "MAX_SURFACE_TRIANGLES",
    "gmsh_session",
    "set_mesh_size",
    "generate_mesh",
    "finish_mesh",
    "available_models",
    "resolve_model",
    "parse_set",
    "coerce_parameters",
    "mesh_model",
] + mesh_quality.__all__          # re-exported: the quality measures and MeshQualityError

#: Most surface triangles a model may ask gmsh for (see :func:`require_element_budget`).
MAX_SURFACE_TRIANGLES = 4_000_000

# gmsh element type -> meshio cell type name (first-order types only: the models write those).
_GMSH_TYPES = {15: "vertex", 1: "line", 2: "triangle", 3: "quad", 4: "tetra", 5: "hexahedron",
               6: "wedge", 7: "pyramid"}


class ModelParameterError(InputError, ValueError):
    """A model parameter that is unknown, of the wrong type, out of range or inconsistent.

    Parameters
    ----------
    param
        Name of the offending parameter (as in the model's ``PARAMETERS``), or ``"model"``
        for a model name or path that cannot be resolved.
    value
        The offending value.
    message
        What is wrong and what would be valid, as a sentence.
    """

    def __init__(self, param: str, value: Any, message: str):
        self.param = param
        super().__init__(None, param, message, value)


# --------------------------------------------------------------------------------------------
# parameters

_TYPE_NAMES = {bool: "a boolean (true/false)", int: "an integer", float: "a number", str: "a string"}


def check_parameters(parameters: dict[str, tuple], given: dict[str, Any]) -> dict[str, Any]:
    """Fill in defaults and check the names and types of a model's parameters.

    Parameters
    ----------
    parameters
        The model's ``PARAMETERS``: name -> (default, unit, description). The default's type
        (bool, int, float or str) is the parameter's type; an int is accepted for a float.
    given
        The values given by the caller (already typed; see :func:`coerce_parameters` for
        strings from the command line).

    Returns
    -------
    dict
        Every parameter with its value (given or default), floats as ``float``.

    Raises
    ------
    ModelParameterError
        An unknown name (the message lists the valid ones), a value of the wrong type, or a
        float that is not finite.
    """
    out: dict[str, Any] = {}
    for key, value in given.items():
        if key not in parameters:
            raise ModelParameterError(key, value, "unknown parameter; valid parameters are: "
                                      + ", ".join(sorted(parameters)))
    for key, (default, _unit, _desc) in parameters.items():
        value = given.get(key, default)
        kind = type(default)
        if kind is float:
            if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
                raise ModelParameterError(key, value, f"must be {_TYPE_NAMES[float]}")
            value = float(value)
            if not math.isfinite(value):
                raise ModelParameterError(key, value, "must be a finite number")
        elif kind is int:
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                raise ModelParameterError(key, value, f"must be {_TYPE_NAMES[int]}")
            value = int(value)
        elif kind is bool:
            if not isinstance(value, (bool, np.bool_)):
                raise ModelParameterError(key, value, f"must be {_TYPE_NAMES[bool]}")
            value = bool(value)
        elif kind is str:
            if not isinstance(value, str):
                raise ModelParameterError(key, value, f"must be {_TYPE_NAMES[str]}")
        out[key] = value
    return out


def require(condition: bool, param: str, value: Any, message: str) -> None:
    """Raise :class:`ModelParameterError` ``(param, value, message)`` unless ``condition``."""
    if not condition:
        raise ModelParameterError(param, value, message)


def require_positive(params: dict[str, Any], *names: str) -> None:
    """Check that each named parameter is > 0 (raises :class:`ModelParameterError`)."""
    for name in names:
        require(params[name] > 0, name, params[name], "must be > 0")


def require_range(params: dict[str, Any], name: str, low: float | None = None, high: float | None = None,
                  *, low_open: bool = False, high_open: bool = False, unit: str = "") -> None:
    """Check ``low <= params[name] <= high`` (``<`` for an open end); ``None`` means unbounded."""
    v = params[name]
    u = f" {unit}" if unit else ""
    if low is not None and (v <= low if low_open else v < low):
        raise ModelParameterError(name, v, f"must be {'>' if low_open else '>='} {low:g}{u}")
    if high is not None and (v >= high if high_open else v > high):
        raise ModelParameterError(name, v, f"must be {'<' if high_open else '<='} {high:g}{u}")


def require_choice(params: dict[str, Any], name: str, choices: tuple[str, ...]) -> None:
    """Check that a string parameter is one of ``choices``."""
    require(params[name] in choices, name, params[name], "must be one of: " + ", ".join(choices))


def require_element_budget(area: float, element_size: float, what: str) -> None:
    """Refuse an ``element_size`` that would cover ``area`` with too many surface triangles.

    Guards against a mistyped element size that would take gmsh hours and all the memory.

    Parameters
    ----------
    area
        Surface area to be meshed, m^2 (an estimate is enough).
    element_size
        Target element edge length, m.
    what
        The object, for the message (e.g. ``"this panel"``).

    Raises
    ------
    ModelParameterError
        (``param == "element_size"``) more than :data:`MAX_SURFACE_TRIANGLES` triangles of
        that size (area 0.433 h^2 each) would be needed.
    """
    tris = area / (0.433 * element_size * element_size)
    require(tris < MAX_SURFACE_TRIANGLES, "element_size", element_size,
            f"too small for {what} (about {tris:.2g} surface triangles; at most {MAX_SURFACE_TRIANGLES:.0e})")


def _parse_bool(text: str) -> bool:
    t = text.strip().lower()
    if t in ("1", "true", "yes", "on"):
        return True
    if t in ("0", "false", "no", "off"):
        return False
    raise ValueError(text)


def coerce_parameters(parameters: dict[str, tuple], raw: dict[str, Any]) -> dict[str, Any]:
    """Convert ``--set`` values (strings) to the types of the parameters' defaults.

    Parameters
    ----------
    parameters
        The model's ``PARAMETERS``.
    raw
        name -> value; strings are parsed as the default's type (float, int, bool: true/false,
        yes/no, 1/0; str as is), other values are passed on unchanged.

    Returns
    -------
    dict
        The typed values (only the given names; defaults are filled in by the model).

    Raises
    ------
    ModelParameterError
        An unknown name (listing the valid names) or a string that does not parse.
    """
    out: dict[str, Any] = {}
    for key, value in raw.items():
        if key not in parameters:
            raise ModelParameterError(key, value, "unknown parameter; valid parameters are: "
                                      + ", ".join(sorted(parameters)))
        kind = type(parameters[key][0])
        if isinstance(value, str) and kind is not str:
            try:
                value = _parse_bool(value) if kind is bool else kind(value.strip())
            except ValueError:
                raise ModelParameterError(key, value, f"must be {_TYPE_NAMES.get(kind, kind.__name__)}") from None
        out[key] = value
    return out


def parse_set(items: list[str] | tuple[str, ...]) -> dict[str, str]:
    """Split command-line ``key=value`` strings into a dict (later keys win).

    Raises
    ------
    ModelParameterError
        An item without ``=`` or with an empty key.
    """
    out: dict[str, str] = {}
    for item in items:
        key, sep, value = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise ModelParameterError("--set", item, "expected key=value")
        out[key] = value.strip()
    return out


# --------------------------------------------------------------------------------------------
# gmsh session

@contextlib.contextmanager
def gmsh_session(name: str = "model") -> Iterator[Any]:
    """A headless gmsh session: yields the ``gmsh`` module, always finalises it.

    Calls ``gmsh.initialize(interruptible=False)`` (safe outside the main thread), silences the
    terminal output and selects MSH 4.1 (ASCII) for writing. gmsh has one global state per
    process, so sessions cannot be nested.

    Parameters
    ----------
    name
        Name of the gmsh model that is added.

    Raises
    ------
    RuntimeError
        gmsh is already initialised (a session is open).
    """
    import gmsh

    if gmsh.isInitialized():
        raise RuntimeError("a gmsh session is already open in this process; sessions cannot be nested")
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.Verbosity", 2)
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.option.setNumber("Mesh.Binary", 0)
        gmsh.option.setNumber("Mesh.SaveAll", 0)
        gmsh.option.setNumber("Mesh.ElementOrder", 1)
        gmsh.model.add(name)
        yield gmsh
    finally:
        gmsh.finalize()


def set_mesh_size(max_size: float, min_size: float = 0.0, curvature: int = 0) -> None:
    """Mesh the open session's model with one target element size, set by options only.

    Sizes from the geometry's points and extended from the boundary are switched off, so the
    elements are ``max_size`` everywhere except where ``curvature`` refines them.

    Parameters
    ----------
    max_size
        Largest (target) element edge length, m.
    min_size
        Smallest element edge length, m (a floor for the curvature refinement).
    curvature
        Elements per 2 pi of curvature (gmsh's ``Mesh.MeshSizeFromCurvature``); 0: off.
    """
    import gmsh

    gmsh.option.setNumber("Mesh.MeshSizeMin", min_size)
    gmsh.option.setNumber("Mesh.MeshSizeMax", max_size)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", curvature)


def generate_mesh(dim: int) -> None:
    """``gmsh.model.mesh.generate(dim)`` in the open session; a gmsh failure becomes a
    :class:`MeshQualityError` (bad input: usually the element size for the geometry)."""
    import gmsh

    try:
        gmsh.model.mesh.generate(dim)
    except Exception as exc:  # gmsh raises a bare Exception with its last error message
        raise MeshQualityError(f"gmsh could not mesh the model ({exc}); another element_size may work") from None


# --------------------------------------------------------------------------------------------
# report

@dataclass
class MeshReport:
    """What a model wrote and how good the mesh is.

    Attributes
    ----------
    path
        The MSH 4.1 file written.
    model
        Model name.
    parameters
        The parameter values used (SI).
    dim
        Dimension of the mesh's cells: 3 (tetrahedra) or 2 (a surface of triangles).
    nodes
        Number of mesh nodes.
    elements
        Number of elements written, by meshio cell type (``"tetra"``, ``"triangle"``, ...).
    groups
        Physical group name -> dimension.
    min_volume, max_volume
        Smallest and largest cell volume (m^3), or area (m^2) for a surface mesh.
    total_volume
        Sum of the cell volumes (m^3), or areas (m^2) for a surface mesh.
    min_angle
        Smallest dihedral angle of a tetrahedron (deg), or smallest interior angle of a
        triangle for a surface mesh.
    min_sicn
        gmsh's smallest signed inverse condition number (1 ideal, <= 0 inverted).
    min_gamma
        gmsh's smallest inscribed/circumscribed radius ratio (normalised, 1 ideal).
    min_inradius
        Smallest inscribed-sphere (circle) radius, m: the length that limits an explicit
        solver's stable time step.
    notes
        Remarks for the user (model layout, quality warnings).
    """

    path: Path
    model: str
    parameters: dict[str, Any]
    dim: int
    nodes: int
    elements: dict[str, int]
    groups: dict[str, int]
    min_volume: float
    max_volume: float
    total_volume: float
    min_angle: float
    min_sicn: float
    min_gamma: float
    min_inradius: float
    notes: list[str] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        """The report as plain JSON-serialisable values (the path as a string)."""
        out = {k: getattr(self, k) for k in self.__dataclass_fields__}
        out["path"] = str(self.path)
        return out

    def text(self) -> str:
        """A few lines for the terminal."""
        what = "volume" if self.dim == 3 else "area"
        unit = "m^3" if self.dim == 3 else "m^2"
        angle = "dihedral angle" if self.dim == 3 else "triangle angle"
        lines = [
            f"wrote {self.path} (model {self.model}, MSH 4.1)",
            f"  nodes: {self.nodes}",
            "  elements: " + ", ".join(f"{n} {t}" for t, n in self.elements.items()),
            "  groups: " + ", ".join(f"{g} ({d}-D)" for g, d in self.groups.items()),
            f"  element {what}: min {self.min_volume:.4g} {unit}, max {self.max_volume:.4g} {unit},"
            f" total {self.total_volume:.6g} {unit}",
            f"  quality: min {angle} {self.min_angle:.2f} deg, min SICN {self.min_sicn:.3f},"
            f" min gamma {self.min_gamma:.3f}, min inscribed radius {self.min_inradius:.3g} m",
        ]
        lines += [f"  note: {n}" for n in self.notes]
        return "\n".join(lines)


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


def _orient_outward_from_volume(gmsh, surfaces: list[int], volumes: list[int], index: np.ndarray,
                                xyz: np.ndarray) -> None:
    """Reverse the mesh of every named boundary surface whose triangles point into the volume."""
    tets = np.concatenate([_entity_elements(gmsh, 3, v, 4, 4, index)[1] for v in volumes])
    faces = np.concatenate([tets[:, [1, 2, 3]], tets[:, [0, 2, 3]], tets[:, [0, 1, 3]], tets[:, [0, 1, 2]]])
    opposite = np.concatenate([tets[:, 0], tets[:, 1], tets[:, 2], tets[:, 3]])
    per_surface = [(s, _entity_elements(gmsh, 2, s, 2, 3, index)[1]) for s in surfaces]
    tris = np.concatenate([t for _, t in per_surface]) if per_surface else np.zeros((0, 3), np.int64)
    if len(tris) == 0:
        return
    keys = np.sort(np.concatenate([faces, tris]), axis=1)
    _, inv = np.unique(keys, axis=0, return_inverse=True)
    inv = inv.ravel()
    face_id, tri_id = inv[:len(faces)], inv[len(faces):]
    owner = np.full(inv.max() + 1, -1, dtype=np.int64)
    count = np.bincount(face_id, minlength=owner.size)
    owner[face_id] = np.arange(len(faces))
    if np.any(count[tri_id] != 1):
        raise MeshQualityError("a named boundary surface has triangles that are not on the volume's "
                               "boundary (not exactly one adjacent tetrahedron)")
    far = xyz[opposite[owner[tri_id]]]
    a, b, c = (xyz[tris[:, k]] for k in range(3))
    outward = np.einsum("ij,ij->i", np.cross(b - a, c - a), a - far) > 0
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
        raise MeshQualityError(f"surface {s} has triangles of mixed orientation")
    if flip:
        gmsh.model.mesh.reverse(flip)


def _orient_closed_surface(gmsh, surfaces: list[int], index: np.ndarray, xyz: np.ndarray) -> None:
    """Orient a closed surface made of several gmsh surfaces consistently and outward.

    Every edge must be shared by exactly two triangles; the entities are flipped so that the
    two triangles at each edge traverse it in opposite directions, then all together so that
    the enclosed volume (divergence theorem) is positive.
    """
    per = [_entity_elements(gmsh, 2, s, 2, 3, index)[1] for s in surfaces]
    tris = np.concatenate(per)
    ent = np.concatenate([np.full(len(t), k) for k, t in enumerate(per)])
    edges = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    eent = np.concatenate([ent, ent, ent])
    forward = edges[:, 0] < edges[:, 1]
    _, inv, counts = np.unique(np.sort(edges, axis=1), axis=0, return_inverse=True, return_counts=True)
    inv = inv.ravel()
    if np.any(counts != 2):
        raise MeshQualityError(f"the surface is not closed: {int(np.sum(counts == 1))} edges belong to one "
                               f"triangle only and {int(np.sum(counts > 2))} to more than two")
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
    a, b, c = (xyz[tris[:, k]] for k in range(3))
    volume = np.sum(signs * np.einsum("ij,ij->i", a, np.cross(b, c))) / 6.0
    if volume < 0:
        flip ^= 1
    targets = [(2, surfaces[k]) for k in range(len(surfaces)) if flip[k] == 1]
    if targets:
        gmsh.model.mesh.reverse(targets)


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
        3 for a tetrahedral volume mesh, 2 for a triangulated surface.
    closed_surface
        For ``dim == 2``: the named surfaces form one closed surface; check it (each edge in
        exactly two triangles) and orient it consistently outward.

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
    etype, nper = (4, 4) if dim == 3 else (2, 3)
    cells = []
    for t in top:
        types, _, _ = gmsh.model.mesh.getElements(dim, t)
        if set(int(x) for x in types) != {etype}:
            raise MeshQualityError(f"{dim}-D entity {t} has element types {list(types)}, expected only "
                                   f"first-order {_GMSH_TYPES[etype]}")
        cells.append(_entity_elements(gmsh, dim, t, etype, nper, index))
    etags = np.concatenate([c[0] for c in cells])
    conn = np.concatenate([c[1] for c in cells])
    size, angle, inradius = check_cells(xyz, conn, dim)

    named_surfaces = sorted({t for (gd, _), (_, ents) in groups.items() if gd == 2 for t in ents})
    if dim == 3 and named_surfaces:
        _orient_outward_from_volume(gmsh, named_surfaces, top, index, xyz)
    elif dim == 2 and closed_surface:
        _orient_closed_surface(gmsh, top, index, xyz)

    sicn = np.asarray(gmsh.model.mesh.getElementQualities(etags, "minSICN"))
    gamma = np.asarray(gmsh.model.mesh.getElementQualities(etags, "gamma"))
    if dim == 3 and sicn.min() <= 0:
        raise MeshQualityError(f"gmsh reports inverted tetrahedra (min SICN {sicn.min():.3g})")

    # count what gmsh writes: the elements of entities in physical groups (each entity once)
    elements: dict[str, int] = {}
    for gd, t in sorted(grouped):
        types, tags, _ = gmsh.model.mesh.getElements(gd, t)
        for ty, tg in zip(types, tags):
            name = _GMSH_TYPES.get(int(ty), f"gmsh type {int(ty)}")
            elements[name] = elements.get(name, 0) + len(tg)
    path.parent.mkdir(parents=True, exist_ok=True)
    gmsh.write(str(path))
    used = np.unique(conn)
    notes = []
    if angle.min() < (5.0 if dim == 3 else 10.0):
        notes.append(f"poor elements (smallest angle {angle.min():.2g} deg): a smaller element_size usually helps")
    return MeshReport(
        path=path, model=model, parameters=dict(parameters), dim=dim, nodes=int(used.size),
        elements=elements, groups={name: gd for (gd, _), (name, _) in sorted(groups.items(), key=lambda kv: (-kv[0][0], kv[0][1]))},
        min_volume=float(size.min()), max_volume=float(size.max()), total_volume=float(size.sum()),
        min_angle=float(angle.min()), min_sicn=float(sicn.min()), min_gamma=float(gamma.min()),
        min_inradius=float(inradius.min()), notes=notes,
    )


# --------------------------------------------------------------------------------------------
# finding and running models

def available_models() -> list[str]:
    """Names of the model modules in ``pdfem.models`` (those that define ``build``)."""
    import pdfem.models as pkg

    names = []
    for info in pkgutil.iter_modules(pkg.__path__):
        if info.name.startswith("_") or info.ispkg:
            continue
        try:
            mod = importlib.import_module(f"pdfem.models.{info.name}")
        except Exception:  # a broken module is not offered as a model
            continue
        if callable(getattr(mod, "build", None)):
            names.append(info.name)
    return sorted(names)


def resolve_model(name_or_path: str | Path) -> ModuleType:
    """Find a model: a bare name in ``pdfem.models``, or a path to a ``.py`` file.

    Parameters
    ----------
    name_or_path
        ``"hull_panel"`` -> ``pdfem.models.hull_panel``; ``"my/model.py"`` -> that file,
        imported under a private module name.

    Returns
    -------
    module
        The model module; it defines ``build`` (and normally ``PARAMETERS``).

    Raises
    ------
    ModelParameterError
        (``param == "model"``) an unknown name (the message lists the available names), a
        missing file, or a module without ``build``.
    """
    text = str(name_or_path)
    is_path = isinstance(name_or_path, Path) or text.endswith(".py") or "/" in text or "\\" in text
    if is_path:
        path = Path(text).expanduser()
        if not path.is_file():
            raise ModelParameterError("model", text, "no such model file")
        if path.suffix != ".py":
            raise ModelParameterError("model", text, "a model file must be a Python script (.py)")
        modname = f"pdfem_user_model_{abs(hash(str(path.resolve())))}"
        spec = importlib.util.spec_from_file_location(modname, path)
        if spec is None or spec.loader is None:
            raise ModelParameterError("model", text, "cannot be imported as a Python module")
        module = importlib.util.module_from_spec(spec)
        sys.modules[modname] = module
        try:
            spec.loader.exec_module(module)
        except Exception:
            sys.modules.pop(modname, None)
            raise
    else:
        names = available_models()
        if text not in names:
            raise ModelParameterError("model", text, "unknown model; available models are: "
                                      + ", ".join(names) + " (or give a path to a .py file)")
        module = importlib.import_module(f"pdfem.models.{text}")
    if not callable(getattr(module, "build", None)):
        raise ModelParameterError("model", text, "the model module defines no build(path, **params) function")
    return module


def mesh_model(model: str | Path, params: dict[str, Any] | None = None, out: Path | str | None = None) -> MeshReport:
    """Build a model's mesh: what ``pdfem mesh MODEL [--set key=value ...] [-o FILE]`` does.

    Parameters
    ----------
    model
        A model name in ``pdfem.models`` or a path to a ``.py`` file (see :func:`resolve_model`).
    params
        Parameter values, usually the strings from ``--set`` (see :func:`parse_set`); they are
        converted to the types of the model's ``PARAMETERS`` defaults.
    out
        Output ``.msh`` file; default ``<model>.msh`` in the current directory.

    Returns
    -------
    MeshReport

    Raises
    ------
    ModelParameterError
        Unknown model, unknown parameter (listing the valid ones), or a bad value.
    MeshQualityError
        The mesh has inverted or zero-volume elements.
    """
    module = resolve_model(model)
    raw = dict(params or {})
    parameters = getattr(module, "PARAMETERS", None)
    if parameters is not None:
        typed = coerce_parameters(parameters, raw)
    else:
        typed = raw
    stem = Path(str(model)).stem
    path = Path(out) if out is not None else Path.cwd() / f"{stem}.msh"
    return module.build(path, **typed)
