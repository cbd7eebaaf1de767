"""Parametric propeller: Z elastic blades of NACA 00xx sections on a rigid hub, with named groups
per blade (root, leading edge, trailing edge, tip, face, back) for loads and supports.

Geometry (SI: m, rad; the laws are in ``models/propeller_sections.py``). The shaft axis is x;
a point at radius r and angle psi around the shaft (from +z toward +y) is
(x, r sin psi, r cos psi). Blade k (k = 1..Z) has its reference line at
psi_k = 2 pi (k - 1) / Z (blade 1 along +z, as ``models/propeller_blade.py``). The leading edges
lie at larger x than the trailing edges; the propeller turns positively about +x (at the top of
the disc the blades move toward -y) with the leading edge ahead, and its face (pressure side)
looks aft (-x), its back (suction side) forward (+x).

* Chord from the expanded area ratio: ``EAR = Z int_{r_h}^{R} c(r) dr / (pi R^2)`` with the
  elliptic-type chord shape of ``propeller_blade`` (largest chord at ``max_chord_radius``, tip
  chord ``tip_chord_ratio`` x the largest).
* Thickness: thickness/chord ratio linear in r from ``root_thickness_ratio`` to
  ``tip_thickness_ratio``; symmetric NACA 00xx sections opened to a blunt trailing edge
  ``trailing_edge_ratio`` x the thickness (no sliver tetrahedra at a sharp edge).
* Constant pitch P = ``pitch_ratio`` x D; skew (skew-back > 0) and rake (aft > 0) linear in r,
  zero at the hub.
* Hub: rigid (not meshed); each blade's root face lies on the hub cylinder r = r_h and is the
  group that is held fixed in the rotating frame.

Named groups (a contract with the shaft and blade outputs): volumes ``blade1``..``bladeZ``;
surfaces ``blade{k}_root`` (on the hub cylinder), ``blade{k}_tip`` (on the cylinder r = R),
``blade{k}_leading_edge`` and ``blade{k}_trailing_edge`` (the strips within ``edge_fraction``
of the chord from each edge, both sides), ``blade{k}_face`` (the pressure side between the
strips, facing -x), ``blade{k}_back`` (suction side, +x), ``blade{k}_surface`` (all of blade k's
faces but the root); ``root`` (all roots) and ``contact`` (all blade faces but the roots). The
strips come from splitting each section at the chordwise fractions ``edge_fraction`` and
1 - ``edge_fraction`` before lofting, so every group is a set of CAD surfaces.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from pdfem.meshing import (MeshReport, check_parameters, finish_mesh, generate_mesh, gmsh_session, require,
                           require_element_budget, require_positive, require_range, set_mesh_size)
from pdfem.models import propeller_sections as sec
from pdfem.models.propeller_blade import _second_order

#: name -> (default, unit, description)
PARAMETERS: dict[str, tuple] = {
    "blades": (4, "-", "number of blades Z"),
    "diameter": (2.0, "m", "propeller diameter D = 2 R"),
    "hub_diameter": (0.6, "m", "hub diameter d (the blade roots lie on the hub cylinder)"),
    "pitch_ratio": (0.7, "-", "pitch ratio P/D (constant pitch)"),
    "ear": (0.5, "-", "expanded area ratio Z int c dr / (pi R^2), sets the chord"),
    "max_chord_radius": (0.65, "m", "radius of the largest chord"),
    "tip_chord_ratio": (0.5, "-", "tip chord / largest chord"),
    "root_thickness_ratio": (0.2, "-", "thickness/chord at the hub (linear in r to the tip)"),
    "tip_thickness_ratio": (0.08, "-", "thickness/chord at the tip"),
    "trailing_edge_ratio": (0.25, "-", "trailing-edge thickness / maximum section thickness (a blunt edge)"),
    "skew_angle": (0.35, "rad", "skew at the tip (skew-back > 0), linear in r from 0 at the hub"),
    "rake_angle": (0.0, "rad", "rake angle (aft > 0): mid-chord line moved by -(r - r_h) tan(rake) along x"),
    "edge_fraction": (0.1, "-", "chord fraction of the leading- and trailing-edge strips"),
    "sections": (16, "-", "number of sections lofted from hub to tip"),
    "element_size": (0.04, "m", "target edge length of the tetrahedra"),
    "element_order": (2, "-", "2: 10-node tetrahedra (default), 1: 4-node tetrahedra"),
}

SIDES = ("root", "leading_edge", "trailing_edge", "tip", "face", "back")
"""The surface groups of each blade (``blade{k}_<side>``)."""


def blade_angle(k: int, blades: int) -> float:
    """Angle psi_k = 2 pi (k - 1) / Z (rad) of blade k's reference line, from +z toward +y."""
    return 2.0 * math.pi * (k - 1) / blades


