"""Blade root stress of the milling propeller against mesh refinement, first- and second-order
tetrahedra (the element-order choice of models/propeller_ice_milling.toml).

The propeller of the milling case (models/propeller.py: D = 2 m, hub 0.6 m, Z = 4, P/D = 0.7,
EAR = 0.5, Ni-Al bronze), its blade roots clamped, under a static load that stands for a blade
passage: the centrifugal load of the steady spin at 300 rpm on every blade (the lumped masses at
``m w^2 r``, radial) plus a uniform pressure ``--pressure`` (Pa) on the back of blade 1
(``blade1_back``). Linear statics, ``K u = f`` (:func:`pdfem.fem.static.static_displacement`;
without the stress stiffening and spin softening of the rotating frame, which are the same
for every mesh). Reported per mesh: nodes, the largest element-centre von Mises stress in the
root band of blade 1 (elements whose centre lies at radii ``--band`` from the shaft axis,
outside the clamped edge at the hub radius, where the stress is singular), the same with the
pressure alone, and blade 1's root bending moment about the root centroid (from the support
reactions). A result is converged when two meshes, one refined 2x, agree within 5 %.

Run::

    python benchmarks/blade_root_convergence.py --sizes 0.2 0.1 0.05 --orders 1 2 [--json F]

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
from pdfem.fem.static import static_displacement
from pdfem.fem.stress import hooke_stress, von_mises
from pdfem.fem.structure import ElasticStructure
from pdfem.models import propeller

PARAMS = dict(blades=4, diameter=2.0, hub_diameter=0.6, pitch_ratio=0.7, ear=0.5, sections=10)
BRONZE = ElasticMaterial(density=7600.0, youngs_modulus=120e9, poisson_ratio=0.32)
OMEGA = 2.0 * np.pi * 5.0          # rad/s: 300 rpm about +x


def section_points(radius: float, n: int = 41) -> np.ndarray:
    """(P, 3) points (m) of the cylinder ``y^2 + z^2 = radius^2`` about the shaft, on a grid
    over x in [-0.35, 0.35] m and the angle from +z in [-0.9, 0.9] rad: they cut blade 1
    (its reference line is +z) at that radius; most lie outside it."""
    x, phi = np.meshgrid(np.linspace(-0.35, 0.35, n), np.linspace(-0.9, 0.9, 3 * n))
    return np.column_stack([x.ravel(), -radius * np.sin(phi.ravel()),
                            radius * np.cos(phi.ravel())])


def point_von_mises(structure: ElasticStructure, points: np.ndarray) -> np.ndarray:
    """(P,) von Mises stress (Pa) of the FE field at ``points`` (NaN outside the mesh): the
    displacement gradient of the element holding each point, at the point."""
    mesh = structure.mesh.mesh
    corners = skfem.MeshTet(mesh.p, mesh.t[:4])    # straight-sided: to find and place points
    finder = corners.element_finder()
    elements = np.array([_find(finder, p) for p in points])
    out = np.full(len(points), np.nan)
    mapping = corners._mapping()
    for k in np.flatnonzero(elements >= 0):
        e = elements[k]
        X = mapping.invF(points[k][:, None, None], tind=np.array([e]))[:, 0, :]
        b = skfem.Basis(mesh, structure.basis.elem, quadrature=(X, np.ones(1)),
                        elements=np.array([e]))
        g = b.interpolate(structure.solver.u).grad[:, :, 0, 0]
        out[k] = float(von_mises(hooke_stress(g, structure.material)))
    return out


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


def root_stress(size: float, order: int, pressure: float, radii: tuple[float, ...],
                workdir: Path) -> dict:
    """Mesh, solve and measure one propeller (see the module docstring)."""
    t0 = time.perf_counter()
    s, f_spin, f_ice = blade_model(size, order, pressure, workdir)
    out = {"element_size": size, "order": order, "nodes": s.n_nodes, "elements": s.cells.shape[0]}
    for label, f in (("spin_and_pressure", f_spin + f_ice), ("pressure", f_ice)):
        u = static_displacement(s, f)
        s.set_state(u)
        for r in radii:
            out[f"points_{r:g}"] = section_points(r)
            vm = point_von_mises(s, out[f"points_{r:g}"])
            out[f"{label}_r{r:g}"] = vm      # NaN where a point is outside this mesh
        out[f"{label}_tip_deflection"] = float(np.abs(u).max())
    out["seconds"] = time.perf_counter() - t0
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=float, nargs="+", default=[0.2, 0.1, 0.05])
    ap.add_argument("--orders", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--pressure", type=float, default=1.0e6, help="Pa on blade 1's back")
    ap.add_argument("--radii", type=float, nargs="+", default=[0.4, 0.5],
                    help="radii (m) of the sections where the stress is read")
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for order in args.orders:
            for size in args.sizes:
                rows.append(root_stress(size, order, args.pressure, tuple(args.radii), Path(tmp)))
                print(f"order {order}, element size {size:g} m: {rows[-1]['nodes']} nodes, "
                      f"{rows[-1]['seconds']:.1f} s", flush=True)
    # the largest stress of each section over the points inside every mesh
    table = []
    for row in rows:
        out = {k: row[k] for k in ("element_size", "order", "nodes", "elements", "seconds")}
        for key, value in row.items():
            if isinstance(value, np.ndarray) and not key.startswith("points_"):
                inside = np.all([np.isfinite(r[key]) for r in rows], axis=0)
                k = int(np.argmax(np.where(inside, value, -np.inf)))
                out[key] = float(value[k])
                out[key + "_at"] = [round(float(c), 4) for c in row["points_" + key.split("_r")[-1]][k]]
                out[key.replace("_r", "_points_r")] = int(inside.sum())
            elif key.endswith("tip_deflection"):
                out[key] = value
        table.append(out)
        print(json.dumps(out))
    if args.json:
        args.json.write_text(json.dumps(table, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
