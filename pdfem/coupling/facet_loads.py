"""Contact loads per facet of a structure's contact surface: pressure per frame, patch forces.

Every coupling step the coupler hands each structure's :class:`FacetLoads` the impulses its
contact pairs' contacts gave every facet (summed contact by contact in the serial order,
:mod:`pdfem.coupling.nodal_impulse`, so 1 and N MPI ranks agree to round-off):

* the force of the step per facet (N, the impulse over the step), whose sum over the facets is
  the structure's total contact force (each contact's impulse goes whole to one facet, and
  whole to that facet's nodes by weights that sum to 1); a *patch* (a surface group of the mesh
  that shares faces with the contact group, e.g. a frame or a plate field) gets the sum over
  its facets, written every step as ``loads/<structure>.<patch>`` (``force``, N, and the
  patch's ``area``, m^2);
* the normal impulse pressing on each facet (N s, along the facet's outward normal at the
  contact's instant), summed over the frame interval: the facet's contact pressure of a frame
  is ``p = J_n / (A T)`` (Pa): normal impulse over the facet's reference area ``A`` and the
  time ``T`` since the previous frame, i.e. the mean normal contact force over the interval
  per unit area; and the largest ``p`` of each facet over the run so far.

:class:`FacetLoadSource` writes them as the structure ``<structure>.contact`` of the results
file: the contact surface's triangles, its displacement ``u`` (m) and the cell fields
``contact_pressure`` and ``contact_pressure_max`` (Pa), shown by ParaView from the XDMF file.
Units: SI (m, m^2, s, N, N s, Pa).
"""

from __future__ import annotations

import numba
import numpy as np

from pdfem.meshing.quality import triangle_areas


@numba.njit(cache=True)
def _patch_sums(force, ptr, rows, out):
    """``out[g]`` = the sum of the rows ``rows[ptr[g]:ptr[g + 1]]`` of ``force`` (F, 3), added
    in row order from the first, as numpy's ``force[rows].sum(axis=0)`` adds them (the same
    bits, without the gathered copy)."""
    for g in range(ptr.shape[0] - 1):
        lo, hi = ptr[g], ptr[g + 1]
        for d in range(3):
            out[g, d] = force[rows[lo], d] if hi > lo else 0.0
        for k in range(lo + 1, hi):
            for d in range(3):
                out[g, d] += force[rows[k], d]


class FacetLoads:
    """The contact loads on the facets of one structure's contact surface (module docstring).

    Parameters
    ----------
    structure
        A contact surface (:class:`pdfem.fem.surface.ContactSurface`) at its reference
        configuration, with ``surface_groups()`` (the load patches) and ``name``.
    """

    def __init__(self, structure) -> None:
        self.structure = structure
        self.name = structure.name
        self.reference = np.array(structure.surface_points(), dtype=np.float64)
        self.triangles = np.asarray(structure.surface_triangles, dtype=np.int32)
        self.area = triangle_areas(self.reference, self.triangles)       # m^2
        self.patches = structure.surface_groups() if len(self.triangles) else {}
        # each patch's facets (ascending, as its mask selects them) and area, for the rows
        self._patch_facets = {g: np.flatnonzero(on) for g, on in self.patches.items()}
        self._patch_rows = np.concatenate([np.zeros(0, dtype=np.int64),
                                           *self._patch_facets.values()]).astype(np.int64)
        self._patch_ptr = np.cumsum([0] + [len(r) for r in self._patch_facets.values()],
                                    dtype=np.int64)
        self._patch_area = {g: float(self.area[on].sum()) for g, on in self.patches.items()}
        n = len(self.triangles)
        self.force = np.zeros((n, 3))        # N, last coupling step
        self.normal_impulse = np.zeros(n)    # N s, since the last frame
        self.max_pressure = np.zeros(n)      # Pa, over the frames so far
        self.since = 0.0                     # s, time of the last frame

    @property
    def n_facets(self) -> int:
        """Number of contact-surface facets."""
        return len(self.triangles)

    def add_step(self, impulse: np.ndarray, normal: np.ndarray, step: float) -> None:
        """One coupling step of length ``step`` (s): per facet, the impulse (F, 3) the
        structure took (N s) and its normal part pressing on the facet (F,) (N s)."""
        self.force = impulse / step
        self.normal_impulse += normal

    def patch_forces(self) -> dict[str, tuple[np.ndarray, float]]:
        """``{patch: ((3,) force (N) of the last coupling step, the patch's area (m^2))}``."""
        sums = np.empty((len(self._patch_facets), 3))
        _patch_sums(np.ascontiguousarray(self.force, dtype=np.float64), self._patch_ptr,
                    self._patch_rows, sums)
        return {g: (sums[k], self._patch_area[g]) for k, g in enumerate(self._patch_facets)}

    def take_frame(self, time: float) -> tuple[np.ndarray, np.ndarray]:
        """``(pressure, max_pressure)`` (F,) (Pa) of the frame at ``time`` (s): the mean normal
        contact pressure on each facet since the previous frame, and the largest over the
        frames so far; the interval then starts again at ``time``."""
        interval = time - self.since
        pressure = (self.normal_impulse / (self.area * interval) if interval > 0.0
                    else np.zeros(self.n_facets))
        np.maximum(self.max_pressure, pressure, out=self.max_pressure)
        self.normal_impulse = np.zeros(self.n_facets)
        self.since = float(time)
        return pressure, self.max_pressure.copy()

    def checkpoint_state(self) -> dict[str, np.ndarray | float]:
        """``normal_impulse`` (N s), ``max_pressure`` (Pa), ``force`` (N) and ``since`` (s)."""
        return {"normal_impulse": self.normal_impulse.copy(),
                "max_pressure": self.max_pressure.copy(), "force": self.force.copy(),
                "since": self.since}

    def restore_state(self, state: dict) -> None:
        """Restore :meth:`checkpoint_state` exactly."""
        self.normal_impulse = np.array(state["normal_impulse"], dtype=np.float64)
        self.max_pressure = np.array(state["max_pressure"], dtype=np.float64)
        self.force = np.array(state["force"], dtype=np.float64)
        self.since = float(state["since"])


