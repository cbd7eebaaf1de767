"""The fracture dissipation of an ice body: the strain energy its bonds held when they broke.

A bond that breaks at positions y takes its share of the strain energy with it: the step's
fracture dissipation is W(y; bonds before) - W(y; bonds after) (J), both with the dilatation of
their own bond set, as :meth:`pdfem.pd.body.IceBody.strain_energy` takes it
(:func:`pdfem.pd.failure.fracture_kernels.released_energy` evaluates it for the particles that lost a
bond). Summed over the steps it is the body's ``fracture_dissipated``, an energy sink of its
own in the run's energy balance: strain before + work in = strain after + kinetic + fracture
dissipated (+ the integrator's error). That error is first order in dt at a breaking bond: the
bond pulls in the half kick before the position update but not in the one after it, and its
energy is taken at the step's end positions (past the critical stretch), so the balance is
off by about F dr / 2 per breaking bond (F its force, dr its extension in that step). A bar
torn apart at 0.8 of the stable step (tests/pd/test_fracture_energy.py): 8.8e-4 J of 1.05e-2 J
put in, 6.2e-3 J dissipated by fracture; half as much at half the step.

:class:`FractureLedger` remembers which bonds were already accounted (one bit per bond), so a
step's new broken bonds are found without touching the force kernels: only in the steps that
broke bonds, and only in the rows of the chunks that broke them. Bonds broken outside the time
loop (pre-cracks cut at set-up, bonds breaking in the initial force call of
:meth:`~pdfem.pd.body.IceBody.start`, a state restored from a checkpoint) are taken as they are
(:meth:`FractureLedger.forget`): they are no dissipation of the run.
"""

from __future__ import annotations

import numpy as np

from pdfem.pd.failure.fracture_kernels import first_rows, released_energy, seen_bits
from pdfem.pd.bonds.data import SIGNED, Particles

_ALL = np.zeros(0, dtype=np.bool_)  # "every particle is owned" (read-only by convention)


class FractureLedger:
    """The bonds of one body already accounted as broken, and the energy the next ones release.

    The body calls :meth:`prepare` before its force pass, :meth:`released` after a force pass
    that broke bonds, and :meth:`forget` whenever its broken flags are set from outside.
    """

    def __init__(self) -> None:
        self._seen: np.ndarray | None = None   # bit set over the pairs: accounted broken bonds
        self._first: np.ndarray | None = None  # (N,) first row holding a bond of each particle

    def forget(self) -> None:
        """Take the body's broken bonds as they are at the next :meth:`prepare` (no energy)."""
        self._seen = None

    def prepare(self, body) -> None:
        """Before a force pass: take the current broken bonds as accounted, if forgotten."""
        b = body.bonds
        if self._seen is None:
            self._seen = seen_bits(b.row_ptr, b.nbr, SIGNED, True, b.weight)
        if self._first is None:
            self._first = first_rows(b.row_ptr, b.nbr)

    def released(self, body, owned: np.ndarray = _ALL) -> tuple[float, int]:
        """Energy (J) released by the bonds the last force pass broke, over the ``owned``
        particles ((n,) bool; default all), and how many of those bonds lie in owned rows
        (each bond of a split body counted on one rank); they count as accounted from now on.

        ``body`` is an :class:`~pdfem.pd.body.IceBody` right after its force pass: the pair
        loop's chunks with broken bonds are those with a non-zero count in its workspace;
        after the full-family loop every row is searched.
        """
        b = body.bonds
        if body.family is None:
            cb, counts = body.workspace.chunk_ptr, body.workspace.counts
        else:
            cb, counts = np.array([0, body.n], dtype=np.int64), np.ones(1, dtype=np.int64)
        mat = body.material
        parts = Particles(body.y, body.vol, body.m, body.theta, body.f, body.nofail)
        energy, counted = released_energy(b, parts, float(mat.K), float(mat.mu), owned,
                                          self._seen, self._first, cb, counts)
        return float(energy), int(counted)
