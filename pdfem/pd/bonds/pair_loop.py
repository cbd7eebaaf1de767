"""The pair-loop LPS kernels' public API: argument checks and calls of the numba loops.

The 3-D linear peridynamic solid (LPS, Silling et al. 2007) over unique bonds. The numba loops
live in :mod:`pdfem.pd.bonds.pair_step_kernels` (dilatation and forces of a step) and
:mod:`pdfem.pd.bonds.pair_sum_kernels` (family sums, energy, damage); the per-bond physics in
:mod:`pdfem.pd.bonds.lps_law`.

Data layout (shared with the rest of pdfem):

- ``y`` (N, 3) float64 current positions (m); ``vol`` (N,) float64 particle volumes (m^3);
- unique bonds i < j grouped by i (CSR, the "particle-pair method"): ``row_ptr`` int64 (N+1,),
  ``nbr`` int32 (P,); bond k joins i and ``nbr[k]`` for k in ``row_ptr[i]:row_ptr[i+1]``;
- ``xi_len`` (P,) float64 reference bond lengths (m);
- ``weight`` (P,) float32 bond weights omega = w beta, the influence function times the
  partial-volume factor (:mod:`pdfem.pd.bonds.influence`);
- ``broken`` (P,) uint8, 1 = broken for good; or :data:`SIGNED` (an empty array), which says
  that a bond is broken when its weight is negative (the bond-break check then negates the
  weight): that is how :class:`pdfem.pd.body.IceBody` stores its bonds, 16 bytes per pair
  (int32 partner, float64 length, float32 signed weight) instead of 17;
- ``nofail`` (N,) uint8, 1 = bonds touching this particle never break.

Per particle i with family j (e = |y_j - y_i| - |xi|, every family sum weighs member j by
``omega V_j``)::

    m_i     = sum_j omega |xi|^2 V_j                       (all initial bonds)
    theta_i = (3 / m_i) sum_j omega |xi| e V_j             (unbroken bonds)
    t_ij    = (3 K theta_i / m_i) |xi| + (15 mu / m_i) e_d,   e_d = e - theta_i |xi| / 3
    L_i     = sum_j (t_ij + t_ji) omega V_j (y_j - y_i) / |y_j - y_i|   (force density, N/m^3)
    W_i     = K theta_i^2 / 2 + (15 mu / (2 m_i)) sum_j omega e_d^2 V_j (energy density, J/m^3)

so that the total strain energy sum_i W_i V_i has gradient -V_i L_i with respect to y_i.

A step computes the dilatation first, then forces with the break check: bond k breaks when its
stretch e / |xi| leaves the failure law's bounds (above ``s0``, the critical stretch; a law may
also bound it below, :mod:`pdfem.pd.bonds.lps_law`) and neither end has ``nofail``; a bond breaking in the force
call contributes no force there and is marked broken (the dilatation of the same step still
used it). Damage is the broken fraction of a particle's initial bonds.

The loops are chunked for race-free, deterministic threading (:mod:`pdfem.pd.bonds.workspace`).
:func:`dilatation_and_forces` is the time loop's entry point: the two passes of a step, with
the bond lengths of the first pass kept for the second (8 bytes per pair of scratch).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from pdfem.pd.bonds.data import SIGNED, Bonds, LawArrays, Particles  # noqa: F401 (SIGNED: API)
from pdfem.pd.failure.crushed_shear import shear_kernel_args
from pdfem.pd.bonds.lps_law import force_coefficients, stretch_limits
from pdfem.pd.bonds.pair_step_kernels import dilatation_pairs, forces_pairs, forces_pairs_law
from pdfem.pd.bonds.pair_sum_kernels import family_sum_pairs
from pdfem.pd.bonds.workspace import c_contiguous, workspace_for

if TYPE_CHECKING:
    from pdfem.pd.failure.crushed_shear import CrushedShear
    from pdfem.pd.bonds.workspace import PairWorkspace

_NO_R = np.zeros(0)  # stands for "no bond-length buffer" (read-only by convention)
_NO_REST = np.zeros(0, dtype=np.float32)  # "broken bonds never push" (read-only by convention)
_ALL_ROWS = np.zeros(0, dtype=np.uint8)  # "every row's crushing energy counts" (read-only)
UNIT_STRENGTH = np.zeros(0)  # "every particle's strength factor is 1" (read-only by convention)
INTACT = np.zeros(0)  # "m' = m: no broken bond" (read-only by convention)


def rest_arg(rest: np.ndarray | None, per_pair: np.ndarray) -> tuple[np.ndarray, bool]:
    """(array, granular) for the force kernels: ``rest`` checked, or the empty default."""
    if rest is None:
        return _NO_REST, False
    if rest.dtype != np.float32 or rest.shape != per_pair.shape or not rest.flags.c_contiguous:
        raise ValueError(f"rest must be a C-contiguous float32 array of shape {per_pair.shape}")
    return rest, True

_NO_F = np.zeros((0, 3))  # "no force output" (the dilatation pass)
_NO_FLAGS = np.zeros(0, dtype=np.uint8)  # "no no-fail flags" (the dilatation pass)


def bond_tuple(row_ptr, nbr, xi_len, weight, broken) -> Bonds:
    """The kernels' :class:`~pdfem.pd.bonds.data.Bonds`, checked (``broken``: uint8 flags or
    :data:`SIGNED`)."""
    check_broken(broken, nbr)
    return Bonds(row_ptr, nbr, xi_len, check_weight(weight, nbr), broken)


def particle_tuple(y, vol, m, theta, f=_NO_F, nofail=_NO_FLAGS) -> Particles:
    """The kernels' :class:`~pdfem.pd.bonds.data.Particles` (``y``, ``f`` C-contiguous)."""
    return Particles(c_contiguous(y, "y"), vol, m, theta, c_contiguous(f, "f_out"), nofail)


