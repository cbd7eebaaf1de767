"""What a model script wrote and how good its mesh is (:class:`MeshReport`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any


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
        Dimension of the mesh's cells: 3 (tetrahedra or hexahedra, first or second order) or 2
        (a surface of triangles or quadrilaterals).
    nodes
        Number of mesh nodes (of quadratic elements: corner and mid-side nodes).
    elements
        Number of elements written, by meshio cell type (``"tetra"``, ``"triangle"``, ...).
    groups
        Physical group name -> dimension.
    min_volume, max_volume
        Smallest and largest cell volume (m^3), or area (m^2) for a surface mesh; of quadratic
        elements, the straight-sided element through their corners.
    total_volume
        Sum of the cell volumes (m^3), or areas (m^2) for a surface mesh.
    min_angle
        Smallest dihedral angle of a tetrahedron, smallest angle between two edges at a corner
        of a hexahedron (90 for a box), or smallest interior angle of a triangle or
        quadrilateral for a surface mesh (deg).
    min_sicn
        gmsh's smallest signed inverse condition number (1 ideal, <= 0 inverted).
    min_gamma
        gmsh's smallest inscribed/circumscribed radius ratio (normalised, 1 ideal) of
        tetrahedra and triangles; gmsh's smallest isotropy measure ``minIsotropy`` (1 ideal) of
        hexahedra and quadrilaterals.
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
        hexa = any(t.startswith("hexahedron") for t in self.elements)
        angle = ("corner edge angle" if hexa else "dihedral angle") if self.dim == 3 else "face angle"
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
