"""The contact's candidate list (:mod:`pdfem.coupling.broad_phase`) and the narrow phase on it.

References: the definition (a particle outside the grid's box grown by the skin cannot reach
the box before it has moved a skin; the list is made again then); a scan of every particle
(:meth:`SurfaceContact.inside`), which the candidate list must reproduce exactly while the
particles move.
"""

from __future__ import annotations

import numpy as np

from pdfem.coupling.broad_phase import moved_beyond
from pdfem.geometry.cell_hash import in_box
from pdfem.coupling.contact import SurfaceContact
from pdfem.fem.step_compliance import LumpedCompliance


def test_in_box_and_moved_beyond():
    y = np.array([[0.0, 0.0, 0.0], [1.0, 0.5, 0.5], [0.5, 0.5, 2.0], [0.2, 0.9, 0.1]])
    assert in_box(y, np.zeros(3), np.ones(3)).tolist() == [0, 1, 3]
    ref = y.copy()
    y2 = y.copy()
    y2[2, 0] += 0.25
    assert not moved_beyond(y2, ref, 0.25) and moved_beyond(y2, ref, 0.24)


class _Plate:
    """A flat square of two triangles at z = 0, normal +z, at rest (a ContactSurface)."""

    surface_triangles = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32)

    def surface_points(self):
        return np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]])

    def surface_velocities(self):
        return np.zeros((4, 3))

    def surface_compliance(self):
        return LumpedCompliance(np.zeros((4, 3)))

    def surface_rotation(self):
        return None


def test_candidates_find_every_particle_a_full_scan_finds_while_they_move():
    """Particles falling through a plate from up to 1 m above: at every step the contacts of the
    candidate list are those of a scan of every particle; the list is made again only after a
    particle has moved a skin (here every few steps, not every step)."""
    rng = np.random.default_rng(3)
    y = np.column_stack([rng.uniform(-0.2, 1.2, 400), rng.uniform(-0.2, 1.2, 400),
                         rng.uniform(-0.05, 1.0, 400)])
    contact = SurfaceContact(_Plate(), search_radius=0.05)
    v = np.tile([0.0, 0.0, -1.0], (400, 1))
    mass = np.ones(400)
    found = 0
    for _ in range(60):
        y_old = y.copy()
        y += 0.01 * v
        expected = np.flatnonzero(contact.inside(y))
        step = contact.resolve(y, y_old, v.copy(), mass, 0.01)
        assert step.rows.tolist() == expected.tolist()
        found += len(expected)
        y = y_old + 0.01 * v   # keep falling (the contact's push-back undone)
    assert found > 100 and 1 < contact.candidates.builds < 60
