"""Same input, same output, whatever the state of numba's on-disk cache.

A small coupled case (an ice block striking a rigid sphere) is run twice in subprocesses that
share a fresh private numba cache (``NUMBA_CACHE_DIR`` in a tmp dir): the first run compiles
every kernel (cold cache), the second loads them from the cache (warm). Their results files
must be identical array by array, bit for bit.

This caught a real bug: a ``parallel=True`` kernel compiled with the fastmath flag
``contract`` ran different machine code in the process that compiled it (the parfor body as
optimized on its own) than in a process that loaded it from the cache (the copy of that body
linked into the kernel and optimized again), and the FMA contractions of the two differed
(see :mod:`pdfem.parallel.kernels`). The ice block has more than
:data:`pdfem.pd.bonds.workspace.SERIAL_BELOW_PAIRS` bonds and two numba threads are asked for, so
the threaded pair loops run.
"""

from __future__ import annotations

import pytest

import os
import subprocess
import sys
from pathlib import Path

from pdfem.benchmarks.compare_results import compare_files

CASE = """
[run]
title = "determinism: cold and warm numba cache"
end_time = 1.5e-4
output_interval = 5.0e-5
short_range_contact = false

[[ice]]
name = "block"
dx = 0.01
shape = { box = { min = [-0.06, -0.06, 0.0005], max = [0.06, 0.06, 0.1205] } }
material = { density = 900.0, youngs_modulus = 4.1e9, poisson_ratio = 0.3, fracture_energy = 1.0 }
initial_velocity = [0.0, 0.0, -2.0]

[[structure]]
name = "ball"
kind = "rigid"
mesh = "indenters"
params = { shape = "sphere", radius = 0.04, center_x = 0.0, center_y = 0.0, center_z = -0.04, element_size = 0.01 }
motion = { velocity = [0.0, 0.0, 0.0] }

[[contact]]
ice = "block"
structure = "ball"
friction = 0.1
"""

RUN = "import sys; from pdfem.cli.main import main; sys.exit(main(sys.argv[1:]))"


def _run(case: Path, out: Path, env: dict[str, str]) -> Path:
    proc = subprocess.run([sys.executable, "-c", RUN, "run", str(case), "--out", str(out),
                           "--quiet"], env=env, cwd=case.parent, capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return out / "results.h5"


@pytest.mark.slow
def test_cold_and_warm_numba_cache_give_identical_results(tmp_path):
    case = tmp_path / "block_on_sphere.toml"
    case.write_text(CASE)
    cache = tmp_path / "numba_cache"
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache), NUMBA_NUM_THREADS="2")
    cold = _run(case, tmp_path / "cold", env)
    assert any(cache.rglob("*.nbi")), "the first run wrote no numba cache"
    warm = _run(case, tmp_path / "warm", env)
    assert compare_files(cold, warm) == []
