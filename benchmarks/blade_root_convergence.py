"""Blade root stress of the milling propeller against mesh refinement, first- and second-order
tetrahedra (the element-order choice of models/propeller_ice_milling.toml, and the definition
of its reported root stress).

The propeller of the milling case (models/propeller.py: D = 2 m, hub 0.6 m, Z = 4, P/D = 0.7,
EAR = 0.5, Ni-Al bronze), its blade roots clamped, under a static load that stands for a blade
passage: the centrifugal load of the steady spin at 300 rpm on every blade (the lumped masses at
``m w^2 r``, radial) plus a uniform pressure ``--pressure`` (Pa) on the back of blade 1
(``blade1_back``). Linear statics, ``K u = f`` (:func:`pdfem.fem.static.static_displacement`;
without the stress stiffening and spin softening of the rotating frame, which are the same
for every mesh). Reported per mesh (blade 1), for the two loads (spin and pressure; pressure
alone):

* ``tip_deflection``: the largest displacement (m);
* ``r<r>``: the largest von Mises stress (Pa) of the FE field on the cylinder of radius ``r``
  (``--radii``) through blade 1, over the points inside every mesh;
* ``monitor``: the von Mises stress (Pa) that the milling case's ``[[monitor]]`` at
  (0, 0, 0.33) m reads (the element whose centre is nearest, 3 cm from the clamped edge);
* ``nominal_tension``, ``nominal_compression``, ``nominal_axial``: the nominal root stress
  (Pa) of the cantilever-beam method (:mod:`pdfem.fem.section_stress`): the resultants of the
  supports' reactions at ``blade1_root`` over the root section's area and second moments,
  largest and smallest over the section and the axial part ``F / A``; with the section's
  ``section_area`` (m^2) and principal second moments ``section_inertia`` (m^4);
* ``hot_spot_<a>_<b>``: a structural hot-spot stress by surface extrapolation (IIW's read-out
  points ``a t`` and ``b t`` from the junction, ``t`` the root section's thickness, 65.6 mm):
  the radial normal stress of the FE field at ``r_h + a t`` and ``r_h + b t``, extrapolated
  linearly to ``r_h`` point by point on the grid of ``section_points``, the largest over the
  points inside every mesh.

A result is converged when two meshes, one refined 2x, agree within 5 %.

Run::

    python benchmarks/blade_root_convergence.py --sizes 0.2 0.1 0.05 --orders 2 [--json F]

SI units: m, Pa, N m.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np
import skfem

from pdfem.fem.elasticity import ElasticMaterial
from pdfem.fem.probe import make_probe, probe_values
from pdfem.fem.section_stress import (principal_axes, resultants, section_axes, section_of,
                                      stress_range)
from pdfem.fem.static import static_displacement
from pdfem.fem.stress import hooke_stress, von_mises
from pdfem.fem.structure import ElasticStructure
from pdfem.meshing import check_parameters
from pdfem.models import propeller
from pdfem.models import propeller_sections as sections

PARAMS = dict(blades=4, diameter=2.0, hub_diameter=0.6, pitch_ratio=0.7, ear=0.5, sections=10)
BRONZE = ElasticMaterial(density=7600.0, youngs_modulus=120e9, poisson_ratio=0.32)
OMEGA = 2.0 * np.pi * 5.0          # rad/s: 300 rpm about +x
MONITOR = (0.0, 0.0, 0.33)         # m: the milling case's [[monitor]] point
HOT_SPOT = ((0.4, 1.0), (0.5, 1.5))  # IIW read-out distances / t: fine and coarse meshes
BLADE1_AXES = section_axes((0.0, 0.0, 1.0), (0.0, -1.0, 0.0))  # spindle +z, e_t = x × e_r = -y


def section_points(radius: float, n: int = 41) -> np.ndarray:
    """(P, 3) points (m) of the cylinder ``y^2 + z^2 = radius^2`` about the shaft, on a grid
    over x in [-0.35, 0.35] m and the angle from +z in [-0.9, 0.9] rad: they cut blade 1
    (its reference line is +z) at that radius; most lie outside it."""
    x, phi = np.meshgrid(np.linspace(-0.35, 0.35, n), np.linspace(-0.9, 0.9, 3 * n))
    return np.column_stack([x.ravel(), -radius * np.sin(phi.ravel()),
                            radius * np.cos(phi.ravel())])


def point_stress(structure: ElasticStructure, points: np.ndarray) -> np.ndarray:
    """(P, 3, 3) stress (Pa) of the FE field at ``points`` (NaN outside the mesh): from the
    displacement gradient of the element holding each point, at the point."""
    mesh = structure.mesh.mesh
    corners = skfem.MeshTet(mesh.p, mesh.t[:4])    # straight-sided: to find and place points
    finder = corners.element_finder()
    elements = np.array([_find(finder, p) for p in points])
    out = np.full((len(points), 3, 3), np.nan)
    mapping = corners._mapping()
    for k in np.flatnonzero(elements >= 0):
        e = elements[k]
        X = mapping.invF(points[k][:, None, None], tind=np.array([e]))[:, 0, :]
        b = skfem.Basis(mesh, structure.basis.elem, quadrature=(X, np.ones(1)),
                        elements=np.array([e]))
        g = b.interpolate(structure.solver.u).grad[:, :, 0, 0]
        out[k] = hooke_stress(g, structure.material)
    return out


def radial_stress(sigma: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(P,) normal stress (Pa) along the radial direction from the shaft (x) axis."""
    e = points.copy()
    e[:, 0] = 0.0
    e /= np.linalg.norm(e, axis=1)[:, None]
    return np.einsum("pi,pij,pj->p", e, sigma, e)