def _check(p: dict) -> np.ndarray:
    require_positive(p, "diameter", "hub_diameter", "pitch_ratio", "ear", "tip_chord_ratio",
                     "root_thickness_ratio", "tip_thickness_ratio", "element_size")
    R, rh = p["diameter"] / 2, p["hub_diameter"] / 2
    require_range(p, "blades", 2, 8)
    require(rh < 0.8 * R, "hub_diameter", p["hub_diameter"], f"must be less than 0.8 x the diameter ({p['diameter']:g} m)")
    require(rh <= p["max_chord_radius"] < R, "max_chord_radius", p["max_chord_radius"],
            f"must be in [hub_diameter / 2, diameter / 2) = [{rh:g}, {R:g}) m")
    require_range(p, "tip_chord_ratio", 0.05, 1.0)
    require_range(p, "root_thickness_ratio", 0.02, 0.4)
    require_range(p, "tip_thickness_ratio", 0.02, 0.4)
    require_range(p, "skew_angle", -1.0, 1.0, unit="rad")
    require_range(p, "rake_angle", -0.5, 0.5, unit="rad")
    require_range(p, "edge_fraction", 0.02, 0.3)
    require_range(p, "trailing_edge_ratio", 0.05, 0.6)
    require_range(p, "sections", 4, 40)
    require_range(p, "element_order", 1, 2)
    radii = np.linspace(rh, R, p["sections"])
    c = sec.chord(radii, p)
    phi = np.arctan(p["pitch_ratio"] * p["diameter"] / (2 * np.pi * radii))
    span = (c * np.cos(phi) + sec.thickness(radii, p) * np.sin(phi)) / radii
    require(np.all(span < 0.9 * 2 * np.pi / p["blades"]), "ear", p["ear"],
            f"makes neighbouring blades overlap (a section wraps {np.degrees(span.max()):.0f} deg around "
            f"the shaft, more than 0.9 x 360/Z deg); lower the ear or move max_chord_radius outward")
    require(c[0] > 0.05 * c.max(), "max_chord_radius", p["max_chord_radius"],
            "the chord law leaves almost no chord at the hub: move max_chord_radius toward the hub")
    h = p["element_size"]
    require(h <= 0.5 * (R - rh), "element_size", h, f"must be at most half the span ({0.5 * (R - rh):g} m)")
    require_element_budget(2 * p["blades"] * np.sum(0.5 * (c[1:] + c[:-1]) * np.diff(radii)), h, "this propeller")
    return radii


def _blade_solid(occ, p: dict, radii: np.ndarray, psi0: float) -> int:
    """The OCC volume of one blade at psi0, cut to the shell r_h <= r <= R."""
    R, rh = p["diameter"] / 2, p["hub_diameter"] / 2
    ext = 0.02 * (R - rh)
    stations = [(rh - ext, rh)] + [(float(r), float(r)) for r in radii] + [(R + ext, R)]
    wires = []
    for r, r_law in stations:
        pts, breaks = sec.section_points(r, r_law, p, psi0)
        tags = [occ.addPoint(*xyz) for xyz in pts]
        tags.append(tags[0])
        ends = breaks + [len(pts)]
        wires.append(occ.addWire([occ.addSpline(tags[a:b + 1]) if b > a + 1 else occ.addLine(tags[a], tags[b])
                                  for a, b in zip(ends[:-1], ends[1:])]))
    lateral = occ.addThruSections(wires, makeSolid=False, makeRuled=False)
    caps = [occ.addSurfaceFilling(wires[0]), occ.addSurfaceFilling(wires[-1])]
    loose = [(2, t) for _, t in lateral] + [(2, t) for t in caps]
    loft = occ.addVolume([occ.addSurfaceLoop([t for _, t in loose], sewing=True)])
    reach = 2.0 * (R + sec.max_chord(p))
    outer = occ.addCylinder(-reach, 0, 0, 2 * reach, 0, 0, R)
    inner = occ.addCylinder(-reach, 0, 0, 2 * reach, 0, 0, rh)
    tube, _ = occ.cut([(3, outer)], [(3, inner)])
    occ.rotate(tube, 0, 0, 0, 1, 0, 0, -(psi0 + math.pi))      # cylinder seams opposite the blade
    blade, _ = occ.intersect([(3, loft)], tube)
    occ.remove(loose, recursive=True)
    volumes = [t for d, t in blade if d == 3]
    if len(volumes) != 1:
        raise RuntimeError(f"the loft of the blade at psi = {psi0:.3f} rad did not give one solid ({volumes})")
    return volumes[0]


