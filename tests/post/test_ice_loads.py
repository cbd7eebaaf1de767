"""Ice-engineering loads: contact pressure per facet, load patches, pressure-area, low-pass.

References: conservation of the contact impulse (the facet shares of every contact sum to the
impulse the structure took, so the patches of a partitioned contact surface sum to the
structure's total load, to round-off); the definition p = J_n / (A T) (the pressure field
integrates back to the normal impulse of the interval, which on a flat face with outward
normal +z is minus the z impulse of the load history); the pressure-area curve at the full
contact area is the total normal force over the contact area by definition (ISO 19906 local
pressure: mean pressure over the loaded area); the analytic gain of a zero-phase digital
Butterworth filter, |H|^2 = 1 / (1 + (tan(pi f/fs) / tan(pi fc/fs))^(2N)) (Oppenheim &
Schafer, "Discrete-Time Signal Processing", 3rd ed., 2010, 7.2.1: bilinear transform).
"""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from pdfem.case.schema import load_case
from pdfem.cli import main as cli
from pdfem.coupling.nodal_impulse import ContactRecords
from pdfem.meshing import gmsh_session
from pdfem.output import read_results
from pdfem.post.lowpass import gain, lowpass
from pdfem.post.pressure_area import facet_neighbours, pressure_area_curve
from pdfem.run.driver import run_case

CASE = """
[run]
end_time = 6e-4
output_interval = 1e-4

[[ice]]
name = "cube"
dx = 0.01
shape = { box = { min = [0.07, 0.07, 0.0355], max = [0.13, 0.13, 0.0955] } }
material = { density = 900.0, youngs_modulus = 4.1e9, poisson_ratio = 0.3, fracture_energy = 1.0 }
initial_velocity = [0.0, 0.0, -3.0]

[[structure]]
name = "block"
mesh = "block.msh"
element_order = 1
material = { density = 7850.0, youngs_modulus = 210e9, poisson_ratio = 0.3 }
fixed_groups = ["fixed"]
contact_group = "contact"

[[contact]]
ice = "cube"
structure = "block"
"""


def _two_part_block(path, size=0.025):
    """A 0.2 x 0.2 x 0.04 m block of two fused halves (x < 0.1, x > 0.1): its top face is two
    gmsh surfaces, groups ``left`` and ``right``; ``contact`` is both, ``fixed`` the base."""
    with gmsh_session("block") as gmsh:
        occ = gmsh.model.occ
        a = occ.addBox(0, 0, 0, 0.1, 0.2, 0.04)
        b = occ.addBox(0.1, 0, 0, 0.1, 0.2, 0.04)
        occ.fragment([(3, a)], [(3, b)])
        occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMin", size)
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        top, base = {}, []
        for _, s in gmsh.model.getEntities(2):
            x, _, z = occ.getCenterOfMass(2, s)
            if abs(z - 0.04) < 1e-9:
                top["left" if x < 0.1 else "right"] = s
            elif abs(z) < 1e-9:
                base.append(s)
        gmsh.model.addPhysicalGroup(3, [v for _, v in gmsh.model.getEntities(3)], name="solid")
        gmsh.model.addPhysicalGroup(2, list(top.values()), name="contact")
        gmsh.model.addPhysicalGroup(2, [top["left"]], name="left")
        gmsh.model.addPhysicalGroup(2, [top["right"]], name="right")
        gmsh.model.addPhysicalGroup(2, base, name="fixed")
        gmsh.model.mesh.generate(3)
        gmsh.write(str(path))


@pytest.fixture(scope="module")
def struck(tmp_path_factory):
    d = tmp_path_factory.mktemp("iceloads")
    _two_part_block(d / "block.msh")
    (d / "case.toml").write_text(CASE)
    summary = run_case(load_case(d / "case.toml"), d / "out", quiet=True)
    return summary.results, read_results(summary.results)