def _find(finder, p: np.ndarray) -> int:
    """The element holding ``p``, -1 if none."""
    try:
        return int(finder(*p[:, None])[0])
    except ValueError:
        return -1


def blade_model(size: float, order: int, pressure: float,
                workdir: Path) -> tuple[ElasticStructure, np.ndarray, np.ndarray]:
    """The clamped propeller of the milling case meshed at ``size`` (m) with tetrahedra of
    ``order``, with its two loads (N, DOF vectors): the centrifugal load of 300 rpm (lumped
    masses at ``m w^2 r``, radial from the x axis) and ``pressure`` (Pa) on blade 1's back."""
    msh = workdir / f"propeller_{size:g}_{order}.msh"
    propeller.build(msh, element_size=size, element_order=order, **PARAMS)
    s = ElasticStructure.from_file(msh, BRONZE, fixed_groups=["root"], element_order=order,
                                   contact_group="contact")
    mass = s.dofmap.to_nodal(s.solver.m)[:, 0]
    radial = s.node_points.copy()
    radial[:, 0] = 0.0                                     # r_perp from the x axis
    f_spin = s.dofmap.to_dofs(mass[:, None] * OMEGA ** 2 * radial)
    s.add_surface_load("blade1_back", pressure=pressure)
    return s, f_spin, s.external_force_dofs(0.0)


def root_nominal_stress(s: ElasticStructure, u: np.ndarray, f: np.ndarray) -> dict:
    """Blade 1's nominal root stress (Pa) under the static displacement ``u`` ((Nn, 3), m) of
    the load ``f`` (DOFs, N): the supports' reactions ``K u - f`` at ``blade1_root``."""
    section = section_of(s.node_points, s.space.face_triangles(s.mesh.group_facets("blade1_root")),
                         BLADE1_AXES)
    nodes = s.group_nodes("blade1_root")
    reaction = s.dofmap.to_nodal(s.K @ s.dofmap.to_dofs(u) - f)[nodes]
    force, moment = resultants(section, s.node_points[nodes], reaction)
    tension, compression, axial = stress_range(section, force, moment)
    return {"nominal_tension": tension, "nominal_compression": compression,
            "nominal_axial": axial, "root_force": force.tolist(),
            "root_moment": moment.tolist(), "section_area": section.area,
            "section_inertia": principal_axes(section)[0].tolist()}


