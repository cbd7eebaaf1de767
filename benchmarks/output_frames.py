"""Benchmark of the results writer: the wall time of one output frame early and late in a run.

Writes ``frames`` frames of a small run (an ice body of ``n`` particles and a 12-tetrahedron
structure with a cell field, plus one history row per frame) with
:class:`pdfem.output.writer.ResultsWriter`, timing every :meth:`write_frame` call
(``time.perf_counter``). It reports the mean and median time of the ``window`` frames from
frame 100 on and from frame ``frames - window`` on, and their ratio: a writer whose cost per
frame does not grow with the run has a ratio near 1. Both windows hold as many frames on which
the XDMF views are made ahead (every ``VIEW_BATCH`` frames), so they compare like with like.
The XDMF file's whole rewrites (when its reserve runs out, at geometrically spaced frames) are
counted and the slowest frame is reported. Not a test: nothing is asserted.

Run it with ``pdfem bench output`` or ``python benchmarks/output_frames.py [--unplanned]``.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from pdfem.output.writer import ResultsWriter


def bench_output_frames(n: int = 200, frames: int = 10_256, window: int = 256,
                        planned: bool = True) -> dict:
    """Time every frame of a ``frames``-frame results file (see the module docstring).

    Parameters
    ----------
    n
        Ice particles.
    frames
        Frames to write (>= 100 + 2 ``window``).
    window
        Frames in each timed window.
    planned
        Tell the writer how many frames to expect, as a run does (``expected_frames``: the
        XDMF file reserves room at the first frame); ``False``: it grows by rewrites.

    Returns
    -------
    dict
        ``early_mean_ms``, ``late_mean_ms``, ``ratio_mean`` (late / early), the same for the
        medians, ``xdmf_rewrites``, ``slowest_ms`` and its ``slowest_frame``, ``total_s``,
        ``xdmf_mb`` and ``h5_mb`` (file sizes at the end).
    """
    frames = max(int(frames), 100 + 2 * window)
    rng = np.random.default_rng(0)
    x0 = rng.random((n, 3))
    points = rng.random((27, 3))
    cells = np.array([[i, i + 1, i + 2, i + 3] for i in range(12)])
    fields = {"u": rng.random((n, 3)), "v": rng.random((n, 3)), "damage": rng.random(n)}
    st = {"u": rng.random((27, 3)), "von_mises": rng.random(12)}
    times = np.empty(frames)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.h5"
        t_all = time.perf_counter()
        with ResultsWriter(path, "[run]\n", expected_frames=frames if planned else 0) as w:
            w.add_ice_body("sheet", x0, volume=np.full(n, 1e-3))
            w.add_structure("panel", points, cells, "tetra")
            for k in range(frames):
                t0 = time.perf_counter()
                w.write_frame(1e-3 * (k + 1), {"sheet": fields}, structures={"panel": st})
                w.append_history("loads/panel", 1e-3 * (k + 1), {"force": st["u"][0]})
                times[k] = time.perf_counter() - t0
            rewrites = w._xdmf.rewrites
        total = time.perf_counter() - t_all
        xdmf_mb = path.with_suffix(".xdmf").stat().st_size / 1e6
        h5_mb = path.stat().st_size / 1e6
    early = times[100:100 + window]
    late = times[frames - window:]
    slow = int(np.argmax(times))
    return {"frames": frames, "particles": n, "window": window, "planned": planned,
            "early_mean_ms": round(1e3 * float(early.mean()), 3),
            "late_mean_ms": round(1e3 * float(late.mean()), 3),
            "ratio_mean": round(float(late.mean() / early.mean()), 3),
            "early_median_ms": round(1e3 * statistics.median(early), 3),
            "late_median_ms": round(1e3 * statistics.median(late), 3),
            "ratio_median": round(statistics.median(late) / statistics.median(early), 3),
            "xdmf_rewrites": rewrites, "slowest_ms": round(1e3 * float(times[slow]), 1),
            "slowest_frame": slow, "total_s": round(total, 1),
            "xdmf_mb": round(xdmf_mb, 1), "h5_mb": round(h5_mb, 1)}


if __name__ == "__main__":
    import json

    import sys

    print(json.dumps(bench_output_frames(planned="--unplanned" not in sys.argv)))