def test_patch_forces_sum_to_the_structure_load(struck):
    """The patches ``left`` and ``right`` partition the contact surface: their forces sum to the
    structure's total ice load at every step, to round-off; both are loaded (the cube straddles
    x = 0.1) and each patch's area is half the top face."""
    _, r = struck
    h = r["histories"]
    total = h["loads/block"]["force"]
    left, right = h["loads/block.left"]["force"], h["loads/block.right"]["force"]
    assert np.abs(total).max() > 0 and np.abs(left).max() > 0 and np.abs(right).max() > 0
    np.testing.assert_allclose(left + right, total, rtol=0, atol=1e-12 * np.abs(total).max())
    assert h["loads/block.left"]["area"][0] == pytest.approx(0.02, rel=1e-9)
    assert h["loads/block.right"]["area"][0] == pytest.approx(0.02, rel=1e-9)


def test_facet_pressure_integrates_to_the_contact_force(struck):
    """sum_f p_f A_f over a frame interval is the mean normal contact force of the interval:
    on the flat top face (outward normal +z) minus the mean z force of the load history over
    the steps of that interval (frictionless contact)."""
    _, r = struck
    s = r["structure"]["block.contact"]
    tri = s["cells"]
    x = s["points"][tri]
    area = 0.5 * np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1)
    load = r["histories"]["loads/block"]
    t = r["time"]
    for k in range(1, len(t)):
        steps = (load["time"] > t[k - 1] * (1 + 1e-9)) & (load["time"] <= t[k] * (1 + 1e-9))
        mean_fz = -load["force"][steps, 2].mean()
        np.testing.assert_allclose((s["contact_pressure"][k] * area).sum(), mean_fz,
                                   rtol=1e-6, atol=1e-9 * np.abs(load["force"]).max())
    assert s["contact_pressure"].max() > 0
    np.testing.assert_array_equal(s["contact_pressure_max"][-1], s["contact_pressure"].max(axis=0))


def test_pressure_area_at_full_contact_is_force_over_area(struck):
    """For every frame the patch-growth curve ends at the whole contact area with the total
    normal force / contact area, and starts at the peak facet's pressure."""
    _, r = struck
    s = r["structure"]["block.contact"]
    x = s["points"][s["cells"]]
    area = 0.5 * np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1)
    nb = facet_neighbours(s["cells"])
    checked = 0
    for p in s["contact_pressure"]:
        a, mean = pressure_area_curve(p, area, nb)
        if not len(a):
            continue
        on = p > 0
        assert a[-1] == pytest.approx(area[on].sum(), rel=1e-12)
        assert mean[-1] == pytest.approx((p * area).sum() / area[on].sum(), rel=1e-12)
        assert mean[0] == p.max()
        assert np.all(np.diff(a) > 0)
        checked += 1
    assert checked >= 2


def test_post_json_and_xdmf_carry_the_loads(struck, capsys):
    """``pdfem post --json --lowpass`` carries the pressure-area envelope, the patch loads and
    raw and filtered peaks; the XDMF file shows the contact pressure on the surface's cells."""
    path, r = struck
    capsys.readouterr()
    assert cli.main(["post", str(path), "--json", "--lowpass", "20000"]) == 0
    s = json.loads(capsys.readouterr().out)
    pa = s["contact_pressure"]["block"]["pressure_area"]
    assert len(pa["area"]) == len(pa["envelope"]) and max(v or 0 for v in pa["envelope"]) > 0
    assert set(s["patches"]) == {"block.left", "block.right"}
    assert s["patches"]["block.left"]["filtered"]["cutoff"] == 20000
    assert "block.contact" not in s["structures"]
    assert s["loads"]["block"]["filtered"]["magnitude"]["peak"] <= \
        s["loads"]["block"]["magnitude"]["per_step_peak"] * 1.5
    assert s["load_split"]["block"]["main"] == "cube-block" or s["load_split"]["block"]["pairs"]
    root = ET.parse(path.with_suffix(".xdmf")).getroot()
    names = {a.get("Name"): a.get("Center") for a in root.iter("Attribute")}
    assert names["contact_pressure"] == "Cell" and names["contact_pressure_max"] == "Cell"
    assert cli.main(["post", str(path), "--lowpass", "1e9"]) == 2  # above Nyquist: exit 2


