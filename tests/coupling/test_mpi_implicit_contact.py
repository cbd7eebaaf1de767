"""Ice contact on an implicit structure whose solves are dealt over the ranks: 1 and 2 ranks
give the same bits.

The tiny milling case (models/validation/propeller_milling_tiny.toml: four linear blades clamped
to the rigid hub, blade 1 meets the ice block at 3.6 ms) with ``integrator = "implicit"``: its
matrix falls into the four blades' independent blocks, which 2 ranks factorise and solve two
each (:mod:`pdfem.fem.block_factor`), while the block's particles are split between the ranks
and every contact impulse amends the implicit step (:meth:`pdfem.fem.implicit.Newmark.end_impulse`).
Reference: the serial run of the same case. Every ice and structure array, the propeller's
load history and the shaft's rows must be identical bit for bit; only the energy accumulators
that each rank keeps for its own particles (summed over the ranks at output) may differ, to
round-off (1e-12 of the energy supplied).
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np
import pytest

from pdfem.case.schema import load_case
from pdfem.output import read_results
from pdfem.run.driver import run_case

from support.mpi import run_script

CASE = Path(__file__).resolve().parents[2] / "models" / "validation" / "propeller_milling_tiny.toml"

SCRIPT = textwrap.dedent('''
    import sys
    from pathlib import Path
    from pdfem.case.schema import load_case
    from pdfem.run.driver import run_case
    run_case(load_case(Path(sys.argv[1])), Path(sys.argv[2]), quiet=True)
''')


def implicit_case(tmp_path: Path) -> Path:
    """The tiny milling case with implicit blades, written next to the tests' runs."""
    text = CASE.read_text()
    marker = "element_order = 1          # linear tetrahedra"
    assert marker in text
    path = tmp_path / "milling_implicit.toml"
    path.write_text(text.replace(marker, 'integrator = "implicit"\n' + marker))
    return path


@pytest.mark.slow
def test_implicit_blades_in_contact_agree_on_one_and_two_ranks(tmp_path):
    path = implicit_case(tmp_path)
    summary = run_case(load_case(path), tmp_path / "one", quiet=True)
    script = tmp_path / "run.py"
    script.write_text(SCRIPT)
    run_script(script, 2, path, tmp_path / "two", timeout=600)
    ref = read_results(summary.results)
    got = read_results(tmp_path / "two" / "results.h5")
    assert (ref["meta"]["ranks"], got["meta"]["ranks"]) == (1, 2)
    # the blade meets the ice: contact loads on the propeller, bonds broken
    force = ref["histories"]["loads/propeller"]["force"]
    assert np.abs(force).max() > 100.0 and ref["ice"]["block"]["damage"].max() > 0.0
    for group in ("ice", "structure"):
        for name, fields in ref[group].items():
            for key, a in fields.items():
                np.testing.assert_array_equal(got[group][name][key], a, err_msg=f"{name}/{key}")
    per_rank = {"contact_dissipated", "dissipated", "fracture_dissipated", "residual"}
    supplied = float(np.abs(ref["histories"]["energy"]["supplied"]).max())
    for history, rows in ref["histories"].items():
        for key, a in rows.items():
            b = got["histories"][history][key]
            if history == "energy" and key in per_rank:
                np.testing.assert_allclose(b, a, rtol=0, atol=1e-12 * supplied)
            else:
                np.testing.assert_array_equal(b, a, err_msg=f"{history}/{key}")