def plain_law(s0, granular: bool) -> bool:
    """Whether the failure test is a plain critical stretch without crushed bonds: then the
    plain force kernel (:func:`~pdfem.pd.bonds.pair_step_kernels.forces_pairs`) runs."""
    lim = stretch_limits(s0)
    return (not granular and lim[1] == 0.0 and lim[2] == -np.inf and lim[3] == 0.0
            and lim[4] == -np.inf and lim[5] == 0.0)


def _force_pass(ws, bonds, P, s0, rbuf, use_r, rest, granular, crush_yield, owned,
                shear) -> int:
    """The force pass after :func:`~pdfem.pd.bonds.lps_law.force_coefficients`: the plain
    critical-stretch kernel, or the general one for other laws (compiled only when used)."""
    if plain_law(s0, granular):
        return int(forces_pairs(ws.parallel, bonds, P, ws.blocks, ws.coef,
                                float(stretch_limits(s0)[0]), rbuf, use_r))
    slip, y0, params = shear_kernel_args(shear)
    law = LawArrays(ws.coef, ws.aux, stretch_limits(s0), float(crush_yield), rest, owned,
                    ws.crush, slip, y0, params)
    return int(forces_pairs_law(ws.parallel, bonds, P, ws.blocks, law, rbuf, use_r, granular))


def check_broken(broken: np.ndarray, per_pair: np.ndarray) -> bool:
    """True if ``broken`` is :data:`SIGNED` (broken = negative weight); False for a (P,) uint8
    flag array shaped like ``per_pair``; ValueError otherwise."""
    if not isinstance(broken, np.ndarray) or broken.dtype != np.uint8:
        raise ValueError("broken must be a uint8 array (or pdfem.pd.bonds.pair_loop.SIGNED)")
    if broken.shape[0] == 0 and per_pair.shape[0] != 0:
        return True
    if broken.shape != per_pair.shape:
        raise ValueError(f"broken must have one flag per pair (shape {per_pair.shape}), "
                         f"got {broken.shape}")
    return False


def signed_weights(weight: np.ndarray, broken: np.ndarray) -> np.ndarray:
    """float32 weights with the broken bonds (``broken`` != 0) negated: the :data:`SIGNED` form."""
    out = np.abs(np.asarray(weight, dtype=np.float32))
    np.negative(out, out=out, where=np.asarray(broken) != 0)
    return out


def broken_flags(weight: np.ndarray) -> np.ndarray:
    """(P,) uint8 broken flags (1 where the weight is negative) of :data:`SIGNED` weights."""
    return (np.asarray(weight) < 0).view(np.uint8)


def check_weight(weight: np.ndarray, per_pair: np.ndarray) -> np.ndarray:
    """``weight`` itself if it is a C-contiguous float32 array shaped like ``per_pair`` (P,)."""
    if (not isinstance(weight, np.ndarray) or weight.dtype != np.float32
            or weight.shape != per_pair.shape or not weight.flags.c_contiguous):
        raise ValueError(
            "weight must be a C-contiguous float32 array with one bond weight per pair "
            f"(shape {per_pair.shape}); build it with pdfem.pd.bonds.influence.bond_weights"
        )
    return weight


# --------------------------------------------------------------------------- public API


