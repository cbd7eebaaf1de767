"""How the numba kernels are built: on one or all threads, with fixed floating-point flags.

Every thread-parallel kernel also runs on one thread (:class:`Twin`, :func:`twin`): a parallel
region costs more than small work, so bodies below :data:`SERIAL_BELOW_PARTICLES` particles
run their per-particle passes on the calling thread. The pair loops of :mod:`pdfem.pd.bonds`,
the contact and drift passes of :mod:`pdfem.coupling`, the short-range contact of
:mod:`pdfem.forces` and the ice integrator share this machinery.

Same input, same output, whatever the state of numba's on-disk cache: :data:`FASTMATH` (the
flags of the hot loops) has no ``contract`` and no ``reassoc``, and the hot loops spell their
fused multiply-adds out with :func:`fma` (``llvm.fma.f64``: one rounding, and no optimization
pass may split, fuse or move it). With ``contract`` the LLVM backend fused a multiply and an
add wherever the shape of the optimized code allowed, and a ``parallel=True`` kernel does not
run the same code in the process that compiles it as in one that loads it from the cache: the
compiling process runs the parfor body as optimized on its own (its gufunc library, loaded
first, wins the symbol), while the cache holds the kernel's module, in which a copy of that
body was linked and optimized a second time. The two copies fused different pairs, so the first
run after a cache clear or a source change differed from later runs by round-off (the demo's
contact force by ~3e-6 N; found in :func:`pdfem.pd.bonds.pair_step_kernels.forces_pairs`). Without
``contract`` the hot loops were ~10 % slower; the explicit FMAs win that back.
``reassoc`` is left out as a value-changing rewrite of the same kind that gained nothing.
tests/run/test_determinism.py runs a coupled case with a cold and then a warm private cache.
"""

from __future__ import annotations

import types

import numba
from llvmlite import ir
from numba.core.types import float64 as _f8
from numba.core.types import int64 as _i8
from numba.extending import intrinsic

SERIAL_BELOW_PARTICLES = 20_000
"""Particles below which the per-particle kernels run on one thread: a parallel region costs
more than the work, and a lot more when the machine is oversubscribed (the threads wait at a
barrier for a descheduled peer)."""

SERIAL_BELOW_STREAMING = 65_536
"""Particles below which the streaming per-particle passes (a few loads and flops a particle:
the velocity-Verlet half kick and drift) run on one thread. Measured on the level-ice sheet,
28,350 particles, 2 threads, the machine shared (load 1.3): the half kick 36 us on one thread
against 56 us on two, the drift 37 against 57 us."""

FASTMATH = {"nsz", "arcp"}


@intrinsic
def fma(typingctx, a, b, c):
    """a * b + c with one rounding (``llvm.fma.f64``): an explicit fused multiply-add."""
    if (a, b, c) != (_f8, _f8, _f8):
        return None
    return _f8(_f8, _f8, _f8), lambda context, builder, sig, args: builder.fma(*args)


@intrinsic
def float_bits(typingctx, x):
    """The 64 bits of the double ``x`` as an int64 (sign, 11 exponent bits, 52 fraction bits)."""
    if x != _f8:
        return None
    return _i8(_f8), lambda context, builder, sig, args: builder.bitcast(args[0], ir.IntType(64))


class Twin:
    """A kernel compiled thread-parallel (``prange``) that also runs on one thread.

    Called as ``kernel(parallel, *args)``. With ``parallel`` false it runs on the calling
    thread, by one of two builds, fixed per kernel (``one_thread``):

    - ``"serial"``: a serial clone of the function (``prange`` = ``range``) under another
      qualified name, so both builds have their own on-disk cache entries. A call costs what a
      plain compiled function's does: the cheap per-particle loops (a half kick of 4,000
      particles: 6 us serial, 9 us as the parallel build on one thread) and the contact's
      narrow phase (the demo's 250 candidates: 112 against 176 us) run this way;
    - ``"parallel"``: the parallel build with numba's thread count set to 1 for the call. numba
      runs the body of a ``prange`` loop, compiled as its parallel-loop function, about twice as
      fast as the same loop in an ordinary compiled function for the ice law's row loop (its
      force pass on a 4,000-particle sheet: 1.0 against 2.05 ms; icebreaker_tiny's first 0.05 s:
      1.07 against 2.77 s), at about 3 us more per call: the force passes of a time step and
      the short-range search (0.38 against 0.46 s) run this way. Which build a kernel takes is
      measured, not guessed: the dilatation pass is a little faster serial (0.55 against
      0.62 s).
    """

    __slots__ = ("par", "ser")

    def __init__(self, pyfunc, fastmath, one_thread="serial"):
        if one_thread not in ("serial", "parallel"):
            raise ValueError(f"one_thread must be 'serial' or 'parallel', got {one_thread!r}")
        fm = FASTMATH if fastmath else False
        self.par = numba.njit(parallel=True, cache=True, fastmath=fm, error_model="numpy")(pyfunc)
        self.ser = None
        if one_thread == "serial":
            clone = types.FunctionType(pyfunc.__code__, pyfunc.__globals__,
                                       pyfunc.__name__ + "_serial", pyfunc.__defaults__,
                                       pyfunc.__closure__)
            clone.__qualname__ = pyfunc.__qualname__ + "_serial"
            clone.__doc__ = pyfunc.__doc__
            self.ser = numba.njit(cache=True, fastmath=fm, error_model="numpy")(clone)

    def __call__(self, parallel, *args):
        if parallel:
            return self.par(*args)
        if self.ser is not None:
            return self.ser(*args)
        threads = numba.get_num_threads()
        numba.set_num_threads(1)
        try:
            return self.par(*args)
        finally:
            numba.set_num_threads(threads)


def twin(fastmath: bool = True, one_thread: str = "serial"):
    """Decorator: compile a kernel as a :class:`Twin` (``fastmath`` uses ``FASTMATH``;
    ``one_thread``: which build runs a call on one thread)."""
    return lambda pyfunc: Twin(pyfunc, fastmath, one_thread)