def collect_facet_loads(records: list, step: float) -> None:
    """End of a coupling step of ``step`` s: hand each structure's :class:`FacetLoads` (its
    coupler record's ``facet_loads``) the facet impulses of its contact pairs, summed in pair
    order (:meth:`pdfem.coupling.contact.SurfaceContact.take_facet_impulse`)."""
    for r in records:
        fl = r.facet_loads
        total, total_normal = np.zeros((fl.n_facets, 3)), np.zeros(fl.n_facets)
        for p in r.pairs:
            impulse, normal = p.contact.take_facet_impulse()
            total += impulse
            total_normal += normal
        fl.add_step(total, total_normal, step)


class FacetLoadSource:
    """The output source (:class:`pdfem.output.source.OutputSource`) of a structure's facet
    loads: the mesh ``<structure>.contact`` with ``u``, ``contact_pressure`` and
    ``contact_pressure_max`` every frame, and ``loads/<structure>.<patch>`` every step."""

    mesh_kind = "structure"

    def __init__(self, loads: FacetLoads, coupler) -> None:
        self.loads, self.coupler = loads, coupler
        self.name = f"{loads.name}.contact"

    @classmethod
    def of_run(cls, setup, per_rank: bool) -> list:
        """One source per structure with a contact surface in a contact pair."""
        return [cls(r.facet_loads, setup.coupler) for r in setup.coupler.records
                if r.facet_loads.n_facets and r.pairs]

    def output_mesh(self) -> tuple[np.ndarray, np.ndarray, str]:
        """The contact surface's reference nodes (m) and triangles."""
        return self.loads.reference, self.loads.triangles, "triangle"

    def frame_fields(self) -> dict[str, np.ndarray]:
        """``u`` (m) of the surface nodes, ``contact_pressure`` and its running maximum (Pa)."""
        pressure, peak = self.loads.take_frame(self.coupler.time)
        return {"u": self.loads.structure.surface_points() - self.loads.reference,
                "contact_pressure": pressure, "contact_pressure_max": peak}

    def frame_rows(self) -> dict:
        """None."""
        return {}

    def step_rows(self) -> dict:
        """``loads/<structure>.<patch>``: ``force`` (N) of the step on each patch and the
        patch's ``area`` (m^2, reference configuration)."""
        return {f"loads/{self.loads.name}.{g}": {"force": f, "area": a}
                for g, (f, a) in self.loads.patch_forces().items()}