def family_sum(
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    weight: np.ndarray,
    values: np.ndarray,
    mode: int,
    ws: PairWorkspace | None = None,
) -> np.ndarray:
    """Family sums over all initial bonds: out_i = sum_j g(|xi|) omega values_j (both ends).

    Parameters
    ----------
    row_ptr, nbr, xi_len, weight
        Pair list, reference bond lengths (m) and bond weights (float32).
    values
        (N,) float64 per-particle values (volumes, or volumes times a factor).
    mode
        g = |xi|^2, 1/|xi|, |xi|, 1 for mode 0, 1, 2, 3.
    ws
        Optional :class:`PairWorkspace` for this pair list.

    Returns
    -------
    ndarray
        (N,) float64 sums.
    """
    ws = workspace_for(ws, row_ptr, nbr)
    out = np.empty(ws.n)
    family_sum_pairs(ws.parallel, Bonds(row_ptr, nbr, xi_len, check_weight(weight, nbr)),
                     np.ascontiguousarray(values, np.float64), int(mode), ws.blocks, out)
    return out


def weighted_volume(
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    weight: np.ndarray,
    vol: np.ndarray,
    ws: PairWorkspace | None = None,
) -> np.ndarray:
    """Weighted volume m_i = sum_j omega |xi|^2 V_j over all initial bonds.

    Parameters
    ----------
    row_ptr, nbr
        CSR unique pairs i < j (int64 (N+1,), int32 (P,)).
    xi_len
        (P,) reference bond lengths (m).
    weight
        (P,) float32 bond weights omega (:func:`pdfem.pd.bonds.influence.bond_weights`).
    vol
        (N,) particle volumes (m^3).
    ws
        Optional :class:`PairWorkspace` for this pair list.

    Returns
    -------
    ndarray
        (N,) float64 weighted volume (m^5).
    """
    return family_sum(row_ptr, nbr, xi_len, weight, vol, 0, ws)


def dilatation(
    y: np.ndarray,
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    weight: np.ndarray,
    broken: np.ndarray,
    vol: np.ndarray,
    m: np.ndarray,
    theta_out: np.ndarray,
    ws: PairWorkspace | None = None,
) -> None:
    """Dilatation theta_i = (3 / m_i) sum_j omega |xi| e V_j over unbroken bonds (pair loop).

    Parameters
    ----------
    y
        (N, 3) current positions (m).
    row_ptr, nbr, xi_len, weight, broken
        Pair list, reference lengths (m), bond weights (float32) and broken flags (uint8, or
        :data:`SIGNED`: broken = negative weight).
    vol, m
        (N,) volumes (m^3) and weighted volumes (m^5, :func:`weighted_volume`).
    theta_out
        (N,) float64, overwritten with the dilatation (dimensionless); 0 where m = 0.
    ws
        Optional :class:`PairWorkspace` for this pair list.
    """
    ws = workspace_for(ws, row_ptr, nbr)
    bonds = bond_tuple(row_ptr, nbr, xi_len, weight, broken)
    dilatation_pairs(ws.parallel, bonds, particle_tuple(y, vol, m, theta_out), ws.blocks, _NO_R,
                     False)


def forces(
    y: np.ndarray,
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    weight: np.ndarray,
    broken: np.ndarray,
    vol: np.ndarray,
    m: np.ndarray,
    theta: np.ndarray,
    K: float,
    mu: float,
    s0: float,
    nofail: np.ndarray,
    f_out: np.ndarray,
    ws: PairWorkspace | None = None,
    rest: np.ndarray | None = None,
    crush_yield: float = np.inf,
    owned: np.ndarray | None = None,
    strength: np.ndarray | None = None,
    m_now: np.ndarray | None = None,
    shear: CrushedShear | None = None,
) -> int:
    """LPS force density with the bond-break check (pair loop).

    A bond with stretch ``e / |xi|`` outside the bounds ``s0`` whose ends both lack ``nofail`` breaks here: it is
    marked in ``broken`` and contributes no force. Already broken bonds are skipped.

    Parameters
    ----------
    y
        (N, 3) current positions (m).
    row_ptr, nbr, xi_len, weight
        Pair list, reference bond lengths (m) and bond weights (float32).
    broken
        (P,) uint8, updated in place; or :data:`SIGNED`, and then a bond that breaks gets its
        ``weight`` negated in place.
    vol, m, theta
        (N,) volumes (m^3), weighted volumes (m^5) and dilatations of this step.
    K, mu
        Bulk and shear modulus (Pa).
    s0
        Critical stretch (``inf``: no breaking), or the six stretch-bound coefficients
        (t0, t1, c0, c1, d0, d1) of a failure law: a bond breaks when its stretch is above
        t0 + t1 theta or below min(c0 + c1 theta, d0 + d1 theta), theta its ends' mean
        dilatation (:mod:`pdfem.pd.bonds.lps_law`).
    nofail
        (N,) uint8, 1 = the particle's bonds never break.
    f_out
        (N, 3) float64, overwritten with the force density L_i (N/m^3).
    ws
        Optional :class:`PairWorkspace` for this pair list.
    rest
        Optional (P,) float32, NaN where unset: with it, broken bonds are crushed bonds,
        compression-only elastic-plastic springs with plastic rest length |xi| (1 + rest)
        (:func:`pdfem.pd.bonds.lps_law.crushed_bond`), which a bond breaking here becomes.
    crush_yield
        The crushed bonds' yield compression (stretch, > 0).
    owned
        Optional (N,) uint8: the rows whose crushed bonds' dissipation counts (default all).
        The energy they dissipated in this call (J) is left in ``ws.crush_dissipated``.
    strength
        Optional (N,) float64 factors on the compressive strength (the constant parts c0, d0 of
        the lower bound; a bond takes its ends' mean), e.g. a strain-rate dependence; default 1.
    m_now
        Optional (N,) weighted volume of each particle's intact bonds (m^5,
        :class:`pdfem.pd.failure.damaged_volume.IntactVolume`): with broken bonds the force is
        then the exact gradient of the strain energy; default m (as if none were broken).
    shear
        Optional shear springs of the crushed bonds (:class:`pdfem.pd.failure.crushed_shear.
        CrushedShear`), advanced if a step is under way; their force is in ``f_out`` and the
        energy lost by slipping in ``ws.crush_dissipated``.

    Returns
    -------
    int
        Number of bonds broken in this call.
    """
    ws = workspace_for(ws, row_ptr, nbr)
    rest, granular = rest_arg(rest, nbr)
    owned = _ALL_ROWS if owned is None else owned
    force_coefficients(ws.parallel_particles, m, INTACT if m_now is None else m_now, theta, K,
                       mu, UNIT_STRENGTH if strength is None else strength, ws.coef, ws.aux)
    nb = _force_pass(ws, bond_tuple(row_ptr, nbr, xi_len, weight, broken),
                     particle_tuple(y, vol, m, theta, f_out, nofail), s0, _NO_R, False, rest,
                     granular, crush_yield, owned, shear)
    ws.crush_dissipated = float(np.sum(ws.crush)) if granular else 0.0
    return nb


