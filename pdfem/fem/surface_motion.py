"""How a structure's contact surface moves over the substeps of a coupled step.

The coupler (:mod:`pdfem.coupling.coupler`) meets the ice with each structure's surface at the
start and end of every substep. A structure tells it, through the object its
:meth:`~pdfem.fem.base.Structure.surface_motion` returns, where its surface goes:

* :class:`PredictedSurface`, a structure that responds to its loads: the surface moves on
  from where it is with its velocity now (predicted), the contact impulses of the substep act
  on the structure as a velocity jump (their work is the structure's kinetic-energy change) and
  the structure steps after the contacts;
* :class:`PrescribedSurface`, a motion that is known whatever the loads (a rigid indenter):
  the structure takes its step first and the surface's motion is what it did; the impulses do
  not change it, and their work is the work its drive does (v . J);
* :class:`SteppedSurface`, a structure advanced by implicit steps (:mod:`pdfem.fem.implicit`):
  it takes its step first under its loads, the surface's motion is what it did, and the
  contact impulses of the step then amend that step (the scheme is linear: the response to a
  force at the step's end is added, :meth:`pdfem.fem.implicit.Newmark.end_impulse`); their
  work is known at once, the trapezoidal work of that force over the amended step.

Each has two ways of walking a coupling step of length D: :meth:`over` for a structure that
takes the substep itself (the structure subcycles, or nobody does), :meth:`sample` for one
that takes the whole step once while the ice subcycles (the surface between its positions at
the step's start and end). Units: m, m/s, s, N s, J.
"""

from __future__ import annotations

import numpy as np


class PredictedSurface:
    """The surface of a structure that responds to its loads (module docstring)."""

    def __init__(self, structure) -> None:
        self.structure = structure
        self._pos: np.ndarray | None = None

    def over(self, h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(start, end, velocity)`` of the surface over the next ``h`` (s), predicted from
        the structure's state now; the structure steps in :meth:`after`."""
        p0, v0 = self.structure.surface_state()
        return p0, p0 + h * v0, v0

    def begin(self, step: float) -> None:
        """A coupling step of ``step`` (s) whose substeps :meth:`sample` walks."""
        self._pos = self.structure.surface_points().copy()

    def sample(self, h: float, frac: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(start, end, velocity)`` of the next substep of ``h`` (s) ending at ``frac`` of
        the coupling step: from the position predicted for the last substep's end, with the
        structure's velocity now (after the impulses of the substeps so far)."""
        v = self.structure.surface_velocities().copy()
        start = self._pos
        self._pos = start + h * v
        return start, self._pos, v

    def respond(self, impulse: np.ndarray) -> float:
        """The contact impulses ``impulse`` ((Ns, 3), N s) act now, as a velocity jump; their
        work (J)."""
        return self.structure.apply_surface_impulse(impulse)

    def drive_work(self, impulse: np.ndarray, velocity: np.ndarray) -> float:
        """No drive: 0 J."""
        return 0.0

    def after(self, h: float) -> None:
        """The structure steps ``h`` (s) under its loads, after the contacts."""
        self.structure.step(h)


class PrescribedSurface:
    """The surface of a structure whose motion is prescribed (module docstring)."""

    def __init__(self, structure) -> None:
        self.structure = structure
        self._p0 = self._dp = self._pos = None
        self._step = 0.0

    def over(self, h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The structure takes its step of ``h`` (s) now; ``(start, end, velocity)`` of what
        its surface did (the mean velocity over the step)."""
        s = self.structure
        p0 = s.surface_points()   # a rigid body's are its own copies (RigidBody)
        s.step(h)
        p1 = s.surface_points()
        return p0, p1, (p1 - p0) / h

    def begin(self, step: float) -> None:
        """The structure takes the coupling step of ``step`` (s) now; :meth:`sample` walks it."""
        s = self.structure
        self._p0 = s.surface_points()
        s.step(step)
        self._dp = s.surface_points() - self._p0
        self._step = step
        self._pos = self._p0

    def sample(self, h: float, frac: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(start, end, velocity)`` of the substep ending at ``frac`` of the coupling step:
        along the straight path of the step (its mean velocity)."""
        start = self._pos
        self._pos = self._p0 + frac * self._dp
        return start, self._pos, self._dp / self._step

    def respond(self, impulse: np.ndarray) -> float:
        """Nothing moves it: 0 J."""
        return 0.0

    def drive_work(self, impulse: np.ndarray, velocity: np.ndarray) -> float:
        """The work (J) its drive does against the impulses ``impulse`` at the surface
        velocity ``velocity``: v . J."""
        return float(np.sum(impulse * velocity))

    def after(self, h: float) -> None:
        """Nothing: the step was taken in :meth:`over` or :meth:`begin`."""


class SteppedSurface(PrescribedSurface):
    """The surface of a structure advanced by implicit steps (module docstring): it steps as a
    prescribed surface does (:meth:`over`, :meth:`begin`, :meth:`sample`: the motion of its free
    step, which the contacts see exactly), and the impulses then amend that step."""

    def sample(self, h: float, frac: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(start, end, velocity)`` of the substep ending at ``frac`` of the coupling step,
        along the straight path from the step's start to where the structure is now (its
        step amended by the impulses so far)."""
        self._dp = self.structure.surface_points() - self._p0
        return super().sample(h, frac)

    def respond(self, impulse: np.ndarray) -> float:
        """The impulses ``impulse`` ((Ns, 3), N s) amend the step just taken; their work (J)
        (:meth:`pdfem.fem.base.Structure.apply_surface_impulse`)."""
        return self.structure.apply_surface_impulse(impulse)

    def drive_work(self, impulse: np.ndarray, velocity: np.ndarray) -> float:
        """No drive: 0 J."""
        return 0.0
