"""Memory per rank of a run through the driver (``pdfem run``'s path), on a small ice box.

What ``benchmarks/memory_cli.py`` measures on 2 M particles (peak RSS per rank on 2 ranks at
0.56 of the serial run's), checked cheaply on 27,000 particles with the memory that Python and
numpy trace (``tracemalloc``: every array the set-up, the body, the output and the time loop
make; not the interpreter's and libraries' fixed cost, which at this size would hide the
arrays). The run is the one the user starts: the pre-flight estimate, the distributed set-up,
the regions, each rank writing its own particles (``output_per_rank``), the first frame, the
load-balance measure every step, frames. Every process first runs the case on a 6^3 box,
untraced, so that no kernel is compiled or loaded in the traced run. Default numba threads.

Three checks:

* each of 2 ranks peaks at most 0.6 times the serial run's traced peak (the issue's bound;
  measured 0.54; 0.81 when the load-balance measure made two int64 arrays of the rank's bond
  count every step);
* no process's traced memory rises in the time loop by more than 4 bytes per local bond above
  its level at the loop's start (measured 1.3; 16.4 with that measure);
* rank 0 keeps nothing of the whole body's size: at the loop's start it holds less than 16
  bytes per particle of the body more than rank 1, whose part is as large (measured 9: the
  history rows it buffers; 41 when it kept the whole body's reference positions and volumes
  for the run).
"""

from __future__ import annotations

import json
import textwrap

from support.mpi import run_script

CASE = """
[run]
end_time = 1.0e-5
output_interval = 5.0e-6
checkpoint_interval_minutes = 0
output_per_rank = true
[[ice]]
name = "box"
dx = 0.01
shape = { box = { min = [0.0, 0.0, 0.0], max = [0.30, 0.30, 0.30] } }
initial_velocity = [0.0, 0.0, -0.1]
fixed = [ { name = "bottom", box = { min = [-0.001, -0.001, -0.001], max = [0.301, 0.301, 0.006] } } ]
"""

SCRIPT = textwrap.dedent('''
    import json
    import sys
    import tracemalloc
    from pathlib import Path

    from pdfem.case.schema import load_case
    from pdfem.parallel.comm import world
    from pdfem.run import driver
    from pdfem.run.parallel import warm_before_ranks

    comm = world()
    warm_before_ranks(comm)
    case, out = load_case(sys.argv[1]), Path(sys.argv[3])
    driver.run_case(load_case(sys.argv[2]), out / "warm", quiet=True, comm=comm)  # kernels loaded
    seen = {}
    build, run_loop = driver.build, driver.run_loop

    def traced_build(*args, **kwargs):
        seen["setup"] = build(*args, **kwargs)
        return seen["setup"]

    def traced_loop(*args, **kwargs):
        seen["loop_start"], seen["setup_peak"] = tracemalloc.get_traced_memory()
        tracemalloc.reset_peak()
        result = run_loop(*args, **kwargs)
        seen["loop_peak"] = tracemalloc.get_traced_memory()[1]
        return result

    driver.build, driver.run_loop = traced_build, traced_loop
    tracemalloc.start()
    driver.run_case(case, out / "run", quiet=True, comm=comm)
    tracemalloc.stop()
    body = seen.pop("setup").bodies[0]
    figures = comm.gather(dict(seen, bonds=len(body.nbr), particles=body.n))
    if comm.rank == 0:
        print("MEMORY " + json.dumps(figures))
''')


def _figures(tmp_path, ranks: int) -> list[dict]:
    (tmp_path / "case.toml").write_text(CASE)
    (tmp_path / "warm.toml").write_text(CASE.replace("0.30", "0.06"))
    script = tmp_path / "trace.py"
    script.write_text(SCRIPT)
    r = run_script(script, ranks, tmp_path / "case.toml", tmp_path / "warm.toml",
                   tmp_path / f"r{ranks}", timeout=300)
    line = next(ln for ln in r.stdout.splitlines() if ln.startswith("MEMORY "))
    return json.loads(line[len("MEMORY "):])


def test_two_ranks_hold_at_most_0_6_of_the_serial_run_and_the_loop_grows_no_bond_array(
        tmp_path):
    serial, = _figures(tmp_path, 1)
    ranks = _figures(tmp_path, 2)
    whole = max(serial["setup_peak"], serial["loop_peak"])
    for r in ranks:
        assert max(r["setup_peak"], r["loop_peak"]) <= 0.6 * whole, (ranks, serial)
    for r in [serial, *ranks]:
        assert r["loop_peak"] - r["loop_start"] <= 4 * r["bonds"], (ranks, serial)
    assert ranks[0]["particles"] == ranks[1]["particles"]
    assert ranks[0]["loop_start"] - ranks[1]["loop_start"] <= 16 * serial["particles"], ranks
