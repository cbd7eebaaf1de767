"""Natural modes and the static solve of elastic structures (pdfem.fem.modes, pdfem.fem.static)
and the ``pdfem modes`` command: analytic spring-mass chains, a steel cantilever against
Euler-Bernoulli / Timoshenko beam theory, the JSON report, exit 2 on bad input, modes.xdmf."""

from __future__ import annotations

import json
import math
from pathlib import Path

import h5py
import meshio
import numpy as np
import pytest
import scipy.sparse as sp

from pdfem.case import load_case
from pdfem.fem.explicit import CentralDifference, power_iteration_max_eigenvalue
from pdfem.fem.modes import generalized_modes, natural_modes
from pdfem.fem.static import static_displacement
from pdfem.run.build_structures import build_structure

from support.cli import run_pdfem

ROOT = Path(__file__).resolve().parents[2]
CANTILEVER = ROOT / "models" / "validation" / "cantilever_frequency.toml"
E, RHO, NU = 210e9, 7850.0, 0.3

BEAM = """
[run]
end_time = 1e-3

[[structure]]
name = "beam"
kind = "elastic"
mesh = "{box}"
params = {{ length_x = 1.0, length_y = 0.1, length_z = 0.1, divisions_x = 20, divisions_y = 2, divisions_z = 2, fixed_faces = "x0", loaded_faces = "x1", contact_faces = "" }}
fixed_groups = ["fixed"]
contact_group = "loaded"

[[structure]]
name = "wall"
kind = "rigid"
mesh = "{box}"
params = {{ surface_only = true, origin_z = -0.5, length_x = 0.2, length_y = 0.2, length_z = 0.02, element_size = 0.05 }}
"""


def _chain(n: int, k: float, m: float, fixed_ends: int) -> sp.csr_matrix:
    """Stiffness of ``n`` equal masses joined by springs ``k``; ``fixed_ends`` (0, 1) extra
    springs tie the first mass to the ground."""
    main = np.full(n, 2.0 * k)
    main[-1] = k
    main[0] = 2.0 * k if fixed_ends else k
    return sp.diags([main, -k * np.ones(n - 1), -k * np.ones(n - 1)], [0, 1, -1]).tocsr()


def test_fixed_free_chain_matches_analytic_eigenvalues():
    """Fixed-free chain of N masses m and springs k: omega_j = 2 sqrt(k/m) sin((2j-1) pi /
    (2 (2N+1))) (e.g. Meirovitch, Elements of Vibration Analysis, 1986, sec. 6.6); shapes are
    mass-normalised, and the same start vector gives the same result."""
    n, k, m = 50, 3.0e6, 2.5
    lam, phi = generalized_modes(_chain(n, k, m, 1), np.full(n, m), 6)
    j = np.arange(1, 7)
    exact = 2.0 * math.sqrt(k / m) * np.sin((2 * j - 1) * math.pi / (2 * (2 * n + 1)))
    np.testing.assert_allclose(np.sqrt(lam), exact, rtol=1e-9)
    np.testing.assert_allclose(phi.T @ (m * phi), np.eye(6), atol=1e-9)
    lam2, phi2 = generalized_modes(_chain(n, k, m, 1), np.full(n, m), 6)
    assert np.array_equal(lam, lam2) and np.array_equal(phi, phi2)


def test_power_iteration_scales_with_the_stiffness():
    """The largest eigenvalue of M^-1 K is linear in K (issue 31: a stiffness of 1e300 gave 0,
    an unlimited step, when |K x|^2 overflowed): the chain times 1e300 (1e-300) gives 1e300
    (1e-300) times the chain's, a K that overflowed gives inf, and the explicit critical step of a Rayleigh-damped
    system stays 2/w (sqrt(1 + xi^2) - xi) (Belytschko et al., Sec. 6.3), about 1 / (w xi) for a
    huge xi (it was inf when xi^2 overflowed)."""
    chain, m = _chain(20, 3.0e6, 2.5, 1), np.full(20, 2.5)
    lam, _ = power_iteration_max_eigenvalue(chain, m)
    for scale in (1e300, 1e-300):  # |K x|^2 overflows, underflows
        scaled, _ = power_iteration_max_eigenvalue(chain * scale, m)
        assert scaled == pytest.approx(scale * lam, rel=1e-12)
    overflowed = chain.copy()
    overflowed.data[0] = math.inf
    assert power_iteration_max_eigenvalue(overflowed, m)[0] == math.inf
    w, beta = math.sqrt(lam), 3e-4
    xi = 0.5 * beta * w
    cd = CentralDifference(chain, m, rayleigh_beta=beta)
    assert cd.critical_time_step() == pytest.approx(2 / w * (math.sqrt(1 + xi**2) - xi),
                                                    rel=1e-12)
    xi = 0.5 * 1e300 * w  # xi^2 overflows: the step is 1 / (w xi) to first order, not inf
    assert CentralDifference(chain, m, rayleigh_beta=1e300).critical_time_step() == \
        pytest.approx(1.0 / (w * xi), rel=1e-12)


