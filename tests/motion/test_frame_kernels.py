"""The moving frame's per-substep kernels against the vector formulas they evaluate.

Reference: the d'Alembert loads of a rotating, accelerating frame, f = -m [R^T a_c + w' x r
+ w x (w x r) + 2 w x u_e'], and the rigid-body kinematics x = c + R r, v = c' + w x (R r) +
R u_e' (docs/rotating_structures.md), written with numpy.cross on random states; with them
the angular momentum sum m (R r) x v . n and kinetic energy 1/2 sum m |v|^2.
"""

import numpy as np

from pdfem.motion.frame_kernels import (StepVectors, inertial_loads, momentum_energy,
                                        support_torque_power, surface_world)
from pdfem.motion.rotation import axis_rotation


def _state(n=50, seed=3):
    rng = np.random.default_rng(seed)
    perm = rng.permutation(3 * n)               # DOFs in any order, not interleaved
    dofs = perm.reshape(3, n)
    r0 = rng.standard_normal((n, 3))
    u, v = 1e-3 * rng.standard_normal(3 * n), rng.standard_normal(3 * n)
    return rng, dofs, r0, u, v


def test_inertial_loads_are_the_dalembert_loads_bit_for_bit():
    rng, dofs, r0, u, v = _state()
    mass = rng.uniform(0.1, 2.0, len(r0))
    acc_c, w_dot, w = rng.standard_normal((3, 3))
    out = np.empty(len(u))
    inertial_loads(r0, u, v, dofs, mass, acc_c, w_dot, w, 0.3, np.zeros(0), out)
    r, ve = r0 + u[dofs.T], v[dofs.T]
    acc = acc_c[None, :] + np.cross(w_dot, r) + np.cross(w, np.cross(w, r)) \
        + 2.0 * np.cross(w, ve)
    assert np.array_equal(out[dofs.T], -mass[:, None] * acc)
    # with the geometric stiffness force s^2 K_sigma u: numpy's f - s^2 (K_sigma u)
    ksu = rng.standard_normal(len(u))
    inertial_loads(r0, u, v, dofs, mass, acc_c, w_dot, w, 0.3, ksu, out)
    f = np.empty(len(u))
    f[dofs.T] = -mass[:, None] * acc
    assert np.array_equal(out, f - 0.3 * ksu)


def test_surface_world_is_the_rigid_motion_plus_the_elastic_one():
    rng, dofs, r0, u, v = _state()
    R = axis_rotation(np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8]), 0.7)
    c, c_dot, w = rng.standard_normal((3, 3))
    table = np.ascontiguousarray(dofs.T)
    x, xv = np.empty_like(r0), np.empty_like(r0)
    surface_world(r0, u, v, table, R, c, c_dot, w, x, xv)
    r = r0 + u[table]
    assert np.allclose(x, c + r @ R.T, rtol=0, atol=1e-14)
    assert np.allclose(xv, c_dot + np.cross(w, r @ R.T) + v[table] @ R.T, rtol=0, atol=1e-14)


def test_momentum_and_energy_of_the_nodes_true_motion():
    rng, dofs, r0, u, v = _state()
    mass = rng.uniform(0.1, 2.0, len(r0))
    axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    R = axis_rotation(axis, 0.7)
    c_dot, w = rng.standard_normal((2, 3))
    momentum, energy = momentum_energy(r0, u, v, dofs, mass, R, c_dot, w, axis)
    rr = (r0 + u[dofs.T]) @ R.T
    vel = c_dot + np.cross(w, rr) + v[dofs.T] @ R.T
    expected_l = float((mass[:, None] * np.cross(rr, vel)).sum(axis=0) @ axis)
    expected_e = 0.5 * float(np.sum(mass[:, None] * vel * vel))
    assert abs(momentum - expected_l) < 1e-13 * np.sum(mass * np.abs(np.cross(rr, vel)).sum(1))
    assert abs(energy - expected_e) < 1e-14 * expected_e


def test_support_torque_and_power_of_the_held_and_damped_nodes():
    rng, dofs, r0, u, v = _state()
    n = len(u)
    held = np.zeros(n, bool)
    held[dofs[:, :10].ravel()] = True            # nodes 0-9 clamped
    held[dofs[0, 10]] = True                     # node 10 held along x only
    ku, f_damp, m, a, f_ext, v_half = rng.standard_normal((6, n))
    m = np.abs(m) + 0.1
    vel_c, w = rng.standard_normal((2, 3))
    axis = np.array([1.0, 0.0, 0.0])
    for alpha, nodes in ((0.0, np.arange(11)), (0.7, np.arange(len(r0)))):
        torque, power = support_torque_power(
            nodes, r0, dofs, held, StepVectors(u, ku, f_damp, m, a, f_ext, v_half), alpha,
            np.array([vel_c, w, axis]))
        g = np.where(held, ku + f_damp + m * a - f_ext, -alpha * m * v_half)
        force = g[dofs.T][nodes]
        r = (r0 + u[dofs.T])[nodes]
        assert np.isclose(torque, np.cross(r, force).sum(axis=0) @ axis, rtol=1e-12)
        assert np.isclose(power, np.sum(force * (vel_c + np.cross(w, r))), rtol=1e-12)
