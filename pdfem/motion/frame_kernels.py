"""The per-substep passes of a structure in a moving frame, as numba kernels.

A spinning propeller takes dozens of structure substeps per coupling step (its thin blade
edges set the stable step), and each substep evaluates the frame's inertial loads on every
node, the true positions and velocities of the contact surface, and the shaft's support torque
and power. Written with numpy these were a dozen small-array operations each (``cross``,
``@ R.T``, gathers, ``add.at``), about as long as the stiffness product itself on a
quadratic-element propeller. Here each is one pass over its nodes, with no temporaries:

* :func:`inertial_loads`: ``f = -m [R^T a_c + w' x r + w x (w x r) + 2 w x u_e']`` per node,
  less the geometric stiffness force ``s^2 K_sigma u``, written into the DOF vector,
  ``r = X - c0 + u_e`` (:mod:`pdfem.motion.moving_frame`; the
  same products and sums in numpy's order, so the same bits);
* :func:`surface_world`: ``x = c + R r`` and ``v = c' + w x (R r) + R u_e'`` of the surface
  nodes (world axes);
* :func:`support_torque_power`: the supports' forces on the held nodes (``K u + C v + M a -
  f_ext`` on the held DOFs, with the integrator's ``K u``), plus the Rayleigh mass-damping
  forces on the free nodes, their moment about the shaft axis and their power on the frame's
  velocity (:mod:`pdfem.motion.shaft_loads`).

Units: m, m/s, m/s^2, kg, N, N m, W.
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np


class StepVectors(NamedTuple):
    """The integrator's DOF vectors (n,) that the support forces read."""

    u: np.ndarray        # m, elastic displacement
    ku: np.ndarray       # N, stiffness force K u
    f_damp: np.ndarray   # N, damping force
    m: np.ndarray        # kg, lumped mass
    a: np.ndarray        # m/s^2, acceleration
    f_ext: np.ndarray    # N, applied force
    v_half: np.ndarray   # m/s, mid-step velocity


@numba.njit(cache=True, inline="always")
def _cross(p0, p1, p2, q0, q1, q2):
    """``p x q`` of two 3-vectors given by their components (numpy's products and differences)."""
    return p1 * q2 - p2 * q1, p2 * q0 - p0 * q2, p0 * q1 - p1 * q0


@numba.njit(cache=True)
def inertial_loads(r0, u, v, dofs, mass, acc_c, w_dot, w, s2, ksu, out):
    """Inertial loads (N, DOF vector ``out``, frame axes) on every node, less ``s2 * ksu``
    (the centrifugal prestress's geometric stiffness force ``s^2 K_sigma u``; none when
    ``ksu`` is empty).

    Parameters
    ----------
    r0
        (Nn, 3) reference positions from the frame's centre, X - c0 (m).
    u, v
        (n,) elastic displacement (m) and velocity (m/s), DOF vectors.
    dofs
        (3, Nn) DOF of component c at node k.
    mass
        (Nn,) lumped nodal masses (kg).
    acc_c
        (3,) the centre's acceleration in frame axes, R^T c'' (m/s^2).
    w_dot, w
        (3,) angular acceleration (rad/s^2) and velocity (rad/s).
    s2, ksu
        The ramp's ``s(t)^2`` and ``K_sigma u`` (N, (n,) or empty).
    out
        (n,) the loads, written.
    """
    stiff = ksu.shape[0] == out.shape[0]
    for k in range(r0.shape[0]):
        d0, d1, d2 = dofs[0, k], dofs[1, k], dofs[2, k]
        r_0, r_1, r_2 = r0[k, 0] + u[d0], r0[k, 1] + u[d1], r0[k, 2] + u[d2]
        e0, e1, e2 = _cross(w_dot[0], w_dot[1], w_dot[2], r_0, r_1, r_2)
        c0, c1, c2 = _cross(w[0], w[1], w[2], r_0, r_1, r_2)
        g0, g1, g2 = _cross(w[0], w[1], w[2], c0, c1, c2)
        k0, k1, k2 = _cross(w[0], w[1], w[2], v[d0], v[d1], v[d2])
        m = -mass[k]
        f0 = m * (acc_c[0] + e0 + g0 + 2.0 * k0)
        f1 = m * (acc_c[1] + e1 + g1 + 2.0 * k1)
        f2 = m * (acc_c[2] + e2 + g2 + 2.0 * k2)
        if stiff:   # numpy's product, then the difference
            f0, f1, f2 = f0 - s2 * ksu[d0], f1 - s2 * ksu[d1], f2 - s2 * ksu[d2]
        out[d0] = f0
        out[d1] = f1
        out[d2] = f2


@numba.njit(cache=True, inline="always")
def _node_motion(r0, u, v, k, d0, d1, d2, rot, c_dot, w):
    """Node ``k``'s turned position ``R r`` (m, from the frame's centre, world axes) and its
    true velocity ``c' + w x (R r) + R u_e'`` (m/s), ``r = X - c0 + u_e``; its DOFs d0-d2."""
    r_0, r_1, r_2 = r0[k, 0] + u[d0], r0[k, 1] + u[d1], r0[k, 2] + u[d2]
    a0 = rot[0, 0] * r_0 + rot[0, 1] * r_1 + rot[0, 2] * r_2
    a1 = rot[1, 0] * r_0 + rot[1, 1] * r_1 + rot[1, 2] * r_2
    a2 = rot[2, 0] * r_0 + rot[2, 1] * r_1 + rot[2, 2] * r_2
    s0, s1, s2 = _cross(w[0], w[1], w[2], a0, a1, a2)
    q0, q1, q2 = v[d0], v[d1], v[d2]
    return (a0, a1, a2,
            c_dot[0] + s0 + (rot[0, 0] * q0 + rot[0, 1] * q1 + rot[0, 2] * q2),
            c_dot[1] + s1 + (rot[1, 0] * q0 + rot[1, 1] * q1 + rot[1, 2] * q2),
            c_dot[2] + s2 + (rot[2, 0] * q0 + rot[2, 1] * q1 + rot[2, 2] * q2))