def test_free_chain_has_a_rigid_body_mode():
    """A free-free chain: omega = 0 (rigid translation, shape 1/sqrt(N m)) and then
    omega_j = 2 sqrt(k/m) sin(j pi / (2 N)); the negative shift keeps the factorisation regular."""
    n, k, m = 30, 1.0e4, 1.0
    lam, phi = generalized_modes(_chain(n, k, m, 0), np.full(n, m), 4)
    exact = 2.0 * math.sqrt(k / m) * np.sin(np.arange(4) * math.pi / (2 * n))
    np.testing.assert_allclose(np.sqrt(lam), exact, rtol=1e-7, atol=1e-5)
    np.testing.assert_allclose(np.abs(phi[:, 0]), 1.0 / math.sqrt(n * m), rtol=1e-7)


def test_bad_mode_count_is_refused():
    with pytest.raises(ValueError, match="number of modes"):
        generalized_modes(_chain(5, 1.0, 1.0, 1), np.ones(5), 5)


@pytest.fixture(scope="module")
def cantilever(tmp_path_factory):
    """The validation cantilever (1 m x 0.1 m x 0.1 m steel, clamped at x = 0), built as a run
    builds it."""
    case = load_case(CANTILEVER)
    return case, build_structure(case.structures[0], tmp_path_factory.mktemp("beam"), case.file)


def test_cantilever_first_frequencies_match_euler_bernoulli(cantilever):
    """f1 = 1.875104^2 / (2 pi L^2) sqrt(E I / (rho A)) = 83.55 Hz (Blevins 1979, table 8-1);
    the square section gives two equal bending modes (y and z); support nodes do not move."""
    _, st = cantilever
    f, shapes = natural_modes(st, 4)
    f1 = 1.875104**2 / (2 * math.pi) * math.sqrt(E * 0.1**4 / 12 / (RHO * 0.01))
    assert abs(f[0] / f1 - 1) < 0.01 and abs(f[1] / f1 - 1) < 0.01
    assert abs(f[1] - f[0]) < 1e-6 * f[0] and np.all(np.diff(f) >= 0)
    assert shapes.shape == (4, st.points.shape[0], 3)
    m = st.solver.m
    for i in range(4):
        phi = st.dofmap.to_dofs(shapes[i])
        assert abs(phi @ (m * phi) - 1.0) < 1e-9
        assert np.abs(phi[st.solver.fixed]).max() == 0.0


def test_cantilever_static_tip_deflection_matches_beam_theory(cantilever):
    """Tip deflection under the case's 1 kN tip load: Timoshenko beam P L^3 / (3 E I) +
    P L / (kappa G A), kappa = 5/6 (Timoshenko & Gere, Mechanics of Materials)."""
    _, st = cantilever
    u = static_displacement(st)
    tip = np.isclose(st.points[:, 0], 1.0)
    inertia, area, g = 0.1**4 / 12, 0.01, E / (2 * (1 + NU))
    exact = 1e3 / (3 * E * inertia) + 1e3 / (5 / 6 * g * area)
    assert abs(-u[tip, 2].mean() / exact - 1) < 0.02
    assert np.abs(st.dofmap.to_dofs(u)[st.solver.fixed]).max() == 0.0


@pytest.fixture(scope="module")
def beam_case(tmp_path_factory):
    d = tmp_path_factory.mktemp("case")
    case = d / "beam_and_wall.toml"
    case.write_text(BEAM.format(box=(ROOT / "models" / "validation" / "box.py").as_posix()))
    return case


