"""Benchmark of one ordinary state-based PD step: the pair loop against the full-family loop.

A cubic lattice of about ``n`` sea-ice particles (dx = 1 cm) with small random displacements;
a step is the dilatation followed by the forces with the bond-break check, as the time loop
runs them (:func:`pdfem.pd.bonds.kernels.dilatation_and_forces`, which keeps the bond lengths of the
dilatation pass for the force pass; the two separate calls and the fused call without the
bond-length scratch are timed as well). Bonds are stored as an ice body stores them: int32
partner, float64 length and a float32 weight whose sign marks a broken bond (16 bytes per pair,
:data:`pdfem.pd.bonds.kernels.SIGNED`). The figure of
merit is unique pair-steps per second (pairs P times steps over the seconds), the same numerator
for both loops, so the full-family loop (which visits every bond twice, the "original PD" of
Zhang et al. 2023) is charged for the work it actually has to do.
"""

from __future__ import annotations

import math
import os
import time

import numba
import numpy as np

from pdfem.pd.bonds import kernels as kn
from pdfem.pd.bonds.family import build_family
from pdfem.pd.failure.ice import IceFailure
from pdfem.pd.materials.lps import SEA_ICE_DEFAULTS, IceMaterial

ICE_LAW_COMPRESSIVE_STRENGTH = 3.0e6
"""sigma_c (Pa) of the "ice" law in the step benchmark (sea ice at ice-structure rates)."""


def _lattice(side: int, dx: float) -> np.ndarray:
    g = np.stack(np.meshgrid(*([np.arange(side)] * 3), indexing="ij"), -1).reshape(-1, 3)
    return (g + 0.5) * dx


def _pairs(x: np.ndarray, delta: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, str]:
    """Cell-sorted positions and their CSR pairs (pdfem's cell search, else scipy's cKDTree)."""
    try:
        from pdfem.pd.bonds.search import cell_pairs
    except ImportError:
        cell_pairs = None
    if cell_pairs is not None:
        perm, row_ptr, nbr = cell_pairs(x, delta)
        return np.ascontiguousarray(x[perm]), row_ptr, nbr, "cell_pairs"
    from scipy.spatial import cKDTree

    n = x.shape[0]
    p = cKDTree(x).query_pairs(delta, output_type="ndarray")
    p.sort(axis=1)
    p = p[np.lexsort((p[:, 1], p[:, 0]))]
    row_ptr = np.zeros(n + 1, np.int64)
    np.cumsum(np.bincount(p[:, 0], minlength=n), out=row_ptr[1:])
    return x, row_ptr, p[:, 1].astype(np.int32), "ckdtree"


def _bond_lengths(x, row_ptr, nbr):
    try:
        from pdfem.pd.bonds.geometry import bond_lengths
    except ImportError:
        i = np.repeat(np.arange(x.shape[0]), np.diff(row_ptr))
        return np.linalg.norm(x[nbr] - x[i], axis=1)
    return bond_lengths(x, row_ptr, nbr)


def _warm_up(horizon_factor: float) -> None:
    """Compile (or load from cache) every kernel the benchmark times, on a tiny block."""
    dx = 1.0
    x = _lattice(6, dx)
    x, row_ptr, nbr, _ = _pairs(x, horizon_factor * dx)
    xi = _bond_lengths(x, row_ptr, nbr)
    n = x.shape[0]
    vol = np.ones(n)
    ws = kn.PairWorkspace(row_ptr, nbr, n_chunks=max(2, numba.get_num_threads()))
    wt = kn.bond_weights(x, row_ptr, nbr, xi, horizon_factor * dx, dx, 1.0)
    m = kn.weighted_volume(row_ptr, nbr, xi, wt, vol, ws)
    th, f = np.empty(n), np.empty((n, 3))
    br, nf = np.zeros(len(nbr), np.uint8), np.zeros(n, np.uint8)
    rest = np.full(len(nbr), np.nan, dtype=np.float32)
    lim = (1.0, 0.0, -1.0, 0.0, -1.0, 0.0)
    kn.dilatation_and_forces(x, row_ptr, nbr, xi, wt, kn.SIGNED, vol, m, 1.0, 1.0, lim, nf, th, f,
                             ws, rest=rest, crush_yield=0.5)
    for b in (br, kn.SIGNED):
        kn.dilatation(x, row_ptr, nbr, xi, wt, b, vol, m, th, ws)
        kn.forces(x, row_ptr, nbr, xi, wt, b, vol, m, th, 1.0, 1.0, 1.0, nf, f, ws)
        kn.dilatation_and_forces(x, row_ptr, nbr, xi, wt, b, vol, m, 1.0, 1.0, 1.0, nf, th, f, ws)
        fam = build_family(row_ptr, nbr, n)
        kn.dilatation_family(x, *fam, xi, wt, b, vol, m, th)
        kn.forces_family(x, *fam, xi, wt, b, vol, m, th, 1.0, 1.0, 1.0, nf, f)