@numba.njit(cache=True)
def surface_world(r0, u, v, dofs, rot, c, c_dot, w, x, xv):
    """World positions ``x`` (m) and velocities ``xv`` (m/s), (Ns, 3), of surface nodes.

    Parameters
    ----------
    r0
        (Ns, 3) reference positions of the surface nodes from the frame's centre (m).
    u, v
        (n,) elastic displacement (m) and velocity (m/s), DOF vectors (frame axes).
    dofs
        (Ns, 3) DOF of each surface node's components.
    rot
        (3, 3) rotation R (frame axes -> world axes).
    c, c_dot, w
        (3,) the frame's centre (m), its velocity (m/s) and angular velocity (rad/s).
    x, xv
        (Ns, 3) outputs.
    """
    for k in range(r0.shape[0]):
        a0, a1, a2, xv[k, 0], xv[k, 1], xv[k, 2] = _node_motion(
            r0, u, v, k, dofs[k, 0], dofs[k, 1], dofs[k, 2], rot, c_dot, w)
        x[k, 0] = c[0] + a0
        x[k, 1] = c[1] + a1
        x[k, 2] = c[2] + a2


@numba.njit(cache=True)
def momentum_energy(r0, u, v, dofs, mass, rot, c_dot, w, axis):
    """The angular momentum about ``axis`` (kg m^2/s) and the kinetic energy (J) of all nodes,
    true motion in the world, lumped mass: ``sum m ((R r) x x') . n`` and ``1/2 sum m |x'|^2``
    with ``x' = c' + w x (R r) + R u_e'`` (:func:`surface_world`'s velocity), summed node by
    node.

    Parameters
    ----------
    r0
        (Nn, 3) reference positions from the frame's centre (m).
    u, v
        (n,) elastic displacement (m) and velocity (m/s), DOF vectors (frame axes).
    dofs
        (3, Nn) DOF of component c at node k.
    mass
        (Nn,) lumped node masses (kg).
    rot, c_dot, w
        The frame's rotation R (frame axes -> world axes), its centre's velocity (m/s) and
        angular velocity (rad/s).
    axis
        (3,) the unit axis of the angular momentum (world axes).
    """
    momentum = 0.0
    twice_energy = 0.0
    for k in range(r0.shape[0]):
        a0, a1, a2, x0, x1, x2 = _node_motion(r0, u, v, k, dofs[0, k], dofs[1, k], dofs[2, k],
                                              rot, c_dot, w)
        l0, l1, l2 = _cross(a0, a1, a2, x0, x1, x2)
        momentum += mass[k] * (l0 * axis[0] + l1 * axis[1] + l2 * axis[2])
        twice_energy += mass[k] * (x0 * x0 + x1 * x1 + x2 * x2)
    return momentum, 0.5 * twice_energy


@numba.njit(cache=True, inline="always")
def _support_force(d, held, s, alpha):
    """The force (N) on DOF ``d`` between the structure and its frame: the support's reaction
    ``K u + C v + M a - f_ext`` on a held DOF, the mass damping ``-alpha m v_half`` on a free one."""
    if held[d]:
        return s.ku[d] + s.f_damp[d] + s.m[d] * s.a[d] - s.f_ext[d]
    return -alpha * s.m[d] * s.v_half[d]


@numba.njit(cache=True)
def support_torque_power(nodes, r0, dofs, held, s, alpha, frame):
    """The shaft's torque (N m) about its axis and power (W) of the supports' forces.

    Parameters
    ----------
    nodes
        (Nh,) the nodes whose forces count: the held ones, or every node with mass damping.
    r0
        (Nn, 3) reference positions from the frame's centre (m).
    dofs
        (3, Nn) DOF of component c at node k.
    held
        (n,) bool: whether a DOF is held by a support.
    s
        The integrator's vectors (:class:`StepVectors`).
    alpha
        Rayleigh mass-damping coefficient (1/s): the force ``-alpha m v_half`` on free DOFs.
    frame
        (3, 3) rows: the frame's centre velocity in frame axes R^T c' (m/s), its angular
        velocity (rad/s) and the unit shaft axis.

    Returns
    -------
    tuple of float
        Torque (N m, about the axis) and power (W) on the frame's velocity at the nodes.
    """
    vel_c, w, axis = frame[0], frame[1], frame[2]
    torque = 0.0
    power = 0.0
    for i in range(nodes.shape[0]):
        k = nodes[i]
        d0, d1, d2 = dofs[0, k], dofs[1, k], dofs[2, k]
        r_0, r_1, r_2 = r0[k, 0] + s.u[d0], r0[k, 1] + s.u[d1], r0[k, 2] + s.u[d2]
        f0 = _support_force(d0, held, s, alpha)
        f1 = _support_force(d1, held, s, alpha)
        f2 = _support_force(d2, held, s, alpha)
        t0, t1, t2 = _cross(r_0, r_1, r_2, f0, f1, f2)
        torque += t0 * axis[0] + t1 * axis[1] + t2 * axis[2]
        s0, s1, s2 = _cross(w[0], w[1], w[2], r_0, r_1, r_2)
        power += f0 * (vel_c[0] + s0) + f1 * (vel_c[1] + s1) + f2 * (vel_c[2] + s2)
    return torque, power