def dilatation_and_forces(
    y: np.ndarray,
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    weight: np.ndarray,
    broken: np.ndarray,
    vol: np.ndarray,
    m: np.ndarray,
    K: float,
    mu: float,
    s0: float,
    nofail: np.ndarray,
    theta_out: np.ndarray,
    f_out: np.ndarray,
    ws: PairWorkspace,
    between=None,
    rest: np.ndarray | None = None,
    crush_yield: float = np.inf,
    owned: np.ndarray | None = None,
    strength: np.ndarray | None = None,
    m_now: np.ndarray | None = None,
    shear: CrushedShear | None = None,
) -> int:
    """One OSB step's internal forces: :func:`dilatation`, then :func:`forces` (pair loops).

    Bit-identical to the two calls, but faster: the dilatation pass stores every unbroken
    bond's current length in the workspace (``ws.bond_length``, float64 (P,), allocated on first
    use: 8 bytes per pair) and the force pass reads it instead of taking a second square root
    (about 30 % of the force pass); so can the strain energy at the same positions
    (``ws.lengths_current``). A workspace built with ``keep_bond_length=False`` skips that
    buffer (for the largest bodies, where memory counts more) and takes the square root twice.

    Parameters are those of :func:`dilatation` and :func:`forces`; ``theta_out`` (N,) and
    ``f_out`` (N, 3) are overwritten; ``ws`` is required. ``between``, if given, is called with
    ``theta_out`` between the two passes (an MPI rank's body exchanges its halo's dilatations
    there). ``rest``, ``crush_yield``, ``owned``, ``strength``, ``m_now``, ``shear``: as in
    :func:`forces`.

    Returns
    -------
    int
        Number of bonds broken in this call.
    """
    ws.check(row_ptr, nbr)
    rbuf = ws.bond_length_buffer() if ws.keep_bond_length else _NO_R
    keep = rbuf.shape[0] > 0
    bonds = bond_tuple(row_ptr, nbr, xi_len, weight, broken)
    rest, granular = rest_arg(rest, nbr)
    owned = _ALL_ROWS if owned is None else owned
    P = particle_tuple(y, vol, m, theta_out, f_out, nofail)
    dilatation_pairs(ws.parallel, bonds, P, ws.blocks, rbuf, keep)
    if between is not None:
        between(theta_out)
    force_coefficients(ws.parallel_particles, m, INTACT if m_now is None else m_now, theta_out,
                       K, mu, UNIT_STRENGTH if strength is None else strength, ws.coef, ws.aux)
    nb = _force_pass(ws, bonds, P, s0, rbuf, keep, rest, granular, crush_yield, owned, shear)
    ws.crush_dissipated = float(np.sum(ws.crush)) if granular else 0.0
    ws.lengths_current = keep
    return nb
