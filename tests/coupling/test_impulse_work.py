"""The work of contact impulses on ice particles within one velocity-Verlet step
(:mod:`pdfem.coupling.impulse_work`).

Reference: the exact kinetic-energy change of a particle whose drift velocity jumps by impulses
inside a velocity-Verlet step (the module's derivation), here checked on one particle by direct
integration, and on many particles against the vector formula
``P . v_t + a_bar . M + |P|^2 / (2 m)`` summed over the owned particles.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from pdfem.coupling.impulse_work import ImpulseWork


def _body(n, rng, owned=None):
    material = SimpleNamespace(density=917.0)
    return SimpleNamespace(material=material, vol=rng.uniform(1e-6, 2e-6, n),
                           v=rng.normal(size=(n, 3)), f=rng.normal(size=(n, 3)) * 1e6,
                           gravity=np.array([0.0, 0.0, -9.81]),
                           owned=np.ones(n, dtype=bool) if owned is None else owned)


def test_one_particle_kinetic_energy_change_is_the_work():
    """A particle under a constant force density f (so a_t = a_T) takes an impulse P at
    tau = t + s inside a step of dt: its exact kinetic energy change minus the work of f over
    the actual path is the impulse work the ledger returns (to round-off)."""
    rng = np.random.default_rng(3)
    body = _body(1, rng)
    m = body.material.density * body.vol[0]
    a = body.f[0] / body.material.density + body.gravity
    v_t = body.v[0].copy()
    work = ImpulseWork(body, body.material.density * body.vol)
    dt, s = 1e-4, 3e-5
    P = np.array([2e-4, -1e-4, 5e-4])
    work.add(np.array([0]), P[None, :], s)
    # exact motion: v(t') = v_t + a t' + P/m H(t' - s); the force's work is m a . (y_T - y_t)
    v_T = v_t + a * dt + P / m
    dy = v_t * dt + 0.5 * a * dt**2 + (dt - s) * P / m
    expected = 0.5 * m * (v_T @ v_T - v_t @ v_t) - m * a @ dy
    assert work.work(body) == pytest.approx(expected, rel=1e-9)


def test_work_over_owned_particles_is_the_vector_formula():
    """Many particles, some not owned, most without impulse: the ledger's work is the vector
    formula's sum over the owned particles; a particle without impulse adds nothing."""
    rng = np.random.default_rng(4)
    n = 2000
    body = _body(n, rng, owned=rng.random(n) < 0.7)
    work = ImpulseWork(body, body.material.density * body.vol)
    hit = rng.random(n) < 0.2
    P = rng.normal(size=(n, 3)) * 1e-4 * hit[:, None]
    rows = np.flatnonzero(hit)
    work.add(rows, P[rows], 0.0)
    work.add(rows, 0.5 * P[rows], 2e-5)
    body.f = rng.normal(size=(n, 3)) * 1e6        # the forces at the step's end
    rho = body.material.density
    a_bar = 0.5 * (work.f0 / rho + body.f / rho) + body.gravity
    total, moment = 1.5 * P, 2e-5 * 0.5 * P
    mass = rho * body.vol
    per = ((total * work.v0).sum(1) + (a_bar * moment).sum(1)
           + 0.5 * (total * total).sum(1) / mass)
    assert work.work(body) == pytest.approx(per[body.owned].sum(), rel=1e-12)
    body.owned = body.owned & ~hit
    assert work.work(body) == 0.0
