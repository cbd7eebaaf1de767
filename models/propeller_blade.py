"""Parametric propeller blade: NACA 00xx sections lofted from the hub to the tip.

Geometry (SI: m, rad). The shaft axis is x; the blade's reference line is the +z axis. A
point at radius r and angle psi around the shaft is (x, r sin psi, r cos psi).

* Chord, elliptic-type law with its maximum ``max_chord`` at ``max_chord_radius`` = r_m and
  ``tip_chord`` at the tip radius R:
  ``c(r) = max_chord * sqrt(1 - s^2 (1 - q^2))``, ``s = (r - r_m) / (R - r_m)``,
  ``q = tip_chord / max_chord`` (so c(r_m) = max_chord, c(R) = tip_chord).
* Maximum thickness, linear from ``root_thickness`` at the hub radius r_h to
  ``tip_thickness`` at R. The section is a symmetric NACA 4-digit profile with thickness
  ratio t(r)/c(r) (any ratio, not only whole percents) and a closed trailing edge (last
  coefficient -0.1036); its area is 0.68088 c t (0.685 c t for the open-edge profile).
* Constant geometric pitch ``pitch`` = P: the chord line makes the pitch angle
  phi(r) = atan(P / (2 pi r)) with the plane of rotation (y-z). The leading edge lies at larger
  x than the trailing edge; the suction side (back) faces +x, the pressure side (face) -x.
* Skew: the mid-chord point of the section at r sits at psi = skew(r) =
  ``skew_angle`` * (r - r_h) / (R - r_h) (linear, 0 at the hub, ``skew_angle`` at the tip).
  Seen at the top of the disc (+z), the blade turns toward -y (a positive rotation about +x)
  with its leading edge ahead; positive skew moves sections back (toward +y), i.e. skew-back.
* No rake. Each section is wrapped onto its cylinder r = const (helicoidal sections, the
  usual propeller-drawing convention), so the root face lies on the hub cylinder r = r_h and
  has exactly the NACA section area, and the tip face lies on the cylinder r = R.

``sections`` sections at equally spaced radii from r_h to R are lofted (OCC ThruSections,
smooth), with one extra section just inside the hub and one just outside the tip; the loft is
then cut by the cylinders r = r_h and r = R. Physical groups: ``blade`` (3-D), ``root`` (2-D,
the face on the hub cylinder; fix it), ``contact`` (2-D, every other face: suction and pressure
sides with the leading and trailing edges, and the tip). Hexahedra do not fit a thin twisted
loft, so the blade is meshed with tetrahedra, by default second-order (``element_order = 2``:
gmsh's 10-node tetrahedra with 6-node triangle faces, mid-side nodes on the curved surfaces),
which bend correctly with one or two elements through the thickness where first-order
tetrahedra lock; ``element_order = 1`` gives first-order tetrahedra.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from pdfem.meshing import (MeshReport, check_parameters, finish_mesh, generate_mesh, gmsh_session, require,
                           require_element_budget, require_positive, require_range, set_mesh_size)

#: name -> (default, unit, description)
PARAMETERS: dict[str, tuple] = {
    "radius": (1.0, "m", "tip radius R"),
    "hub_radius": (0.3, "m", "hub radius r_h (the blade root)"),
    "pitch": (1.4, "m", "geometric pitch P (constant); pitch angle atan(P / (2 pi r))"),
    "max_chord": (0.5, "m", "largest chord length"),
    "max_chord_radius": (0.6, "m", "radius of the largest chord"),
    "tip_chord": (0.15, "m", "chord length at the tip"),
    "root_thickness": (0.07, "m", "maximum section thickness at the hub radius"),
    "tip_thickness": (0.015, "m", "maximum section thickness at the tip"),
    "skew_angle": (0.35, "rad", "skew angle at the tip (skew-back > 0), linear in radius from 0 at the hub"),
    "sections": (10, "-", "number of NACA sections lofted from hub to tip"),
    "element_size": (0.02, "m", "target edge length of the tetrahedra"),
    "element_order": (2, "-", "2: 10-node tetrahedra (default), 1: 4-node tetrahedra"),
}

_POINTS_PER_SIDE = 31           # cosine-spaced profile points on each side, LE and TE included
_CLOSED_TE = (0.2969, -0.1260, -0.3516, 0.2843, -0.1036)
#: area of a NACA 00xx section with the closed trailing edge, in units of chord * thickness
NACA_AREA_FACTOR = 10.0 * (_CLOSED_TE[0] * 2 / 3 + _CLOSED_TE[1] / 2 + _CLOSED_TE[2] / 3
                           + _CLOSED_TE[3] / 4 + _CLOSED_TE[4] / 5)


def chord_at(r: float | np.ndarray, **params) -> float | np.ndarray:
    """Chord length c(r) (m) at radius r (m) for the given parameters (defaults otherwise)."""
    p = check_parameters(PARAMETERS, params)
    return _chord(np.asarray(r, dtype=float), p)


def thickness_at(r: float | np.ndarray, **params) -> float | np.ndarray:
    """Maximum section thickness t(r) (m) at radius r (m) for the given parameters."""
    p = check_parameters(PARAMETERS, params)
    return _thickness(np.asarray(r, dtype=float), p)


def _chord(r, p):
    s = (r - p["max_chord_radius"]) / (p["radius"] - p["max_chord_radius"])
    q = p["tip_chord"] / p["max_chord"]
    return p["max_chord"] * np.sqrt(np.maximum(1.0 - s * s * (1.0 - q * q), 0.0))


def _thickness(r, p):
    f = (r - p["hub_radius"]) / (p["radius"] - p["hub_radius"])
    return p["root_thickness"] + f * (p["tip_thickness"] - p["root_thickness"])


def _check(p: dict) -> np.ndarray:
    require_positive(p, "radius", "hub_radius", "pitch", "max_chord", "tip_chord", "root_thickness",
                     "tip_thickness", "element_size")
    R, rh = p["radius"], p["hub_radius"]
    require(rh < R, "hub_radius", rh, f"must be less than the tip radius ({R:g} m)")
    require(rh <= p["max_chord_radius"] < R, "max_chord_radius", p["max_chord_radius"],
            f"must be in [hub_radius, radius) = [{rh:g}, {R:g}) m")
    require(p["tip_chord"] <= p["max_chord"], "tip_chord", p["tip_chord"],
            f"must not exceed max_chord ({p['max_chord']:g} m)")
    require_range(p, "skew_angle", -1.0, 1.0, unit="rad")
    require_range(p, "sections", 4, 40)
    require_range(p, "element_order", 1, 2)
    radii = np.linspace(rh, R, p["sections"])
    c, t = _chord(radii, p), _thickness(radii, p)
    require(c[0] > 0.05 * p["max_chord"], "max_chord_radius", p["max_chord_radius"],
            f"the elliptic chord law leaves almost no chord at the hub ({c[0]:.3g} m): "
            "move max_chord_radius toward the hub or raise tip_chord")
    ratio = t / c
    for k, name in ((0, "root_thickness"), (-1, "tip_thickness")):
        require(0.02 <= ratio[k] <= 0.4, name, p[name],
                f"gives thickness/chord {ratio[k]:.3g} at r = {radii[k]:g} m; NACA 00xx sections need 0.02..0.4")
    require(np.all((ratio >= 0.02) & (ratio <= 0.4)), "root_thickness", p["root_thickness"],
            f"thickness/chord leaves 0.02..0.4 between hub and tip (range {ratio.min():.3g}..{ratio.max():.3g})")
    phi = np.arctan(p["pitch"] / (2 * np.pi * radii))
    span = c * np.cos(phi) / radii                     # angle the chord wraps around the shaft
    require(np.all(span < 0.5 * np.pi), "max_chord", p["max_chord"],
            "the sections wrap more than a quarter turn around the shaft; shorten the chords")
    h = p["element_size"]
    require(h <= 0.5 * (R - rh), "element_size", h, f"must be at most half the span ({0.5 * (R - rh):g} m)")
    require_element_budget(2 * np.sum(0.5 * (c[1:] + c[:-1]) * np.diff(radii)), h, "this blade")
    return radii


def _profile(ratio: float) -> tuple[np.ndarray, np.ndarray]:
    """Closed NACA 00xx loop (chord 1): TE, upper side, LE, lower side, back to TE (not repeated)."""
    b = 0.5 * (1 - np.cos(np.linspace(0.0, np.pi, _POINTS_PER_SIDE)))
    a0, a1, a2, a3, a4 = _CLOSED_TE
    y = 5 * ratio * (a0 * np.sqrt(b) + a1 * b + a2 * b**2 + a3 * b**3 + a4 * b**4)
    y[-1] = 0.0
    xi = np.concatenate([b[::-1], b[1:-1]])
    eta = np.concatenate([y[::-1], -y[1:-1]])
    return xi, eta


def _section_points(r: float, p: dict, r_law: float) -> np.ndarray:
    """Profile points of the helicoidal section on the cylinder of radius r (laws taken at r_law)."""
    c = float(_chord(np.asarray(r_law), p))
    t = float(_thickness(np.asarray(r_law), p))
    xi, eta = _profile(t / c)
    xi = (xi - 0.5) * c                                  # from mid-chord; LE at -c/2
    eta = eta * c
    phi = math.atan(p["pitch"] / (2 * math.pi * r))
    s = xi * math.cos(phi) + eta * math.sin(phi)         # circumferential (toward +y at the top)
    x = -xi * math.sin(phi) + eta * math.cos(phi)        # axial: LE forward, suction side +x
    skew = p["skew_angle"] * (r_law - p["hub_radius"]) / (p["radius"] - p["hub_radius"])
    psi = s / r + skew
    return np.column_stack([x, r * np.sin(psi), r * np.cos(psi)])


def section_area(r: float, **params) -> float:
    """Analytic area (m^2) of the blade section at radius r: NACA_AREA_FACTOR * c(r) * t(r)."""
    p = check_parameters(PARAMETERS, params)
    return float(NACA_AREA_FACTOR * _chord(np.asarray(r, float), p) * _thickness(np.asarray(r, float), p))


def build(path: str | Path, **params) -> MeshReport:
    """Mesh one propeller blade and write it as MSH 4.1.

    Parameters
    ----------
    path
        Output ``.msh`` file.
    radius : float, default 1.0
        Tip radius R, m.
    hub_radius : float, default 0.3
        Hub radius r_h, m (< R).
    pitch : float, default 1.4
        Geometric pitch P, m (pitch angle atan(P / (2 pi r))).
    max_chord : float, default 0.5
        Largest chord, m.
    max_chord_radius : float, default 0.6
        Radius of the largest chord, m, in [r_h, R).
    tip_chord : float, default 0.15
        Chord at the tip, m (<= max_chord).
    root_thickness : float, default 0.07
        Maximum section thickness at the hub, m.
    tip_thickness : float, default 0.015
        Maximum section thickness at the tip, m.
    skew_angle : float, default 0.35
        Skew at the tip, rad (0.35 rad = 20 deg; skew-back > 0), in [-1, 1].
    sections : int, default 10
        Number of lofted sections, 4..40.
    element_size : float, default 0.02
        Target tetrahedron edge length, m.
    element_order : int, default 2
        2: second-order (10-node) tetrahedra with 6-node triangle faces; 1: first-order.

    Returns
    -------
    MeshReport
        With physical groups ``blade`` (3-D), ``root`` (2-D) and ``contact`` (2-D).

    Raises
    ------
    ModelParameterError
        A bad or inconsistent parameter (named).
    MeshQualityError
        Inverted or zero-volume tetrahedra.
    """
    p = check_parameters(PARAMETERS, params)
    radii = _check(p)
    R, rh = p["radius"], p["hub_radius"]
    ext = 0.02 * (R - rh)
    stations = [(rh - ext, rh)] + [(float(r), float(r)) for r in radii] + [(R + ext, R)]
    with gmsh_session("propeller_blade") as gmsh:
        occ = gmsh.model.occ
        wires = []
        for r, r_law in stations:
            pts = _section_points(r, p, r_law)
            tags = [occ.addPoint(*xyz) for xyz in pts]
            lead = _POINTS_PER_SIDE - 1
            upper = occ.addSpline(tags[:lead + 1])
            lower = occ.addSpline(tags[lead:] + tags[:1])
            wires.append(occ.addWire([upper, lower]))
        lateral = occ.addThruSections(wires, makeSolid=False, makeRuled=False)
        caps = [occ.addSurfaceFilling(wires[0]), occ.addSurfaceFilling(wires[-1])]
        loose = [(2, t) for _, t in lateral] + [(2, t) for t in caps]
        loft = occ.addVolume([occ.addSurfaceLoop([t for _, t in loose], sewing=True)])
        reach = 2.0 * (R + p["max_chord"])
        outer = occ.addCylinder(-reach, 0, 0, 2 * reach, 0, 0, R)
        inner = occ.addCylinder(-reach, 0, 0, 2 * reach, 0, 0, rh)
        tube, _ = occ.cut([(3, outer)], [(3, inner)])
        occ.rotate(tube, 0, 0, 0, 1, 0, 0, math.pi)      # cylinder seams to -z, away from the blade
        blade, _ = occ.intersect([(3, loft)], tube)
        occ.remove(loose, recursive=True)
        occ.synchronize()
        volumes = [t for d, t in gmsh.model.getEntities(3)]
        if len(volumes) != 1 or [t for d, t in blade if d == 3] != volumes:
            raise RuntimeError(f"the blade loft did not give one solid (got volumes {volumes})")

        h = p["element_size"]
        # refine toward the leading edge by curvature, but not below h / 2: the explicit
        # solver's stable step scales with the smallest element (h / 4 halves the smallest
        # inscribed radius for a 0.1 % better volume)
        set_mesh_size(h, min_size=0.5 * h, curvature=12)
        gmsh.option.setNumber("Mesh.Algorithm3D", 10)
        gmsh.option.setNumber("Mesh.Optimize", 1)
        generate_mesh(3)

        # the root is the face whose (first-order) mesh nodes all lie on the hub cylinder
        root, contact = [], []
        for _, s in gmsh.model.getEntities(2):
            _, xyz, _ = gmsh.model.mesh.getNodes(2, s, includeBoundary=True, returnParametricCoord=False)
            xyz = np.asarray(xyz).reshape(-1, 3)
            radial = np.hypot(xyz[:, 1], xyz[:, 2])
            (root if np.max(np.abs(radial - rh)) < 1e-6 * R else contact).append(s)
        if not root:
            raise RuntimeError("no blade face lies on the hub cylinder")
        straight = p["element_order"] == 2 and _second_order(gmsh)
        gmsh.model.addPhysicalGroup(3, volumes, name="blade")
        gmsh.model.addPhysicalGroup(2, contact, name="contact")
        gmsh.model.addPhysicalGroup(2, root, name="root")
        report = finish_mesh(path, "propeller_blade", p, dim=3)
    if straight:
        report.notes.append("some curved 10-node tetrahedra were inverted at the thin edges: all mid-side "
                            "nodes were put on the straight edges instead (the faceted first-order shape)")
    phi_h, phi_t = (math.degrees(math.atan(p["pitch"] / (2 * math.pi * r))) for r in (rh, R))
    report.notes.append(f"chord {float(_chord(np.asarray(rh), p)):.3g} m at the hub, {p['tip_chord']:.3g} m at "
                        f"the tip; pitch angle {phi_h:.1f} deg at the hub, {phi_t:.1f} deg at the tip")
    return report


def _second_order(gmsh) -> bool:
    """Raise the open session's tetrahedra to second order, mid-side nodes on the curved
    geometry (gmsh's high-order optimiser untangles what it can). If some curved elements stay
    inverted (thin trailing edges), put all mid-side nodes on the straight edges instead: valid
    wherever the first-order mesh is. Returns True in that case."""
    gmsh.option.setNumber("Mesh.HighOrderOptimize", 2)
    gmsh.model.mesh.setOrder(2)
    tags = np.concatenate([np.asarray(t) for t in gmsh.model.mesh.getElements(3)[1]])
    if np.min(gmsh.model.mesh.getElementQualities(tags, "minSICN")) > 0:
        return False
    gmsh.model.mesh.setOrder(1)
    gmsh.option.setNumber("Mesh.SecondOrderLinear", 1)
    gmsh.option.setNumber("Mesh.HighOrderOptimize", 0)
    gmsh.model.mesh.setOrder(2)
    return True
