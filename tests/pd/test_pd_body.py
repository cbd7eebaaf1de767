"""Tests of pdfem.pd.body (IceBody) and pdfem.pd.bonds.surface: bond weights, fused step, stable step.

Each test names its reference in the docstring.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from pdfem.pd.bonds import kernels as kn
from pdfem.pd.body import IceBody
from pdfem.pd.bonds.influence import bond_weights, isotropy_gain, partial_volume_factor
from pdfem.geometry.lattice import fill
from pdfem.pd.materials.lps import IceMaterial
from pdfem.geometry.shapes import Box

DX = 0.01
E, RHO = 4.0e9, 900.0
ICE = IceMaterial(density=RHO, youngs_modulus=E, poisson_ratio=0.3)


def block(nx, ny, nz, material=ICE, **kw) -> IceBody:
    return IceBody.from_shape("b", Box((0.0, 0.0, 0.0), (nx * DX, ny * DX, nz * DX)), material,
                              DX, 3.015 * DX, **kw)


def second_moments(b: IceBody) -> np.ndarray:
    """(N, 3, 3) sum_j omega |xi|^2 n n V_j per particle, by numpy from the pair list."""
    i = np.repeat(np.arange(b.n), np.diff(b.row_ptr))
    j = b.nbr.astype(np.int64)
    xi = b.x0[j] - b.x0[i]
    c = b.weight.astype(np.float64)[:, None, None] * np.einsum("pa,pb->pab", xi, xi)
    M2 = np.zeros((b.n, 3, 3))
    np.add.at(M2, i, c * b.vol[j, None, None])
    np.add.at(M2, j, c * b.vol[i, None, None])
    return M2


def anisotropy(M2: np.ndarray) -> np.ndarray:
    """max |3 M2 / tr M2 - I| per particle."""
    m = np.trace(M2, axis1=1, axis2=2)
    return np.abs(3 * M2 / m[:, None, None] - np.eye(3)).max(axis=(1, 2))


def test_from_points_keeps_w_equal_one_and_from_shape_weighs_the_lattice():
    """Reference: the definitions. From a point cloud the bond weight is the partial-volume
    factor alone (w = 1); from a shape (a cubic lattice) it includes the cubic influence
    function; both give m = sum omega |xi|^2 V (numpy)."""
    x = fill(Box((0, 0, 0), (8 * DX, 8 * DX, 8 * DX)), DX)
    plain = IceBody.from_points("p", x, ICE, DX, 3.015 * DX)
    assert plain.influence_gain == 0.0
    np.testing.assert_array_equal(
        plain.weight, partial_volume_factor(plain.xi_len, plain.delta, DX).astype(np.float32))
    lat = block(8, 8, 8, surface_correction=False)
    assert lat.influence_gain == isotropy_gain(3.015)
    np.testing.assert_array_equal(
        lat.weight, bond_weights(lat.x0, lat.row_ptr, lat.nbr, lat.xi_len, lat.delta, DX,
                                 isotropy_gain(3.015)))
    m = np.trace(second_moments(lat), axis1=1, axis2=2)
    np.testing.assert_allclose(lat.m, m, rtol=1e-12)


def test_surface_correction_makes_face_families_isotropic():
    """Reference: the LPS dilatation is exact under uniform strain iff the family's second
    moment sum omega |xi|^2 n n V is (m/3) I (numpy moments). Truncated families at faces
    miss that by up to 0.23 without the correction and meet it to 5e-3 with it; edges and
    corners cannot be made isotropic with positive weights and stay bounded; the weights stay
    within the clip bounds (1/2 to 2 times the uncorrected ones)."""
    raw = block(12, 12, 12, surface_correction=False)
    cor = block(12, 12, 12)
    x = cor.x0 / DX
    depth = np.minimum(x, 12 - x)  # distance to each pair of faces, in dx
    near = (depth < 3.1).sum(axis=1)
    face = near == 1  # near exactly one face: not an edge or corner
    bulk = near == 0
    a_raw, a_cor = anisotropy(second_moments(raw)), anisotropy(second_moments(cor))
    assert a_raw[face].max() > 0.2 and a_raw[bulk].max() < 1e-6
    assert a_cor[face].max() < 5e-3 and a_cor[bulk].max() < 5e-3
    ratio = cor.weight / raw.weight
    assert ratio.min() >= 0.5 - 1e-6 and ratio.max() <= 2.0 + 1e-6
    # theta = tr(eps) under a uniaxial-stress strain: 1 % on the faces, 20-40 % off without
    eps = np.diag([1.0, -0.3, -0.3]) * 1e-6
    err = []
    for b in (raw, cor):
        b.y[:] = b.x0 + b.x0 @ eps.T
        b.compute_forces()
        err.append(np.abs(b.theta[face] / np.trace(eps) - 1).max())
    assert err[0] > 0.2 and err[1] < 0.015


def test_surface_correction_threaded_and_in_place_match_serial():
    """Reference: the serial surface correction (one chunk). The chunked, threaded pass over the
    pairs sums the moments in another order, so the weights agree to float32 round-off; the
    result does not depend on timing (two runs are bit-identical); correcting the weight array
    in place (out=weight) gives the same weights as a separate output."""
    from pdfem.pd.bonds.surface import surface_corrected_weights

    b = block(10, 9, 8, surface_correction=False)
    args = (b.x0, b.row_ptr, b.nbr, b.xi_len, b.weight, b.vol)
    serial = surface_corrected_weights(*args, ws=kn.PairWorkspace(b.row_ptr, b.nbr, n_chunks=1))
    ws3 = kn.PairWorkspace(b.row_ptr, b.nbr, n_chunks=3)
    chunked = surface_corrected_weights(*args, ws=ws3)
    assert not np.array_equal(serial, b.weight)  # the correction did something
    np.testing.assert_allclose(chunked, serial, rtol=1e-6)
    assert np.array_equal(surface_corrected_weights(*args, ws=ws3), chunked)
    w = b.weight.copy()
    surface_corrected_weights(b.x0, b.row_ptr, b.nbr, b.xi_len, w, b.vol, ws=ws3, out=w)
    assert np.array_equal(w, chunked)


def test_body_step_uses_the_fused_kernel_bit_identical_to_two_passes():
    """Reference: kernels.dilatation then kernels.forces (the two-pass step). IceBody's force
    evaluation uses the fused kernel, which only reuses the bond lengths: theta, forces, broken
    flags and the count are bit-identical, with bonds breaking in the call, for the serial and
    the chunked (threaded) builds."""
    for chunks in (1, 3):
        mat = IceMaterial(density=RHO, youngs_modulus=E, poisson_ratio=0.3, critical_stretch=2e-3)
        b = block(9, 8, 7, material=mat)
        b.workspace = kn.PairWorkspace(b.row_ptr, b.nbr, n_chunks=chunks)
        rng = np.random.default_rng(chunks)
        b.y[:] = b.x0 + 2e-3 * DX * rng.standard_normal(b.x0.shape)
        b.nofail[rng.random(b.n) < 0.05] = 1
        broken0 = b.broken.copy()
        w0 = b.weight.copy()  # the body negates the weights of bonds that break (SIGNED)
        nb = b.compute_forces()
        th, f = np.empty(b.n), np.empty((b.n, 3))
        kn.dilatation(b.y, b.row_ptr, b.nbr, b.xi_len, w0, broken0, b.vol, b.m, th, b.workspace)
        nb2 = kn.forces(b.y, b.row_ptr, b.nbr, b.xi_len, w0, broken0, b.vol, b.m, th, mat.K,
                        mat.mu, b.s0, b.nofail, f, b.workspace)
        assert nb == nb2 > 0
        assert np.array_equal(b.theta, th) and np.array_equal(b.f, f)
        assert np.array_equal(b.broken, broken0)
        assert np.array_equal(np.abs(b.weight), w0)  # only the signs changed


@pytest.mark.parametrize("shape", [(20, 20, 2), (8, 8, 8)])
def test_stable_time_step_is_safe_for_a_two_layer_plate(shape):
    """Reference: the true critical step 2 / sqrt(lambda_max) of the linearised LPS (Lanczos,
    kernels.max_eigenvalue_time_step) and energy conservation of velocity Verlet. The body's
    step is below the true limit for a two-layer plate (where Silling & Askari's estimate alone
    is above it) and for a bulk block, and 2000 steps at 0.95 times it conserve kinetic + strain
    energy: no drift between the first and last 200 steps, and only the bounded oscillation of a
    symplectic integrator (Hairer, Lubich & Wanner, Geometric Numerical Integration, ch. IX)."""
    b = block(*shape)
    mat = b.material
    true = kn.max_eigenvalue_time_step(b.x0, b.row_ptr, b.nbr, b.xi_len, b.weight, b.broken, b.vol,
                                       b.m, mat.K, mat.mu, DX, RHO, ws=b.workspace)
    sa = kn.stable_time_step(b.row_ptr, b.nbr, b.xi_len, b.weight, b.vol, b.delta, RHO, mat.K,
                             ws=b.workspace)
    dt = b.stable_time_step()
    assert 0.4 * true < dt <= true
    if shape[2] == 2:
        assert sa > true  # the estimate alone would be unstable here
    L = b.x0.max(axis=0) + 0.5 * DX
    s = np.sin(math.pi * b.x0 / L)
    b.v[:, 2] = 0.05 * s[:, 0] * s[:, 1]  # the lowest bending-like mode shape, 5 cm/s
    b.v[:, 0] = 0.05 * np.sin(2 * math.pi * b.x0[:, 1] / L[1])
    b.start()
    e0 = b.kinetic_energy() + b.strain_energy()
    energy = []
    for k in range(2000):
        b.step(0.95 * dt)
        if k % 10 == 9:
            energy.append(b.kinetic_energy() + b.strain_energy())
    energy = np.array(energy) / e0
    assert abs(energy[-20:].mean() - energy[:20].mean()) < 1e-3  # no growth (drift)
    assert np.abs(energy - 1).max() < 2e-2  # only the bounded O(dt^2) oscillation
