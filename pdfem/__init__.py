"""pdfem: ice loads on structures by peridynamics (ice) coupled with finite elements (structure).

All quantities are SI: metres, kilograms, seconds, newtons, pascals, joules.

Threads: pdfem's parallel kernels (numba, OpenMP) alternate with serial work (the structure's
sparse products, the contact's bookkeeping) thousands of times per second of a coupled run.
OpenMP's default lets idle threads spin, and a spinning thread takes the core the serial work
needs: measured on the demo (2 cores), each contact search took 5 ms instead of 0.1 ms and the
run 84 s instead of 19 s. So the threads sleep when idle (``OMP_WAIT_POLICY=passive``) unless
the user set the policy; the peridynamic step's own throughput does not change (measured
399 vs 417 M pair-steps/s, ``pdfem bench step``).
"""

import os as _os

_os.environ.setdefault("OMP_WAIT_POLICY", "passive")

__version__ = "0.1.0"
