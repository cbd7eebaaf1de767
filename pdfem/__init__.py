"""pdfem: ice loads on structures by peridynamics (ice) coupled with finite elements (structure).

All quantities are SI: metres, kilograms, seconds, newtons, pascals, joules.

The Python interface (docs/api.md, :mod:`pdfem.api`)::

    import pdfem
    case = pdfem.load_case("case.toml", overrides={"run.end_time": 2e-3})
    res = pdfem.run(case, out="results/short")     # the Results of the run
    res.loads["panel"]["force"]                     # (steps, 3) ice force on "panel", N

``load_case``, ``run``, ``open_results``, ``sweep``, ``collect``, ``Results`` and the errors
``InputError`` (bad input, exit 2 of the command line) and ``InstabilityError`` are loaded from
:mod:`pdfem.api` when first used (by name, so that ``import pdfem`` stays cheap and the package
root imports none of the layers that import it). ``pdfem.run`` is also the package
:mod:`pdfem.run` (its modules are ``pdfem.run.driver``, ...): calling it runs a case.

Threads: pdfem's parallel kernels (numba, OpenMP) alternate with serial work (the structure's
sparse products, the contact's bookkeeping) thousands of times per second of a coupled run.
OpenMP's default lets idle threads spin, and a spinning thread takes the core the serial work
needs: measured on the demo (2 cores), each contact search took 5 ms instead of 0.1 ms and the
run 84 s instead of 19 s. So the threads sleep when idle (``OMP_WAIT_POLICY=passive``) unless
the user set the policy; the peridynamic step's own throughput does not change (measured
399 vs 417 M pair-steps/s, ``pdfem bench step``).
"""

import importlib as _importlib
import os as _os
import types as _types

_os.environ.setdefault("OMP_WAIT_POLICY", "passive")

__version__ = "0.1.0"

_API = ("load_case", "open_results", "sweep", "collect", "Results", "History", "InputError",
        "InstabilityError")
"""Names of :mod:`pdfem.api` that ``pdfem.<name>`` gives (the errors are :mod:`pdfem.errors`')."""

__all__ = ["__version__", "run", *_API]


def __getattr__(name: str):
    if name in _API[-2:]:  # the errors alone: pdfem.errors is cheap, pdfem.api is not
        return getattr(_importlib.import_module("pdfem.errors"), name)
    if name in _API:
        return getattr(_importlib.import_module("pdfem.api"), name)
    raise AttributeError(f"module 'pdfem' has no attribute {name!r}")


class _RunPackage(_types.ModuleType):
    """The package :mod:`pdfem.run`, callable: ``pdfem.run(case, out=DIR)`` is
    :func:`pdfem.api.run`."""

    def __call__(self, case, out=None, **options):
        """Run a case in this process and return its results (:func:`pdfem.api.run`)."""
        return _importlib.import_module("pdfem.api").run(case, out, **options)


_importlib.import_module("pdfem.run").__class__ = _RunPackage
