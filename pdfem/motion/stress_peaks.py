"""The largest element von Mises stress of a structure and of each of its parts (a propeller's
blades), every coupling step, each part's elements evaluated once over the ranks.

A rotating structure reports every step the peak von Mises stress over all its elements and over
each blade (:mod:`pdfem.motion.shaft_loads`). The stress at an element's centre is one sparse
product of the displacement (:func:`pdfem.motion.shaft_loads.gradient_operator`) and Hooke's
law, element by element. :class:`StressPeaks` keeps that product split by part: with a
communicator of several ranks the parts are dealt out by their element counts
(:class:`pdfem.parallel.deal.Dealt`), each rank evaluates its own parts' elements, and the
parts' peaks (value and element) are shared, with anything else the caller makes of each part
there (:meth:`StressPeaks.peaks_with`: a blade's row of the shaft loads). The elements in no
part are evaluated on every rank. The peaks are those of the whole field bit for bit: each
element's stress is the same arithmetic on any rank (its own row of the product, element-wise
operations after it), and the overall peak is the largest of the parts' peaks, the first element
on a tie, as ``numpy.argmax`` over all elements picks it. Stresses in Pa.
"""

from __future__ import annotations

from typing import Callable, Sequence

import numpy as np
import scipy.sparse as sp

from pdfem.fem.stress import hooke_stress, von_mises
from pdfem.parallel.comm import SerialComm
from pdfem.parallel.deal import Dealt


def _rows_of(elements: np.ndarray, n_elements: int) -> np.ndarray:
    """The rows of a (9 Ne, n) gradient operator that hold the elements ``elements``, in the
    operator's order (component by component)."""
    return (np.arange(9)[:, None] * n_elements + elements[None, :]).ravel()


def _peak(vm: np.ndarray, elements: np.ndarray) -> tuple[float, int]:
    """The largest of ``vm`` (the values of ``elements``, in that order) and its element (the
    first on a tie, as ``numpy.argmax``); ``(-inf, -1)`` for no elements."""
    if len(elements) == 0:
        return -np.inf, -1
    i = int(np.argmax(vm))
    return float(vm[i]), int(elements[i])


def _largest(peaks: Sequence[tuple[float, int]]) -> tuple[float, int]:
    """The largest of several ``(value, element)`` peaks, the smallest element on a tie (a NaN
    counts as the largest, as ``numpy.argmax`` takes it)."""
    return min(peaks, key=lambda p: (not np.isnan(p[0]), -p[0] if not np.isnan(p[0]) else 0.0,
                                     p[1]))


class StressPeaks:
    """Peak element von Mises stresses, overall and per part (module docstring).

    Parameters
    ----------
    grad
        (9 Ne, n) the displacement gradient at the element centres (row ``(3 i + j) Ne + e``).
    material
        The elastic material (Hooke's law).
    parts
        The elements of each part (int arrays); a part given as None is every element.
    comm
        The ranks that share the parts (:mod:`pdfem.parallel.comm`); default one process.
    """

    def __init__(self, grad: sp.csr_matrix, material, parts: Sequence[np.ndarray | None],
                 comm=SerialComm()) -> None:
        self.material = material
        n_el = grad.shape[0] // 9
        self._whole = any(p is None for p in parts)
        # ascending: a part's first peak is then its smallest element, as argmax over all
        self.parts = [np.arange(n_el) if p is None else np.unique(np.asarray(p, dtype=np.int64))
                      for p in parts]
        covered = np.zeros(n_el, dtype=bool)
        for p in self.parts:
            covered[p] = True
        self.rest = np.flatnonzero(~covered)
        # each part's rows of the operator, and those of the elements in no part
        self._grads = [sp.csr_matrix(grad[_rows_of(p, n_el)]) for p in self.parts]
        self._rest_grad = sp.csr_matrix(grad[_rows_of(self.rest, n_el)])
        self.distribute(comm)

    def distribute(self, comm) -> None:
        """Deal the parts out over the ranks of ``comm`` (a part that is every element is not
        dealt: then every rank evaluates all). Collective from then on."""
        self.dealt = Dealt([len(p) for p in self.parts],
                           SerialComm() if self._whole else comm)

    def _von_mises(self, grad: sp.csr_matrix, u: np.ndarray) -> np.ndarray:
        g = (grad @ u).reshape(3, 3, -1)
        return von_mises(hooke_stress(g, self.material).transpose(2, 0, 1))

    def peaks(self, u: np.ndarray) -> tuple[tuple[float, int], list[tuple[float, int]]]:
        """The peak over all elements and that of each part, as ``(von Mises stress (Pa),
        element)``, of the displacement ``u`` (m). Collective when the parts are dealt out."""
        overall, parts, _ = self.peaks_with(u)
        return overall, parts

    def peaks_with(self, u: np.ndarray, report: Callable[[int, tuple[float, int]], object]
                   | None = None) -> tuple[tuple[float, int], list[tuple[float, int]], list]:
        """:meth:`peaks`, and each part's ``report(k, peak)`` made on the rank that evaluates
        part ``k`` and shared with its peak (None without ``report``): the overall peak, the
        parts' peaks and their reports, in part order. Collective when the parts are dealt
        out."""
        mine = []
        for k in self.dealt.mine:
            peak = _peak(self._von_mises(self._grads[k], u), self.parts[k])
            mine.append((peak, None if report is None else report(k, peak)))
        every = [part for _, part in sorted(self.dealt.everyone(mine), key=lambda kp: kp[0])]
        parts = [peak for peak, _ in every]
        rest = _peak(self._von_mises(self._rest_grad, u), self.rest)
        return _largest(parts + [rest]), parts, [r for _, r in every]