def root_stress(size: float, order: int, pressure: float, radii: tuple[float, ...],
                workdir: Path) -> dict:
    """Mesh, solve and measure one propeller (see the module docstring)."""
    t0 = time.perf_counter()
    s, f_spin, f_ice = blade_model(size, order, pressure, workdir)
    out = {"element_size": size, "order": order, "nodes": s.n_nodes, "elements": s.cells.shape[0]}
    rh = PARAMS["hub_diameter"] / 2
    t_root = float(sections.thickness(rh, check_parameters(propeller.PARAMETERS, PARAMS)))
    hot = sorted({a * t_root for pair in HOT_SPOT for a in pair})
    probe = make_probe(s, MONITOR)
    for label, f in (("spin_and_pressure", f_spin + f_ice), ("pressure", f_ice)):
        u = static_displacement(s, f)
        s.set_state(u)
        for r in radii:
            sigma = point_stress(s, section_points(r))
            out[f"{label}_r{r:g}"] = von_mises(sigma)      # NaN where a point is outside
        for d in hot:
            pts = section_points(rh + d)
            out[f"{label}_radial_{d:.6f}"] = radial_stress(point_stress(s, pts), pts)
        out[f"{label}_tip_deflection"] = float(np.abs(u).max())
        out[f"{label}_monitor"] = probe_values(s, probe)[1]
        out.update({f"{label}_{k}": v for k, v in root_nominal_stress(s, u, f).items()})
    out["root_thickness"] = t_root
    out["seconds"] = time.perf_counter() - t0
    return out


def _largest_inside(values: list[np.ndarray]) -> list[float]:
    """The largest of each mesh's ``values`` over the points where every mesh has a value."""
    inside = np.all([np.isfinite(v) for v in values], axis=0)
    return [float(np.max(np.where(inside, v, -np.inf))) for v in values]


def summarise(rows: list[dict], radii) -> list[dict]:
    """One JSON-ready record per mesh: the scalars, and each field's largest value over the
    points inside every mesh (section stresses, hot-spot extrapolations)."""
    table = [{k: v for k, v in row.items() if not isinstance(v, np.ndarray)} for row in rows]
    t_root = rows[0]["root_thickness"]
    for label in ("spin_and_pressure", "pressure"):
        for r in radii:
            key = f"{label}_r{r:g}"
            for out, value in zip(table, _largest_inside([row[key] for row in rows])):
                out[key] = value
        for a, b in HOT_SPOT:
            near = [row[f"{label}_radial_{a * t_root:.6f}"] for row in rows]
            far = [row[f"{label}_radial_{b * t_root:.6f}"] for row in rows]
            extrapolated = [(b * n - a * f) / (b - a) for n, f in zip(near, far)]
            key = f"{label}_hot_spot_{a:g}_{b:g}"
            for out, value in zip(table, _largest_inside(extrapolated)):
                out[key] = value
    return table


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=float, nargs="+", default=[0.2, 0.1, 0.05])
    ap.add_argument("--orders", type=int, nargs="+", default=[2])
    ap.add_argument("--pressure", type=float, default=1.0e6, help="Pa on blade 1's back")
    ap.add_argument("--radii", type=float, nargs="+", default=[0.4, 0.5, 0.6],
                    help="radii (m) of the sections where the von Mises stress is read")
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)
    table = []
    with tempfile.TemporaryDirectory() as tmp:
        for order in args.orders:
            rows = []
            for size in args.sizes:
                rows.append(root_stress(size, order, args.pressure, tuple(args.radii), Path(tmp)))
                print(f"order {order}, element size {size:g} m: {rows[-1]['nodes']} nodes, "
                      f"{rows[-1]['seconds']:.1f} s", flush=True)
            table += summarise(rows, args.radii)
    for out in table:
        print(json.dumps(out))
    if args.json:
        args.json.write_text(json.dumps(table, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
