"""Tests of pdfem.pd.materials.lps (LPS constants, critical stretch, IceMaterial)."""

from __future__ import annotations

import math

import pytest

from pdfem.pd.materials.lps import SEA_ICE_DEFAULTS, IceMaterial, critical_stretch, lps_constants


def test_lps_constants_isotropic_elasticity():
    """Reference: isotropic linear elasticity, K = E / (3 (1 - 2 nu)), mu = E / (2 (1 + nu));
    E and nu recovered back through E = 9 K mu / (3 K + mu), nu = (3K - 2mu) / (2 (3K + mu))."""
    K, mu = lps_constants(4.1e9, 0.3)
    assert K == pytest.approx(4.1e9 / 1.2, rel=1e-15)
    assert mu == pytest.approx(4.1e9 / 2.6, rel=1e-15)
    for E, nu in ((1e9, 0.0), (4.1e9, 0.3), (2e11, 0.45), (5e9, -0.5)):
        K, mu = lps_constants(E, nu)
        assert 9 * K * mu / (3 * K + mu) == pytest.approx(E, rel=1e-14)
        assert (3 * K - 2 * mu) / (2 * (3 * K + mu)) == pytest.approx(nu, abs=1e-14)


@pytest.mark.parametrize("E, nu", [(0.0, 0.3), (-1e9, 0.3), (math.nan, 0.3), (1e9, 0.5),
                                   (1e9, -1.0), (1e9, 0.7), (1e9, math.inf)])
def test_lps_constants_rejects_bad_input(E, nu):
    """Reference: the admissible ranges E > 0, -1 < nu < 0.5 of a stable isotropic solid."""
    with pytest.raises(ValueError, match="Young's modulus|Poisson's ratio"):
        lps_constants(E, nu)


def test_critical_stretch_hand_values():
    """Reference: hand evaluation of s0 = sqrt(G0 / ((3 mu + (3/4)^4 (K - 5 mu / 3)) delta)).

    With K = 5 mu / 3 the bulk term vanishes: s0 = sqrt(30 / (3e9 * 0.1)) = sqrt(1e-7).
    Sea ice (E = 4.1 GPa, nu = 0.3, G0 = 10 J/m^2, delta = 0.15 m): 3 mu = 4.7307692e9,
    (3/4)^4 (K - 5 mu / 3) = 0.31640625 * 0.7884615e9 = 0.2494742e9, so
    s0 = sqrt(10 / (4.9802434e9 * 0.15)) = 1.156989e-4.
    """
    assert critical_stretch(30.0, 5e9 / 3, 1e9, 0.1) == pytest.approx(math.sqrt(1e-7), rel=1e-14)
    K, mu = lps_constants(4.1e9, 0.3)
    assert critical_stretch(10.0, K, mu, 0.15) == pytest.approx(1.156989e-4, rel=1e-6)
    # s0 scales as 1 / sqrt(delta) and sqrt(G0)
    assert critical_stretch(40.0, K, mu, 0.6) == pytest.approx(critical_stretch(10.0, K, mu, 0.15))


@pytest.mark.parametrize("args", [(0.0, 3e9, 1e9, 0.1), (10.0, 3e9, 1e9, 0.0),
                                  (10.0, -3e9, 1e9, 0.1), (-1.0, 3e9, 1e9, 0.1)])
def test_critical_stretch_rejects_bad_input(args):
    """Reference: G0, K, mu and delta are positive physical quantities."""
    with pytest.raises(ValueError):
        critical_stretch(*args)


def test_ice_material():
    """Reference: the definitions (bar wave speed sqrt(E / rho), s0 precedence: given critical
    stretch, else from G0, else no fracture) and the documented sea-ice defaults."""
    d = SEA_ICE_DEFAULTS
    assert d["density"] == 900.0 and d["youngs_modulus"] == 4.1e9 and d["poisson_ratio"] == 0.3
    assert d["fracture_energy"] == 10.0
    assert d["flexural_strength_min"] == 0.4e6 and d["flexural_strength_max"] == 0.9e6
    ice = IceMaterial(d["density"], d["youngs_modulus"], d["poisson_ratio"],
                      fracture_energy=d["fracture_energy"])
    assert (ice.K, ice.mu) == lps_constants(4.1e9, 0.3)
    assert ice.wave_speed == pytest.approx(math.sqrt(4.1e9 / 900.0), rel=1e-15)
    assert ice.s0(0.15) == pytest.approx(1.156989e-4, rel=1e-6)
    both = IceMaterial(900.0, 4.1e9, 0.3, fracture_energy=10.0, critical_stretch=2e-3)
    assert both.s0(0.15) == 2e-3
    assert IceMaterial(900.0, 4.1e9, 0.3).s0(0.15) == math.inf
    with pytest.raises(AttributeError):
        ice.density = 1.0  # frozen
    for bad in (dict(density=0.0), dict(poisson_ratio=0.5), dict(fracture_energy=-1.0),
                dict(critical_stretch=0.0)):
        kw = dict(density=900.0, youngs_modulus=4.1e9, poisson_ratio=0.3) | bad
        with pytest.raises(ValueError):
            IceMaterial(**kw)