def _classify(gmsh, p: dict, volume: int, psi0: float) -> dict[str, list[int]]:
    """The blade's CAD surfaces by side: on the hub cylinder (root), on r = R (tip), else by
    the chordwise fraction and side of the mean of their mesh nodes."""
    R, rh = p["diameter"] / 2, p["hub_diameter"] / 2
    out: dict[str, list[int]] = {side: [] for side in SIDES}
    _, surfaces = gmsh.model.getAdjacencies(3, volume)
    for s in surfaces:
        _, xyz, _ = gmsh.model.mesh.getNodes(2, int(s), includeBoundary=True, returnParametricCoord=False)
        xyz = np.asarray(xyz).reshape(-1, 3)
        radial = np.hypot(xyz[:, 1], xyz[:, 2])
        if np.max(np.abs(radial - rh)) < 1e-6 * R:
            out["root"].append(int(s))
        elif np.max(np.abs(radial - R)) < 1e-6 * R:
            out["tip"].append(int(s))
        else:
            b, eta = sec.chordwise(xyz, p, psi0)
            b, eta = float(np.mean(b)), float(np.mean(eta))
            side = ("leading_edge" if b < p["edge_fraction"] else "trailing_edge" if b > 1 - p["edge_fraction"]
                    else "back" if eta > 0 else "face")
            out[side].append(int(s))
    for side in SIDES:
        if not out[side]:
            raise RuntimeError(f"the blade at psi = {psi0:.3f} rad has no '{side}' surface")
    return out


def build(path: str | Path, **params) -> MeshReport:
    """Mesh the propeller's blades and write them as MSH 4.1.

    Parameters
    ----------
    path
        Output ``.msh`` file.
    **params
        See ``PARAMETERS`` (name, default, unit, meaning): blades Z (2..8), diameter D (m),
        hub_diameter d (m), pitch_ratio P/D, ear (expanded area ratio), max_chord_radius (m),
        tip_chord_ratio, root_thickness_ratio and tip_thickness_ratio (t/c), skew_angle and
        rake_angle (rad), edge_fraction, sections, element_size (m), element_order (1 or 2).

    Returns
    -------
    MeshReport
        With the volume groups ``blade1``..``bladeZ`` and the surface groups
        ``blade{k}_<side>`` (``SIDES``), ``blade{k}_surface``, ``root`` and ``contact``.

    Raises
    ------
    ModelParameterError
        A bad or inconsistent parameter (named).
    MeshQualityError
        Inverted or zero-volume tetrahedra.
    """
    p = check_parameters(PARAMETERS, params)
    radii = _check(p)
    Z = p["blades"]
    with gmsh_session("propeller") as gmsh:
        occ = gmsh.model.occ
        volumes = [_blade_solid(occ, p, radii, blade_angle(k, Z)) for k in range(1, Z + 1)]
        occ.synchronize()
        h = p["element_size"]
        set_mesh_size(h, min_size=0.5 * h, curvature=12)
        gmsh.option.setNumber("Mesh.Algorithm3D", 10)
        gmsh.option.setNumber("Mesh.Optimize", 1)
        generate_mesh(3)
        sides = [_classify(gmsh, p, v, blade_angle(k, Z)) for k, v in enumerate(volumes, start=1)]
        straight = p["element_order"] == 2 and _second_order(gmsh)
        roots, contact = [], []
        for k, (v, groups) in enumerate(zip(volumes, sides), start=1):
            gmsh.model.addPhysicalGroup(3, [v], name=f"blade{k}")
            for side in SIDES:
                gmsh.model.addPhysicalGroup(2, groups[side], name=f"blade{k}_{side}")
            surface = [s for side in SIDES[1:] for s in groups[side]]
            gmsh.model.addPhysicalGroup(2, surface, name=f"blade{k}_surface")
            roots += groups["root"]
            contact += surface
        gmsh.model.addPhysicalGroup(2, contact, name="contact")
        gmsh.model.addPhysicalGroup(2, roots, name="root")
        report = finish_mesh(path, "propeller", p, dim=3)
    if straight:
        report.notes.append("some curved 10-node tetrahedra were inverted at the thin edges: all mid-side "
                            "nodes were put on the straight edges instead (the faceted first-order shape)")
    rh = p["hub_diameter"] / 2
    report.notes.append(f"largest chord {sec.max_chord(p):.4g} m (EAR {p['ear']:g}); blade volume "
                        f"{sec.blade_volume(p):.4g} m^3 (section-area integral); pitch angle "
                        f"{math.degrees(math.atan(p['pitch_ratio'] * p['diameter'] / (2 * math.pi * rh))):.1f} deg "
                        f"at the hub, {math.degrees(math.atan(p['pitch_ratio'] / math.pi)):.1f} deg at the tip")
    return report