def _timed(step, broken, steps: int) -> tuple[float, float, int]:
    """Total and fastest seconds of ``steps`` calls of ``step(broken)`` after one untimed call
    (which touches the scratch memory and breaks the bonds the displacements break), and the
    bonds broken in all calls; ``broken`` is the signed weight array the step updates."""
    nbroken = step(broken)
    total, best = 0.0, math.inf
    for _ in range(steps):
        t0 = time.perf_counter()
        nbroken += step(broken)
        dt = time.perf_counter() - t0
        total += dt
        best = min(best, dt)
    return total, best, nbroken


def bench_step(n: int = 1_000_000, horizon_factor: float = 3.015, steps: int = 10,
               damage: bool = True) -> dict:
    """Time ``steps`` OSB steps with the pair loop and with the full-family loop.

    Parameters
    ----------
    n
        Approximate number of particles (a cube of ``round(n ** (1/3))`` per side).
    horizon_factor
        Horizon over lattice spacing.
    steps
        Steps timed per loop (after a compile warm-up on a tiny block and one untimed step
        on the full block).
    damage
        With True the break check is live: sea-ice critical stretch (G0 = 10 J/m^2) and random
        displacements of s0/3 dx, which break about 0.1 % of the bonds in the first step;
        with False ``s0 = inf`` and displacements of 1e-6 dx.

    Returns
    -------
    dict
        ``n_particles``, ``n_pairs``, ``threads``, ``step_s`` (seconds per pair-loop step),
        ``pair_steps_per_s`` (unique pairs x steps / s, pair loop),
        ``separate_step_s`` and ``separate_pair_steps_per_s`` (pair loop as two calls,
        :func:`~pdfem.pd.bonds.kernels.dilatation` then :func:`~pdfem.pd.bonds.kernels.forces`),
        ``full_family_step_s``, ``full_family_pair_steps_per_s`` (same numerator),
        ``speedup_pairs_vs_full_family``, ``pair_steps_per_s_best`` and
        ``full_family_pair_steps_per_s_best`` (from the fastest single step),
        ``lean_pair_steps_per_s`` and ``lean_pair_steps_per_s_best`` (fused step without the
        bond-length scratch), ``bytes_per_pair`` (stored per unique pair: partner, length,
        signed weight), ``scratch_bytes_per_pair`` (the bond-length scratch of the fused step),
        ``bonds_broken``, ``ice_law_step_s``, ``ice_law_pair_steps_per_s`` and
        ``ice_law_overhead`` (the fused step with the "ice" failure law and its crushed bonds,
        :mod:`pdfem.pd.failure.ice`, and its extra time over the critical-stretch step, as a
        fraction), ``max_force_difference`` (relative,
        pair vs full family after the last step), ``search`` (how the pairs were built),
        ``load_average`` and ``load_average_after`` (1-minute load before and after the
        timing: other work on the machine skews the figures), plus the inputs.
    """
    side = max(2, round(n ** (1.0 / 3.0)))
    dx = 0.01
    delta = horizon_factor * dx
    _warm_up(horizon_factor)

    x, row_ptr, nbr, how = _pairs(_lattice(side, dx), delta)
    xi = _bond_lengths(x, row_ptr, nbr)
    npart, npairs = x.shape[0], nbr.shape[0]
    d = SEA_ICE_DEFAULTS
    ice = IceMaterial(d["density"], d["youngs_modulus"], d["poisson_ratio"],
                      fracture_energy=d["fracture_energy"])
    K, mu = ice.K, ice.mu
    s0 = ice.s0(delta) if damage else math.inf
    amp = s0 / 3.0 if damage else 1e-6
    y = x + amp * dx * np.random.default_rng(0).standard_normal(x.shape)
    vol = np.full(npart, dx**3)
    nofail = np.zeros(npart, np.uint8)
    ws = kn.PairWorkspace(row_ptr, nbr)
    # bond weights of a cubic lattice body: influence function times partial-volume factor
    wt = kn.bond_weights(x, row_ptr, nbr, xi, delta, dx, kn.isotropy_gain(horizon_factor))
    m = kn.weighted_volume(row_ptr, nbr, xi, wt, vol, ws)
    theta = np.empty(npart)
    f_pair = np.empty((npart, 3))
    f_fam = np.empty((npart, 3))
    load = os.getloadavg()[0]

    ws_lean = kn.PairWorkspace(row_ptr, nbr, keep_bond_length=False)

    def pair_step(w):
        return kn.dilatation_and_forces(y, row_ptr, nbr, xi, w, kn.SIGNED, vol, m, K, mu, s0,
                                        nofail, theta, f_pair, ws)

    def lean_step(w):
        return kn.dilatation_and_forces(y, row_ptr, nbr, xi, w, kn.SIGNED, vol, m, K, mu, s0,
                                        nofail, theta, f_fam, ws_lean)

    def separate_step(w):
        kn.dilatation(y, row_ptr, nbr, xi, w, kn.SIGNED, vol, m, theta, ws)
        return kn.forces(y, row_ptr, nbr, xi, w, kn.SIGNED, vol, m, theta, K, mu, s0, nofail,
                         f_fam, ws)

    w_pair = wt.copy()
    t_pair, best_pair, nbroken = _timed(pair_step, w_pair, steps)
    t_lean, best_lean, _ = _timed(lean_step, wt.copy(), steps)
    t_sep, _, _ = _timed(separate_step, wt.copy(), steps)
    del ws, ws_lean

    # the "ice" failure law on the same displacements: stretch bounds in the bond's mean
    # dilatation, broken bonds kept as crushed bonds (one float32 per pair)
    law = IceFailure(ice.youngs_modulus * s0, ICE_LAW_COMPRESSIVE_STRENGTH, 30.0, K, mu)
    rest = np.full(npairs, np.nan, dtype=np.float32)
    ws_ice = kn.PairWorkspace(row_ptr, nbr)

    def ice_step(w):
        return kn.dilatation_and_forces(y, row_ptr, nbr, xi, w, kn.SIGNED, vol, m, K, mu,
                                        law.stretch_limits(), nofail, theta, f_fam, ws_ice,
                                        rest=rest, crush_yield=law.crush_yield)

    t_ice, best_ice, _ = _timed(ice_step, wt.copy(), steps)
    del ws_ice

    fam_ptr, fam_nbr, fam_bond = build_family(row_ptr, nbr, npart)
    coef = np.empty((npart, 2))

    def family_step(w):
        kn.dilatation_family(y, fam_ptr, fam_nbr, fam_bond, xi, w, kn.SIGNED, vol, m, theta)
        return kn.forces_family(y, fam_ptr, fam_nbr, fam_bond, xi, w, kn.SIGNED, vol, m, theta, K,
                                mu, s0, nofail, f_fam, coef)

    w_fam = wt.copy()
    t_fam, best_fam, nbroken_fam = _timed(family_step, w_fam, steps)
    if nbroken_fam != nbroken or not np.array_equal(w_pair < 0, w_fam < 0):
        raise RuntimeError("pair loop and full-family loop broke different bonds (a bug)")
    scale = float(np.abs(f_pair).max()) or 1.0
    return {
        "n_particles": int(npart),
        "n_pairs": int(npairs),
        "threads": int(numba.get_num_threads()),
        "horizon_factor": float(horizon_factor),
        "steps": int(steps),
        "damage": bool(damage),
        "search": how,
        "step_s": t_pair / steps,
        "pair_steps_per_s": npairs * steps / t_pair,
        "pair_steps_per_s_best": npairs / best_pair,
        "full_family_pair_steps_per_s_best": npairs / best_fam,
        "full_family_step_s": t_fam / steps,
        "full_family_pair_steps_per_s": npairs * steps / t_fam,
        "speedup_pairs_vs_full_family": t_fam / t_pair,
        "lean_pair_steps_per_s": npairs * steps / t_lean,
        "lean_pair_steps_per_s_best": npairs / best_lean,
        "bytes_per_pair": int(nbr.itemsize + xi.itemsize + wt.itemsize),
        "scratch_bytes_per_pair": 8,
        "separate_step_s": t_sep / steps,
        "separate_pair_steps_per_s": npairs * steps / t_sep,
        "bonds_broken": int(nbroken),
        "ice_law_step_s": t_ice / steps,
        "ice_law_pair_steps_per_s": npairs * steps / t_ice,
        "ice_law_overhead": t_ice / t_pair - 1.0,
        "max_force_difference": float(np.abs(f_pair - f_fam).max() / scale),
        "load_average": float(load),
        "load_average_after": float(os.getloadavg()[0]),
    }
