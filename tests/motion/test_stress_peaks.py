"""The peak element von Mises stresses, overall and per part, evaluated part by part (and on
2 ranks, each rank its own parts) are those of the whole field.

Reference: Hooke's law and the von Mises stress of every element from the whole gradient
product (:func:`pdfem.fem.stress.hooke_stress`, :func:`pdfem.fem.stress.von_mises`) and
``numpy.argmax`` over all elements and over each part (the first element on a tie): the same
values and elements bit for bit, on one rank and on two.
"""

from __future__ import annotations

import textwrap

import numpy as np
import scipy.sparse as sp

from pdfem.fem.elasticity import ElasticMaterial
from pdfem.fem.stress import hooke_stress, von_mises
from pdfem.motion.stress_peaks import StressPeaks

from support.mpi import script_says

N_EL = 40
N_DOF = 60


def problem(seed: int = 0):
    """A random (9 Ne, n) gradient operator, a displacement, a material and parts: three
    blades of unequal size (one of them shuffled) and elements in no part."""
    rng = np.random.default_rng(seed)
    grad = sp.random(9 * N_EL, N_DOF, density=0.2, random_state=rng, format="csr")
    u = rng.standard_normal(N_DOF) * 1e-4
    perm = rng.permutation(N_EL)
    parts = [np.sort(perm[:12]), perm[12:20], np.sort(perm[20:35])]   # perm[35:]: no part
    return grad, u, ElasticMaterial(density=7600.0, youngs_modulus=120e9,
                                    poisson_ratio=0.32), parts


def reference(grad, u, material, parts):
    vm = von_mises(hooke_stress((grad @ u).reshape(3, 3, -1), material).transpose(2, 0, 1))
    i = int(np.argmax(vm))
    return (float(vm[i]), i), [(float(vm[p].max()), int(p[np.argmax(vm[p])])) for p in parts], vm


def test_peaks_part_by_part_are_the_whole_field_s():
    grad, u, material, parts = problem()
    overall, per_part = StressPeaks(grad, material, parts).peaks(u)
    ref_overall, ref_parts, _ = reference(grad, u, material, parts)
    assert overall == ref_overall and per_part == ref_parts


def test_a_non_finite_stress_is_the_peak_at_its_first_element():
    """A NaN displacement: the peak is NaN at the lowest-numbered element it reaches, as
    ``numpy.argmax`` takes it, also from a part that lists those elements backwards."""
    grad, u, material, _ = problem(2)
    u[7] = np.nan
    hit = np.unique(grad[:, 7].nonzero()[0] % N_EL)          # the elements the DOF reaches
    vm = reference(grad, u, material, [hit])[2]
    parts = [hit[::-1], np.setdiff1d(np.arange(N_EL), hit)]
    overall, per_part = StressPeaks(grad, material, parts).peaks(u)
    assert len(hit) > 2 and np.isnan(vm).sum() == len(hit)
    assert np.isnan(overall[0]) and overall[1] == int(np.argmax(vm)) == hit[0]
    assert np.isnan(per_part[0][0]) and per_part[0][1] == hit[0]


def test_a_tie_goes_to_the_first_element_and_a_part_of_none_is_everything():
    """Two parts whose elements have the same gradient rows (a symmetric propeller's blades):
    the overall peak is the lower-numbered element, as ``numpy.argmax`` takes it."""
    grad, u, material, _ = problem(1)
    rows = grad.tolil()
    for c in range(9):   # element 30 is a copy of element 5
        rows[c * N_EL + 30] = grad[c * N_EL + 5]
    grad = rows.tocsr()
    parts = [np.array([30, 31, 32]), np.array([5, 6, 7])]
    overall, per_part = StressPeaks(grad, material, parts).peaks(u)
    ref_overall, ref_parts, vm = reference(grad, u, material, parts)
    assert vm[5] == vm[30]
    assert overall == ref_overall and per_part == ref_parts
    whole, every = StressPeaks(grad, material, [None, parts[1]]).peaks(u)
    assert whole == ref_overall and every[0] == ref_overall


SCRIPT = textwrap.dedent('''
    import sys
    sys.path[:0] = [sys.argv[1], sys.argv[2]]
    from test_stress_peaks import problem
    from pdfem.motion.stress_peaks import StressPeaks
    from pdfem.parallel.comm import SerialComm, world
    comm = world()
    grad, u, material, parts = problem()
    split, serial = StressPeaks(grad, material, parts, comm), StressPeaks(grad, material, parts)
    assert split.peaks(u) == serial.peaks(u), "not the serial peaks"
    evaluated = comm.gather(split.dealt.mine)   # the parts whose stresses it evaluates
    # each part's report is made once, on the rank of the part, and reaches every rank
    made = []
    report = lambda k, peak: (made.append(k), (k, comm.rank, peak))[1]
    overall, peaks, reports = split.peaks_with(u, report)
    assert made == split.dealt.mine
    assert (overall, peaks) == serial.peaks(u)
    assert reports == [(k, int(split.dealt.owner[k]), peak) for k, peak in enumerate(peaks)]
    if comm.rank == 0:
        print("ok", evaluated)
''')


def test_two_ranks_evaluate_their_own_parts_and_agree_with_one_bit_for_bit(tmp_path):
    # the largest part (15 elements) to rank 0, the next (12) to rank 1, the last (8) to rank 1
    assert script_says(SCRIPT, 2, tmp_path, __file__) == "[[2], [0, 1]]"