def test_lowpass_gain_of_a_sine_is_the_butterworth_gain():
    """A sine at f through the zero-phase filter keeps its phase and is scaled by |H(f)|^2 of
    the single pass (analytic, module docstring), at, below and above the cut-off."""
    fs, fc = 1.0e5, 2.0e3
    t = np.arange(20000) / fs
    for f in (500.0, 2000.0, 4000.0):
        y = np.sin(2 * np.pi * f * t)
        out = lowpass(t, np.stack([y, 2 * y], axis=1), fc)
        mid = slice(5000, 15000)  # away from the ends
        expected = gain(f, fc, fs)
        np.testing.assert_allclose(out[mid, 0], expected * y[mid], atol=2e-4)
        np.testing.assert_allclose(out[mid, 1], 2 * expected * y[mid], atol=4e-4)
    assert gain(fc, fc, fs) == pytest.approx(0.5)
    with pytest.raises(ValueError, match="Nyquist"):
        lowpass(t, t, fs)


def test_facet_sums_do_not_depend_on_the_rank_split():
    """The per-facet impulses of contacts split over two 'ranks' (gathered, summed in global
    particle order) equal the serial ones bit for bit; they sum to the nodal impulses' total."""
    rng = np.random.default_rng(4)
    tri = np.array([[0, 1, 2], [1, 3, 2], [2, 3, 4]])
    n = 50
    ids, facet = rng.permutation(n), rng.integers(0, 3, n)
    w = rng.random((n, 3))
    w /= w.sum(axis=1, keepdims=True)
    imp, normal = rng.standard_normal((n, 3)), rng.random(n)
    serial = ContactRecords(5, tri)
    serial.add(ids, facet, w, imp, normal)
    nodal = serial.take()
    fs, ns = serial.take_facets()
    ranks = [ContactRecords(5, tri), ContactRecords(5, tri)]
    half = [slice(0, 20), slice(20, n)]
    for rec, sl in zip(ranks, half):
        rec.add(ids[sl], facet[sl], w[sl], imp[sl], normal[sl])
    gathered = [ranks[0].calls, ranks[1].calls]
    for rec in ranks:
        rec.take(lambda calls: gathered)
    for rec in ranks:
        f, nn = rec.take_facets()
        np.testing.assert_array_equal(f, fs)
        np.testing.assert_array_equal(nn, ns)
    np.testing.assert_allclose(fs.sum(axis=0), nodal.sum(axis=0), rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(fs.sum(axis=0), -imp.sum(axis=0), rtol=1e-13, atol=1e-13)


def test_load_split_names_the_main_pair():
    """Two ice bodies on one structure (pairs named by default "<ice>-<structure>"): the pair
    with the larger impulse (time integral of the force, trapezoid rule) is the main load, the
    shares are the impulses over their sum."""
    from pdfem.post.ice_loads import load_split

    t = np.linspace(0.0, 1.0, 11)
    sheet = np.zeros((11, 3))
    sheet[:, 2] = -300.0                    # 300 N s over 1 s
    floe = np.zeros((11, 3))
    floe[5, 2] = -1000.0                    # one hit: 1000 N x 0.1 s = 100 N s
    case = ('[[ice]]\nname = "sheet"\n[[ice]]\nname = "floe"\n'
            '[[structure]]\nname = "panel"\n')
    results = {"meta": {"case": case}}
    split = load_split(results, {"sheet-panel": {"time": t, "force": sheet},
                                 "floe-panel": {"time": t, "force": floe}})
    s = split["panel"]
    assert s["main"] == "sheet-panel"
    assert s["pairs"]["sheet-panel"]["impulse"] == pytest.approx(300.0)
    assert s["pairs"]["floe-panel"]["impulse"] == pytest.approx(100.0)
    assert s["pairs"]["floe-panel"]["share"] == pytest.approx(0.25)
