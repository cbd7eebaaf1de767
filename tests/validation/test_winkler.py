"""The floating plate on a Winkler foundation (pdfem/validation/cases/winkler.py).

References: Hertz 1884 / Wyman 1950 for the infinite plate on a foundation k (P / w0 =
8 sqrt(D k), w(r) ~ kei(r / l), l = (D / k)^(1/4)); Morley 1968 for the finite plate the
validation case compares against. SI units.
"""

from __future__ import annotations

import dataclasses
import math

import pytest

from pdfem.validation import all_cases
from pdfem.validation.case import load_validation_case
from pdfem.validation.cases import winkler
from pdfem.validation.runner import run_validation

D = 2.745e6 * 0.04**3 / (12.0 * (1.0 - 0.3**2))  # N m: the case's ice plate
K = 1025.0 * 9.81                                  # N/m^3: rho_w g
L0 = (D / K) ** 0.25                               # m: 0.200


def test_morley_reference_is_hertz_for_a_large_plate():
    """A free plate reaching 6 l each way from a small square punch (half-width l / 20) is the
    infinite plate: its profile is kei(r / l) with l = (D / k)^(1/4) (measured: within 0.3 %),
    and its P / w0 is Hertz's 8 sqrt(D k) for a point load, raised a little by the punch's
    finite size (measured: 1.022)."""
    stiff, x, w = winkler.morley_plate(6 * L0, 0.01, D, 0.3, K, 0.0025, L0 / 8)
    hertz = stiff / (8.0 * math.sqrt(D * K))
    assert hertz == pytest.approx(1.0, abs=0.04)   # Hertz 1884, within the punch's effect
    assert hertz > 1.0                             # a punch is stiffer than a point load
    assert winkler.fit_length(x, w, L0) == pytest.approx(L0, rel=0.01)


def _two_layers(case):
    """The case at the default horizon with 2 particles through h (dx = h/2, delta = 3.015 dx)
    on a 0.8 m plate (edges 2 l from the load), run to 0.7 s: 3,200 particles."""
    return winkler.resized(case, 0.4, 0.02, 3.015, 0.7)


def test_the_winkler_entries_are_registered():
    """The full case (6 particles through h, delta = 1.515 dx = h/4) passes its 5 %
    (docs/water.md: 0.959 and 0.972 of the Morley plate's P / w0 and l), so both are entries."""
    names = {c.name for c in all_cases()}
    assert {"floating_plate_winkler", "floating_plate_winkler_length"} <= names
    case = load_validation_case("floating_plate_winkler.toml")
    assert case.ice[0].horizon / case.ice[0].dx == pytest.approx(1.515)
    assert 0.04 / case.ice[0].dx == pytest.approx(6.0)


@pytest.mark.slow
def test_a_two_layer_floating_plate_records_the_bending_deficit(tmp_path):
    """Two particles through h at the default horizon (a 0.8 m plate: edges 2 l from the load)
    against the same finite plate with Morley elements: the lattice sheet is too soft in
    bending (docs/water.md, "Winkler plate"), P / w0 = 0.84 and l = 0.87 of the Kirchhoff
    plate's. The check records that deficit: it fails if the ice law's bending stiffness or the
    water's foundation changes. About half of it is the lattice sheet's plate moduli
    (pdfem/pd/plate_moduli.py): the same plate as the orthotropic Kirchhoff plate with the
    moduli of a 2-layer sheet has 0.916 and 0.908 of the isotropic plate's P / w0 and l, and
    the run is softer still."""
    cases = [dataclasses.replace(c, quick=_two_layers) for c in winkler.CASES]
    by_name = {r.name: r for r in run_validation(cases, tmp_path, quick=True)}
    p = by_name["floating_plate_winkler"]
    length = by_name["floating_plate_winkler_length"]
    assert p.reference == pytest.approx(3024.0, rel=0.005)        # Morley, 0.940 x Hertz
    assert length.reference == pytest.approx(0.2138, rel=0.005)
    assert p.value / p.reference == pytest.approx(0.837, abs=0.02)
    assert length.value / length.reference == pytest.approx(0.875, abs=0.02)
    assert not (p.passed or length.passed)
    two = _two_layers(load_validation_case("floating_plate_winkler.toml"))
    lattice_p, lattice_l = winkler.lattice_plate(two)
    assert lattice_p / p.reference == pytest.approx(0.916, abs=0.005)
    assert lattice_l / length.reference == pytest.approx(0.908, abs=0.005)
    assert p.value < lattice_p and length.value < lattice_l
