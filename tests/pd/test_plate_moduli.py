"""Plate moduli of a lattice ice sheet (pdfem/pd/plate_moduli.py) against Kirchhoff's plate.

Reference: the energies per area of the Kirchhoff plate modes, D k^2 / 2 (cylindrical bending),
D (1 - nu) k^2 (twist), D (1 + nu) k^2 (spherical bending), D = E h^3 / (12 (1 - nu^2)), and
E h e^2 / (2 (1 - nu^2)) for a membrane stretch with eps_yy = 0 (Timoshenko & Woinowsky-Krieger
1959, Theory of Plates and Shells, ch. 1-2). SI units.
"""

from __future__ import annotations

import pytest

from pdfem.pd.plate_moduli import plate_moduli


def test_thick_sheet_is_a_kirchhoff_plate():
    """16 particles through h at a horizon of 2.015 dx (delta / h = 0.126): every mode within
    3 % of Kirchhoff's energy, the bending modes within 1 %."""
    p = plate_moduli(16, 2.015, 0.3)
    assert p.cylindrical == pytest.approx(1.0, abs=0.01)
    assert p.spherical == pytest.approx(1.0, abs=0.01)
    assert p.twist == pytest.approx(1.0, abs=0.03)
    assert p.membrane == pytest.approx(1.0, abs=0.01)
    assert p.d12 == pytest.approx(0.3, abs=0.01)           # nu D
    assert p.d66 == pytest.approx(0.35, abs=0.015)         # (1 - nu) D / 2


def test_thin_sheet_is_soft_in_bending_and_twist():
    """The default horizon (3.015 dx) with 2 and 4 particles through h: the deficits of
    docs/water.md ("Winkler plate"), which make the floating plate too soft; the twist is the
    weakest mode, and a sheet 2 particles thick is 1.6 times too stiff as a membrane."""
    two, four = plate_moduli(2, 3.015), plate_moduli(4, 3.015)
    assert (two.cylindrical, two.twist, two.membrane) == pytest.approx((0.817, 0.600, 1.594),
                                                                      abs=0.01)
    assert (four.cylindrical, four.twist, four.membrane) == pytest.approx((0.846, 0.740, 1.022),
                                                                         abs=0.01)
    # without the surface correction the thin sheet bends as Kirchhoff's plate by a
    # cancellation: the stiff skin (membrane 1.23) against the cut families
    bare = plate_moduli(4, 3.015, surface_correction=False)
    assert bare.cylindrical == pytest.approx(1.0, abs=0.01)
    assert bare.membrane == pytest.approx(1.234, abs=0.01)


def test_a_sheet_needs_a_layer():
    with pytest.raises(ValueError, match="at least one particle layer"):
        plate_moduli(0, 3.015)
