"""When the run re-partitions its split ice bodies, and the imbalance history it writes.

Under MPI every coupling step :class:`LoadBalance` asks each ice body for its imbalance (the
largest rank's work over the mean, :func:`pdfem.pd.layout.rebalance.imbalance`) and
re-partitions it (:func:`~pdfem.pd.layout.rebalance.rebalance`) every
``run.rebalance_every`` coupling steps, or when the imbalance exceeds
``run.rebalance_imbalance``. It writes the history ``parallel/<body>`` (``imbalance``: of the
partition the next step runs with, -; ``rebalanced``: 1 at the steps that re-partitioned) and
reports each re-partition. After one, the coupler rebuilds its per-particle tables
(:meth:`pdfem.coupling.coupler.Coupler.particles_moved`). A serial run writes nothing.
"""

from __future__ import annotations

import time


class LoadBalance:
    """The load balance of a run's ice bodies (see the module docstring).

    Parameters
    ----------
    case
        The validated case (``run.rebalance_every``, ``run.rebalance_imbalance``).
    setup
        The built run (:class:`pdfem.run.build.Setup`: ``bodies``, ``coupler``, ``forces``).
    comm
        The communicator.
    say
        Function taking one line of the run's report.

    A re-partition moves the particle forces' per-particle state with the particles
    (:meth:`pdfem.forces.base.ParticleForce.moving_state`: water's drag and added-mass
    counters); short-range contact rebuilds its halo when a body's halo plan changes
    (:mod:`pdfem.forces.short_range_halo`).
    """

    def __init__(self, case, setup, comm, say=lambda s: None) -> None:
        run = case.run
        self.every, self.limit = int(run.rebalance_every), float(run.rebalance_imbalance)
        self.bodies, self.coupler, self.say = setup.bodies, setup.coupler, say
        self.active = comm.size > 1 and bool(self.bodies)  # whole bodies never move
        self.size = comm.size
        self._left: dict[str, float] = {}  # body -> imbalance right after its last re-partition
        self._levels: dict[str, tuple[int, float]] = {}  # body -> (layout version, imbalance)
        if self.active:
            levels = ", ".join(f"'{b.name}' {self.imbalance(b):.3f}" for b in self.bodies)
            when = " and ".join(w for w in ((f"every {self.every:,} steps" if self.every else ""),
                                            (f"above {self.limit:g}" if self.limit else "")) if w)
            say(f"  load balance (largest rank's bond work / mean): {levels}; re-partition "
                f"{when or 'never (run.rebalance_every, run.rebalance_imbalance)'}")

    def imbalance(self, body) -> float:
        """The imbalance of ``body`` (:meth:`pdfem.pd.body.IceBody.imbalance`), measured again
        only when its particles have moved: a rank's work, the bonds of its owned particles
        broken or not, changes by a migration only (collective)."""
        version, level = self._levels.get(body.name, (None, 1.0))
        if version != body.layout_version:
            level = body.imbalance()
            self._levels[body.name] = (body.layout_version, level)
        return level

    def after_step(self, step: int, t: float, writer) -> None:
        """Measure, re-partition where due, write the history rows of step ``step`` ending at
        ``t`` (s) with ``writer`` (collective)."""
        if not self.active:
            return
        moved = False
        for b in self.bodies:
            level = self.imbalance(b)
            # above the limit, unless it is what the last re-partition left (the work only
            # changes by a migration: re-partitioning again would give the same)
            over = self.limit and level > self.limit and level != self._left.get(b.name)
            due = (self.every and step % self.every == 0) or over
            if due:
                before, t0 = level, time.perf_counter()
                forces = self.coupler.forces
                carry = {f"{i}:{k}": v for i, f in enumerate(forces)
                         for k, v in f.moving_state(b).items()}
                carried = b.rebalance(carry)
                for i, f in enumerate(forces):
                    f.moved_state(b, {k.split(":", 1)[1]: v for k, v in carried.items()
                                      if k.split(":", 1)[0] == str(i)})
                level, moved = self.imbalance(b), True
                self._left[b.name] = level
                self.say(f"  t = {t:.6e} s (step {step:,}): re-partitioned '{b.name}' over "
                         f"{self.size} ranks, imbalance {before:.3f} -> {level:.3f} "
                         f"({time.perf_counter() - t0:.2f} s)")
            writer.append_history(f"parallel/{b.name}", t,
                                  {"imbalance": level, "rebalanced": float(bool(due))})
        if moved:
            self.coupler.particles_moved()
