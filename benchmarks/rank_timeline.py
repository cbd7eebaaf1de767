"""Where each rank's time goes in a run: every phase of the coupling step and of the loop's
tasks, with the part of it spent waiting for the other ranks (in a collective).

``--profile`` reports the largest rank's time per component, waits included; this splits each
phase's time into work ("busy") and waiting, rank by rank, which is what shows a load
imbalance (one rank amending the blade in the ice while the other waits) and what a perfect
balance could gain (the mean of the ranks' busy times against the serial run's).

Run (the milling case shortened to 0.02 s, say)::

    mpiexec -n 2 -env NUMBA_NUM_THREADS 1 python benchmarks/rank_timeline.py CASE OUT
    NUMBA_NUM_THREADS=1 python benchmarks/rank_timeline.py CASE OUT

Each rank writes ``OUT/timeline_<rank>.txt``: seconds per phase, its waits and its busy time,
largest first. The phases are methods of the coupler, the structures' integrators and the
loop's tasks, timed by wrapping them (this script only; the run is otherwise the user's).
SI units: s.
"""

from __future__ import annotations

import collections
import sys
import time
from pathlib import Path

import pdfem.parallel.comm as comm_module
import pdfem.run.loop as loop
from pdfem.cli.main import main
from pdfem.coupling.coupler import Coupler
from pdfem.fem.block_factor import BlockFactor
from pdfem.fem.implicit import Newmark
from pdfem.motion.frame_structure import FrameStructure
from pdfem.motion.shaft_loads import ShaftLoads
from pdfem.pd.body import IceBody

PHASES = {
    Coupler: ("step", "_set_surfaces", "_contact", "_hand_over", "_apply_impulses",
              "_finish_ice_step", "_after_breaking"),
    Newmark: ("step", "end_impulse", "_solved", "_rhs_product", "_rows"),
    BlockFactor: ("solve_mine",),
    FrameStructure: ("step", "_amend_step", "_inertial_dofs"),
    ShaftLoads: ("after_step", "rows"),
    IceBody: ("begin_step", "compute_forces"),
    **{getattr(loop, name): ("after_step",) for name in (
        "Histories", "Balance", "MotionCheck", "EnergyCheck", "Frames", "Checkpoints")},
}
COLLECTIVES = ("allreduce_sum", "allreduce_max", "gather", "allgather", "exchange")

total: dict[str, float] = collections.defaultdict(float)
waited: dict[str, float] = collections.defaultdict(float)
open_phases: list[str] = []


def timed(label: str, method):
    def call(*args, **kwargs):
        open_phases.append(label)
        start = time.perf_counter()
        try:
            return method(*args, **kwargs)
        finally:
            total[label] += time.perf_counter() - start
            open_phases.pop()
    return call


def waiting(method):
    def call(*args, **kwargs):
        start = time.perf_counter()
        try:
            return method(*args, **kwargs)
        finally:
            spent = time.perf_counter() - start
            for label in set(open_phases) | {"all collectives"}:
                waited[label] += spent
    return call


def instrument() -> None:
    for cls, names in PHASES.items():
        for name in names:
            setattr(cls, name, timed(f"{cls.__name__}.{name}", getattr(cls, name)))
    for name in COLLECTIVES:
        setattr(comm_module.MPIComm, name, waiting(getattr(comm_module.MPIComm, name)))


def report(out: Path, rank: int) -> None:
    lines = [f"{total[k]:9.3f} s  wait {waited[k]:8.3f}  busy {total[k] - waited[k]:8.3f}  {k}"
             for k in sorted(total, key=lambda k: -total[k])]
    lines.append(f"waiting in all collectives: {waited['all collectives']:.3f} s")
    (out / f"timeline_{rank}.txt").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    case, out = sys.argv[1], Path(sys.argv[2])
    instrument()
    sys.argv = ["pdfem", "run", case, "--out", str(out), "--quiet"]
    try:
        main()
    except SystemExit:
        pass
    report(out, comm_module.world().rank)
