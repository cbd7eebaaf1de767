"""Rigid bodies with prescribed motion (indenters, a rigid bow or blade) and their contact load.

A :class:`RigidBody` is a triangulated surface that translates with a constant velocity ``v``
(m/s), or along a piecewise-linear displacement path ``u(t)`` (m,
:class:`pdfem.geometry.path.DisplacementPath`), and rotates with a constant angular velocity
``w`` (rad/s) about a centre ``c`` that moves with it. The pose is exact at any time ``t``::

    x(t) = c(t) + R(w t) (X - c0),          R: Rodrigues' formula for the angle |w| t about w/|w|
    x'(t) = c'(t) + w x (x(t) - c(t)),      c(t) = c0 + v t  or  c0 + u(t)

with ``c'`` the slope of the path's current segment (its velocity jumps at the path's points;
the coupler books the work of the contact on the body with the displacement over each step, so
the jumps cost the energy balance nothing).

so many steps accumulate no drift (the rotation is recomputed from the accumulated angle, not
composed step by step). The body offers the same surface interface as an elastic structure
(:class:`pdfem.fem.surface.ContactSurface`); the contact forces it receives are accumulated and
reported (total force N, moment N m) but do not change its motion. It has no stable-step limit.
"""

from __future__ import annotations

import math
import os

import numpy as np

from pdfem.fem.surface_motion import PrescribedSurface

from pdfem.fem.mesh import load_mesh, read_msh_groups
from pdfem.fem.base import Structure
from pdfem.fem.surface import orient_outward, split_quads
from pdfem.fem.surface_patches import surface_patches
from pdfem.geometry.vectors import cross
from pdfem.motion.rotation import rotation_matrix


def read_surface(path: str | os.PathLike, group: str = "contact") -> tuple[np.ndarray, np.ndarray]:
    """Triangles of a named surface group of a gmsh file, outward oriented.

    If the file has a volume mesh, the faces are oriented out of the volume; otherwise (a surface
    mesh) they are oriented consistently and, for a closed surface, outward
    (:func:`pdfem.fem.surface.orient_outward`). Quadrilaterals are split into two triangles.

    Parameters
    ----------
    path
        A gmsh ``.msh`` file (4.1 or 2.2).
    group
        Name of a surface (2-D) physical group.

    Returns
    -------
    points, triangles
        (Ns, 3) coordinates (m) of the group's nodes and (T, 3) int32 triangles into them.

    Raises
    ------
    ValueError
        If the group is missing or is not a surface group.
    """
    raw = read_msh_groups(path)
    if group not in raw.groups or raw.groups[group][0] != 2:
        have = ", ".join(sorted(raw.groups)) or "(none)"
        extra = f" ('{group}' is not a surface group)" if group in raw.groups else ""
        raise ValueError(f"group '{group}' not in {raw.path}{extra}; the file has groups: {have}")
    if raw.volume_cells:
        mesh = load_mesh(path)
        faces = split_quads(mesh.group_facets(group))
        nodes, local = np.unique(faces, return_inverse=True)
        return mesh.points[nodes], local.reshape(faces.shape).astype(np.int32)
    blocks = [c for ct, c in raw.groups[group][1] if ct in ("triangle", "quad")]
    others = sorted({ct for ct, _ in raw.groups[group][1] if ct not in ("triangle", "quad")})
    if others:
        raise ValueError(f"{raw.path}: surface group '{group}' has {', '.join(others)} elements; "
                         "a rigid surface needs first-order triangles or quadrilaterals")
    tris = np.vstack([split_quads(c) for c in blocks]) if blocks else np.zeros((0, 3), np.int32)
    nodes, local = np.unique(tris, return_inverse=True)
    pts = raw.points[nodes]
    return pts, orient_outward(pts, local.reshape(tris.shape))


