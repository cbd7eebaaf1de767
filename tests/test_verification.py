"""Verification of the peridynamic ice solver against analytic answers and conservation laws.

Each test names its reference. Lattices are small (a few thousand particles) so the suite stays
fast; tolerances are those the design promises.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from pdfem.pd.body import IceBody
from pdfem.pd.material import IceMaterial
from pdfem.shapes import Box

E, NU, RHO = 4.0e9, 0.3, 900.0
ICE = IceMaterial(density=RHO, youngs_modulus=E, poisson_ratio=NU)  # no fracture energy: unbreakable


def block(nx, ny, nz, dx=0.01, material=ICE, factor=3.015, loop="pairs") -> IceBody:
    shape = Box((0.0, 0.0, 0.0), (nx * dx, ny * dx, nz * dx))
    return IceBody.from_shape("b", shape, material, dx, factor * dx, loop=loop)


def run(body: IceBody, steps: int, dt: float, record=None):
    body.start()
    out = []
    for k in range(steps):
        body.step(dt)
        if record is not None:
            out.append(record(body))
    return np.array(out)


def test_energy_is_conserved_without_damage():
    """Velocity Verlet on the (hyperelastic) LPS conserves kinetic + strain energy:
    drift < 0.1 % over 2000 steps (reference: energy conservation of a Hamiltonian system)."""
    b = block(12, 10, 8)
    L = b.x0.max(axis=0) + 0.5 * b.dx
    # a smooth initial velocity field: the first few standing waves of the block
    b.v[:, 0] = 0.5 * np.sin(math.pi * b.x0[:, 0] / L[0]) * np.cos(math.pi * b.x0[:, 1] / L[1])
    b.v[:, 2] = 0.3 * np.sin(2 * math.pi * b.x0[:, 2] / L[2])
    dt = 0.8 * b.stable_time_step()
    b.start()
    e0 = b.kinetic_energy() + b.strain_energy()
    energies = []
    for k in range(2000):
        b.step(dt)
        if k % 50 == 49:
            energies.append(b.kinetic_energy() + b.strain_energy())
    energies = np.array(energies)
    assert b.strain_energy() > 0.05 * e0  # energy really moved between kinetic and strain
    assert np.max(np.abs(energies - e0)) / e0 < 1e-3
    # momentum too: internal forces are equal and opposite pairwise (Newton's third law)
    assert np.linalg.norm(b.momentum()) < 1e-9 * RHO * b.vol.sum() * 0.5


def test_wave_speed_in_slender_bar():
    """Free-free bar released from uniform uniaxial stress: it rings at the fundamental period
    2L/c, c = sqrt(E/rho) (1-D wave equation; Madenci & Oterkus 2014, sec. 6.1 bar example).
    The measured period is within 3 %."""
    nx, nyz, dx = 100, 8, 0.01
    b = block(nx, nyz, nyz, dx)
    Lx = nx * dx
    eps0 = 1e-5
    xc = b.x0.mean(axis=0)
    b.y[:] = b.x0 + eps0 * (b.x0 - xc) * np.array([1.0, -NU, -NU])
    c = math.sqrt(E / RHO)
    T_exact = 2 * Lx / c
    dt = 0.8 * b.stable_time_step()
    right = b.x0[:, 0] > xc[0]
    steps = int(1.6 * T_exact / dt)
    # q = stretch of the bar (mean u of right half - mean u of left half): cos(2 pi t / T) dominated
    q = run(b, steps, dt, lambda bb: (bb.y[right, 0] - bb.x0[right, 0]).mean()
            - (bb.y[~right, 0] - bb.x0[~right, 0]).mean())
    t = dt * np.arange(1, steps + 1)
    zc = np.flatnonzero(np.sign(q[:-1]) != np.sign(q[1:]))
    assert len(zc) >= 2
    tz = [t[k] - q[k] * (t[k + 1] - t[k]) / (q[k + 1] - q[k]) for k in zc[:2]]
    T = 2 * (tz[1] - tz[0])
    assert T == pytest.approx(T_exact, rel=0.03)


def test_recovered_youngs_modulus_and_poisson_ratio():
    """A block under uniaxial stress (traction on its end faces, dynamic relaxation): the interior
    strains give E and nu within 3 % of the input, nu = 0.3 (Hooke's law; shows the state-based
    model is free of bond-based PD's nu = 1/4)."""
    nx, ny, nz, dx = 36, 14, 14, 0.01
    b = block(nx, ny, nz, dx)
    sigma = 1e6  # Pa
    x = b.x0[:, 0]
    lo_end, hi_end = x < x.min() + 0.5 * dx, x > x.max() - 0.5 * dx
    area_per_particle = dx * dx
    traction = np.zeros_like(b.x0)  # force density (N/m^3) on the end layers
    traction[lo_end, 0] = -sigma * area_per_particle / b.vol[lo_end]
    traction[hi_end, 0] = sigma * area_per_particle / b.vol[hi_end]
    dt = 0.8 * b.stable_time_step()
    c = math.sqrt(E / RHO)
    omega = math.pi * c / (nx * dx)  # lowest (axial) mode, for near-critical damping
    damp = math.exp(-omega * dt)
    b.start()
    for k in range(6000):
        b.f += traction
        b.v += 0.5 * dt * b.f / RHO
        b.v *= damp
        b.y += dt * b.v
        b.compute_forces()
        b.f += traction
        b.v += 0.5 * dt * b.f / RHO
    u = b.y - b.x0
    core = (np.abs(b.x0[:, 1] - b.x0[:, 1].mean()) < 4 * dx) & (np.abs(b.x0[:, 2] - b.x0[:, 2].mean()) < 4 * dx)
    mid = (x > x.min() + 0.3 * nx * dx) & (x < x.max() - 0.3 * nx * dx)
    sel = core & mid
    exx = np.polyfit(b.x0[sel, 0], u[sel, 0], 1)[0]
    eyy = np.polyfit(b.x0[sel, 1], u[sel, 1], 1)[0]
    ezz = np.polyfit(b.x0[sel, 2], u[sel, 2], 1)[0]
    E_pd = sigma / exx
    nu_pd = -0.5 * (eyy + ezz) / exx
    assert E_pd == pytest.approx(E, rel=0.03)
    assert nu_pd == pytest.approx(NU, rel=0.03)


def test_notched_bar_fracture_energy():
    """A notched bar pulled apart: no bond breaks before some stretch passes s0, and the energy
    taken out by broken bonds (external work - kinetic - strain after separation) is G0 times the
    ligament area within 15 % (Griffith energy balance; s0 calibrated from G0, Madenci & Oterkus
    2014 OSB critical stretch)."""
    G0 = 10.0
    mat = IceMaterial(density=RHO, youngs_modulus=E, poisson_ratio=NU, fracture_energy=G0)
    nx, ny, nz, dx = 40, 10, 10, 0.005
    b = block(nx, ny, nz, dx, material=mat)
    Lx, Ly, Lz = nx * dx, ny * dx, nz * dx
    notch = 3 * dx
    # pre-crack: the plane x = Lx/2, from z = 0 to z = notch, across the whole width
    assert b.cut_crack((Lx / 2, 0, 0), (1, 0, 0), (Lx / 2 - dx, -1, -1), (Lx / 2 + dx, 1, notch)) > 0
    x = b.x0[:, 0]
    grip_l, grip_r = x < 3 * dx, x > Lx - 3 * dx
    b.nofail[grip_l | grip_r] = 1
    vpull = 0.5  # m/s each end, ramped
    b.add_velocity_constraint(grip_l, (-vpull, 0, 0), ramp_time=2e-4)
    b.add_velocity_constraint(grip_r, (vpull, 0, 0), ramp_time=2e-4)
    dt = 0.8 * b.stable_time_step()
    b.start()
    s0 = b.s0
    i_of_bond = np.repeat(np.arange(b.n), np.diff(b.row_ptr))
    pre = int(b.broken.sum())
    first_break_stretch = None
    for k in range(20000):
        y_before = b.y.copy()
        n_new = b.step(dt)
        if n_new and first_break_stretch is None:
            d = b.y[b.nbr] - b.y[i_of_bond]
            stretch = (np.linalg.norm(d, axis=1) - b.xi_len) / b.xi_len
            first_break_stretch = stretch[b.broken.astype(bool)].max()
            # before this step no bond of the intact set was stretched beyond s0
            d0 = y_before[b.nbr] - y_before[i_of_bond]
            s_prev = (np.linalg.norm(d0, axis=1) - b.xi_len) / b.xi_len
            intact_before = np.ones(b.n_bonds, bool)
            intact_before[:] = True
            assert s_prev.max() <= s0 * (1 + 1e-12) or first_break_stretch > s0
        # separated: no intact bond crosses the mid plane
        if k % 200 == 0 and b.broken.sum() > pre:
            xi_i = b.x0[i_of_bond, 0]
            xj = b.x0[b.nbr, 0]
            crossing = ((xi_i - Lx / 2) * (xj - Lx / 2) < 0) & (b.broken == 0)
            if not crossing.any():
                break
    assert first_break_stretch is not None and first_break_stretch > s0
    ke, se = b.kinetic_energy(), b.strain_energy()
    dissipated = b.external_work - ke - se
    area = Ly * (Lz - notch)
    assert dissipated == pytest.approx(G0 * area, rel=0.15)
