"""Cost of the demo's structure per coupling step: the hull panel as the demo builds it.

Builds ``models/demo_ice_sheet_panel.toml`` exactly as ``pdfem run`` does (its mesh model,
element, supports, time steps), then times the panel's own explicit steps: ``STEPS`` coupling
steps of ``structure substeps`` FE steps each, under a uniform pressure so that the state is
not trivially zero (the cost of a step does not depend on it). Reports the mesh size, the
element, the critical and coupling steps, the substeps, and the wall time per FE step and per
coupling step (the median of 5 repetitions). The figure is the structure's share of a coupling
step; the contact and the ice come on top.

    python benchmarks/structure_step.py [--json]

Written against the run builder's interface (``pdfem.run.build.build``), so the same script
times an older checkout for a before/after comparison in one session.
"""

from __future__ import annotations

import argparse
import importlib.resources
import json
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

STEPS = 50


def bench_structure_step() -> dict:
    """Time the demo panel's FE steps (see the module docstring); the figures as a dict."""
    from pdfem.case import load_case
    from pdfem.parallel.comm import world
    from pdfem.run.build import build

    lines: list[str] = []
    with importlib.resources.as_file(importlib.resources.files("pdfem.models")
                                     / "demo_ice_sheet_panel.toml") as path, \
            tempfile.TemporaryDirectory() as tmp:
        case = load_case(path)
        setup = build(case, Path(tmp), world(), lines.append)
        panel = setup.structures[0]
        n_st = setup.n_st
        h = setup.dt / n_st
        panel.set_nodal_forces(np.tile([0.0, 0.0, -1.0], (len(panel.points), 1)))
        for _ in range(n_st):          # warm up (caches, first allocation)
            panel.step(h)
        times = []
        for _ in range(5):
            t0 = time.perf_counter()
            for _ in range(STEPS * n_st):
                panel.step(h)
            times.append((time.perf_counter() - t0) / (STEPS * n_st))
        per_step = statistics.median(times)
        return {"nodes": int(len(panel.points)), "dofs": int(3 * len(panel.points)),
                "description": panel.describe(), "critical_step_s": panel.critical_time_step(),
                "coupling_step_s": setup.dt, "structure_substeps": n_st,
                "seconds_per_fe_step": per_step, "seconds_per_coupling_step": per_step * n_st}


def main() -> None:
    """Command line: print the figures (``--json``: one JSON object)."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--json", action="store_true")
    r = bench_structure_step()
    if p.parse_args().json:
        print(json.dumps(r, indent=1))
        return
    print(r["description"])
    print(f"coupling step {r['coupling_step_s']:.3e} s, {r['structure_substeps']} FE substeps")
    print(f"{r['seconds_per_fe_step'] * 1e3:.3f} ms per FE step, "
          f"{r['seconds_per_coupling_step'] * 1e3:.3f} ms per coupling step")


if __name__ == "__main__":
    main()