class RigidBody(Structure):
    """A rigid surface moving with prescribed translation and constant rotation (a
    :class:`pdfem.fem.base.Structure` with ``prescribed_motion``: no step limit, no energy).

    Parameters
    ----------
    points
        (Ns, 3) surface node coordinates at t = 0 (m).
    triangles
        (T, 3) triangles into ``points``, outward oriented (see ``orient``).
    velocity
        (3,) translation velocity v (m/s).
    angular_velocity
        (3,) angular velocity w (rad/s).
    centre
        (3,) centre of rotation at t = 0 (m); it moves with the translation.
    translation
        A :class:`~pdfem.geometry.path.DisplacementPath` of the translation instead of
        ``velocity`` (the body starts at the path's displacement at t = 0).
    name
        Name of the body.
    orient
        Re-orient the triangles consistently and, if the surface is closed, outward.
    """

    def __init__(self, points: np.ndarray, triangles: np.ndarray, velocity=(0.0, 0.0, 0.0),
                 angular_velocity=(0.0, 0.0, 0.0), centre=(0.0, 0.0, 0.0), name: str = "rigid",
                 orient: bool = True, translation=None):
        self.name = name
        self.x0 = np.ascontiguousarray(points, dtype=np.float64)
        if self.x0.ndim != 2 or self.x0.shape[1] != 3:
            raise ValueError(f"points must be (N, 3), got {self.x0.shape}")
        tri = np.asarray(triangles, dtype=np.int64)
        if (tri.ndim != 2 or tri.shape[1] != 3
                or (tri.size and (tri.min() < 0 or tri.max() >= len(self.x0)))):
            raise ValueError("triangles must be (T, 3) indices into points")
        self.surface_triangles = orient_outward(self.x0, tri) if orient else tri.astype(np.int32)
        self.velocity = np.asarray(velocity, dtype=np.float64).reshape(3).copy()
        self.angular_velocity = np.asarray(angular_velocity, dtype=np.float64).reshape(3).copy()
        self.centre0 = np.asarray(centre, dtype=np.float64).reshape(3).copy()
        self.translation = translation
        self._arm0 = self.x0 - self.centre0   # the nodes about the centre, at t = 0
        self.time = 0.0
        self._time_carry = 0.0
        self._surface_forces = np.zeros((len(self.x0), 3))
        self.patches: dict[str, np.ndarray] = {}
        self._update_pose()

    @classmethod
    def from_msh(cls, path: str | os.PathLike, group: str = "contact", **kwargs) -> "RigidBody":
        """Build from a named surface group of a gmsh file; ``kwargs`` as for the constructor."""
        pts, tri = read_surface(path, group)
        body = cls(pts, tri, **kwargs)
        body.patches = surface_patches(path, group, body.x0, body.surface_triangles)
        return body

    # ------------------------------------------------------------------ pose
    def centre(self) -> np.ndarray:
        """(3,) current centre of rotation c0 + v t, or c0 + u(t) on a path (m)."""
        if self.translation is not None:
            return self.centre0 + self.translation.displacement(self.time)
        return self.centre0 + self.velocity * self.time

    def translation_velocity(self) -> np.ndarray:
        """(3,) current velocity of the centre (m/s): v, or the slope of the path's segment."""
        if self.translation is None:
            return self.velocity
        return self.translation.velocity(self.time)

    def rotation(self) -> np.ndarray:
        """(3, 3) current rotation R(w t)."""
        return rotation_matrix(self.angular_velocity * self.time)

    def surface_rotation(self) -> np.ndarray:
        """(3, 3) the body's rotation (:meth:`rotation`): the surface moves rigidly."""
        return self.rotation()

    def _update_pose(self) -> None:
        c = self.centre()
        if np.any(self.angular_velocity):
            self._x = c + self._arm0 @ self.rotation().T
            self._v = self.translation_velocity() + cross(self.angular_velocity, self._x - c)
        else:  # a body that only translates: R = I, w x r = 0 (the same values, no products)
            self._x = c + self._arm0
            self._v = np.broadcast_to(self.translation_velocity(), self._x.shape).copy()

    def step(self, dt: float) -> None:
        """Advance the pose by ``dt`` (s).

        The time is accumulated with compensated (Kahan) summation, so that after many steps the
        angle ``|w| t`` carries no round-off drift from the sum.
        """
        y = float(dt) - self._time_carry
        t = self.time + y
        self._time_carry = (t - self.time) - y
        self.time = t
        self._update_pose()

    def checkpoint_state(self) -> dict[str, np.ndarray | float]:
        """Time (s), its summation carry and the contact forces (N), for a checkpoint."""
        return {"time": self.time, "time_carry": self._time_carry,
                "surface_forces": self._surface_forces.copy()}

    def restore_state(self, state: dict) -> None:
        """Restore a state from :meth:`checkpoint_state` exactly (the pose follows from the time)."""
        forces = np.asarray(state["surface_forces"], dtype=np.float64)
        if forces.shape != self._surface_forces.shape:
            raise ValueError(f"surface_forces has shape {forces.shape}, expected "
                             f"{self._surface_forces.shape}")
        self.time = float(state["time"])
        self._time_carry = float(state["time_carry"])
        self._surface_forces[:] = forces
        self._update_pose()

    prescribed_motion = True

    def surface_motion(self) -> PrescribedSurface:
        """The surface moves as prescribed: the body steps first, whatever the contacts."""
        return PrescribedSurface(self)

    def stable_time_step(self) -> float:
        """A rigid body imposes no step limit: ``inf``."""
        return math.inf

    def output_mesh(self) -> tuple[np.ndarray, np.ndarray, str]:
        """Surface nodes at t = 0 (m) and the surface triangles."""
        return self.x0, self.surface_triangles, "triangle"

    def output_fields(self) -> dict[str, np.ndarray]:
        """``u`` (Ns, 3): displacement (m) and ``v`` (Ns, 3): velocity (m/s) of the surface
        nodes."""
        return {"u": self.surface_points() - self.x0, "v": self.surface_velocities()}

    def surface_groups(self) -> dict[str, np.ndarray]:
        """The load patches: the surface mesh's other groups on the contact surface
        (:func:`pdfem.fem.surface_patches.surface_patches`; set by :meth:`from_msh`)."""
        return self.patches

    def describe(self) -> str:
        """Surface nodes."""
        return f"rigid body '{self.name}': {len(self.x0):,} surface nodes"

    # ------------------------------------------------------------------ surface interface
    def surface_points(self) -> np.ndarray:
        """(Ns, 3) current surface node positions (m), a new array (the prescribed surface
        motion keeps it as the substep's start)."""
        return self._x.copy()

    def surface_velocities(self) -> np.ndarray:
        """(Ns, 3) surface node velocities v + w x (x - c) (m/s)."""
        return self._v.copy()

    def total_surface_moment(self, about=None) -> np.ndarray:
        """(3,) moment (N m) of the accumulated surface forces about ``about`` (default: the
        current centre of rotation)."""
        return super().total_surface_moment(self.centre() if about is None else about)