def test_modes_json_and_files(beam_case, tmp_path):
    """``--json``: exactly the documented object on stdout; the rigid wall is skipped;
    modes.h5 holds the frequencies and shapes, modes.xdmf one frame per mode (meshio)."""
    r = run_pdfem("modes", str(beam_case), "--n", "3", "--out", str(tmp_path), "--json")
    assert r.returncode == 0, r.stderr
    report = json.loads(r.stdout)
    assert list(report) == ["structures"] and list(report["structures"]) == ["beam"]
    beam = report["structures"]["beam"]
    assert set(beam) == {"frequencies_hz", "n_nodes", "n_elements"}
    assert len(beam["frequencies_hz"]) == 3 and beam["n_elements"] == 80
    with h5py.File(tmp_path / "modes.h5") as f:
        np.testing.assert_allclose(f["structures/beam/frequencies_hz"][:], beam["frequencies_hz"])
        assert f["structures/beam/shapes"].shape == (3, beam["n_nodes"], 3)
        shape2 = f["structures/beam/shapes"][2]
    reader = meshio.xdmf.TimeSeriesReader(tmp_path / "modes.xdmf")
    points, _ = reader.read_points_cells()
    assert reader.num_steps == 3 and len(points) == beam["n_nodes"]
    t, data, _ = reader.read_data(2)
    assert t == 3.0 and np.array_equal(data["mode_shape"], shape2)
    assert data["frequency_hz"][0] == beam["frequencies_hz"][2]


def test_modes_table_says_rigid_skipped(beam_case, tmp_path):
    r = run_pdfem("modes", str(beam_case), "--n", "2", "--out", str(tmp_path))
    assert r.returncode == 0, r.stderr
    assert "'wall' is rigid" in r.stdout and "skipped" in r.stdout
    assert "mode   frequency [Hz]" in r.stdout and (tmp_path / "modes.xdmf").is_file()


@pytest.mark.parametrize("args, words", [
    (["--n", "0"], "--n"),
    (["--structure", "nope"], "no structure of that name"),
    (["--structure", "wall"], "only elastic structures"),
    (["--n", "100000"], "free degrees of freedom"),
])
def test_bad_input_exits_2_with_one_paragraph(beam_case, tmp_path, args, words):
    r = run_pdfem("modes", str(beam_case), "--out", str(tmp_path), *args)
    assert r.returncode == 2 and words in r.stderr
    assert "Traceback" not in r.stderr and r.stderr.strip().count("\n") == 0


ATTACHED = """
[run]
end_time = 1e-3
{hull}
[[structure]]
name = "beam"
mesh = "{box}"
params = {{ length_x = 1.0, length_y = 0.1, length_z = 0.1, divisions_x = 10, divisions_y = 1, divisions_z = 1, fixed_faces = "x0", contact_faces = "x1" }}
fixed_groups = ["fixed"]
element_order = 1
{attached}
"""

HULL = """
[water]

[[structure]]
name = "hull"
kind = "ship"
mesh = "{box}"
params = {{ surface_only = true, origin_x = -0.5, origin_y = -0.5, origin_z = -0.1, length_x = 2.0, length_y = 1.0, length_z = 0.2, element_size = 0.1 }}
"""


def test_structure_on_a_ship_has_its_modes_on_its_supports(tmp_path):
    """A beam attached to a ship: ``pdfem modes`` skips the ship and gives the beam the modes
    of the same beam clamped on its own (the hull held still), to round-off."""
    from pdfem.cli.modes import compute
    box = (ROOT / "models" / "validation" / "box.py").as_posix()
    files = {}
    for name, hull, attached in (("alone", "", ""),
                                 ("on_ship", HULL.format(box=box), 'attached_to = "hull"')):
        files[name] = tmp_path / f"{name}.toml"
        files[name].write_text(ATTACHED.format(box=box, hull=hull, attached=attached))
    said = []
    alone = compute(load_case(files["alone"]), tmp_path / "a", None, 3, said.append)
    on_ship = compute(load_case(files["on_ship"]), tmp_path / "b", None, 3, said.append)
    assert [m.name for m in on_ship] == ["beam"] and "'hull' is ship" in said[0]
    np.testing.assert_allclose(on_ship[0].frequencies_hz, alone[0].frequencies_hz, rtol=1e-12)
