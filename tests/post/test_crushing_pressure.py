"""Korzhavin's (IEC 61400-3 Annex E) and ISO 19906's (2010, A.8.2.4.3.3) global crushing loads
(pdfem.post.crushing_pressure) against the worked numbers of OpenFAST IceFloe's test cases, and
the edge-crushing case's Korzhavin reference built from them."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pdfem.post import crushing_pressure as cp


def test_korzhavin_force_matches_icefloe_iec_test_case():
    """IceFloe's IEC/Korzhavin test (modules/icefloe/test/GLA_proto_lockin_IEC.log): h = 1 m,
    D = 5 m, sigma_c = 2.2 MPa, k1 = 0.9, k2 = 0.5 give 7.00036e6 N."""
    assert cp.korzhavin_force(1.0, 5.0, 2.2e6) == pytest.approx(7.00036e6, rel=1e-6)
    assert cp.korzhavin_force(1.0, 5.0, 2.2e6, 1.0, 1.0) == pytest.approx(
        math.sqrt(2.0) * 5.0 * 2.2e6, rel=1e-12)


def test_iso_global_force_matches_icefloe_iso_test_case():
    """IceFloe's ISO test (GLA_proto_randomCrush_ISO.log): h = 1 m, w = 5 m, C_R = 2.2 MPa give
    8.50271e6 N; the thickness exponent is -0.5 + h/5 below 1 m and -0.3 from 1 m on."""
    assert cp.iso_global_force(1.0, 5.0, 2.2e6) == pytest.approx(8.50271e6, rel=1e-6)
    assert cp.iso_exponent_n(0.2) == pytest.approx(-0.46)
    assert cp.iso_exponent_n(2.0) == -0.3
    assert cp.iso_pressure_factor(0.2, 0.4) == pytest.approx(0.2**-0.46 * 2.0**-0.16, rel=1e-12)


def test_edge_crushing_reference_is_the_iec_cycle_mean_of_korzhavin():
    """The ``edge_crushing_pressure`` reference is 0.75 k1 k2 <sqrt(1 + 5 h / w(t))>, w the
    wedge's width at the push's penetration (0.1 m/s after a 10 ms ramp, plus half a 4 cm cell),
    averaged over the 0.5 s run: by hand on a finer grid."""
    from pdfem.validation.case import load_validation_case
    from pdfem.validation.cases.edge_crushing import korzhavin_mean

    t = np.linspace(0.0, 0.5, 200001)
    push = np.where(t < 0.01, 0.5 * 0.1 * t * t / 0.01, 0.1 * (t - 0.005))
    w = 2.0 * (push + 0.02) / math.tan(math.radians(30.0))
    expect = 0.75 * 0.9 * 0.5 * np.mean(np.sqrt(1.0 + 5.0 * 0.2 / w))
    assert korzhavin_mean(load_validation_case("ice_edge_crushing.toml")) == pytest.approx(
        expect, rel=1e-4)
