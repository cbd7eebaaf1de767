"""The icebreaker's elastic bow panel (models/bow_panel.py, pdfem/motion/attached_frame.py,
docs/icebreaking.md): towed with the rigid hull through level ice, and riding on a free ship.
SI units. References: Newton's third law at the contact (the impulse the ice receives from the
panel is minus the panel's), the energy balance of the run, and the momentum balance of ship +
panel (its change equals the external impulses: the pressure pulse's p A t_eff n and the ship's
gravity, hydrostatics)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from pdfem.case.schema import load_case
from pdfem.coupling.contact import SurfaceContact
from pdfem.meshing import check_parameters
from pdfem.models import bow_panel
from pdfem.output import read_results
from pdfem.run.build_structures import build_structure
from pdfem.run.driver import run_case

CASES = Path(__file__).resolve().parents[2] / "models" / "validation"


def test_panel_sits_on_the_bow_entrance_plane():
    """The panel's inner plating face lies on the hull's port entrance plane
    y = tan(a) (L/2 + z / tan(phi) - x) (models/icebreaker.py), its normal is the plane's
    outward normal (tan a, 1, -tan a / tan phi) / |.|, and its centre is at the bow_panel
    group's centre x = L/2 - L_entr / 4 on the waterline."""
    p = check_parameters(bow_panel.PARAMETERS, {"length": 1.5, "beam": 0.3})
    Q, o = bow_panel.placement(p)
    ta, ts = np.tan(np.radians(30.0)), np.tan(np.radians(25.0))
    n = np.array([ta, 1.0, -ta / ts]) / np.linalg.norm([ta, 1.0, -ta / ts])
    np.testing.assert_allclose(Q[:, 2], n, atol=1e-12)
    np.testing.assert_allclose(Q.T @ Q, np.eye(3), atol=1e-12)
    inner = o + Q @ np.array([0.5 * p["panel_length"], 0.5 * p["panel_breadth"], -0.003])
    entr = 0.15 / ta
    assert inner[0] == pytest.approx(0.75 - entr / 4, abs=1e-12)
    assert inner[2] == pytest.approx(0.0, abs=1e-12)
    for a in (0.0, p["panel_length"]):
        for b in (0.0, p["panel_breadth"]):
            x = o + Q @ np.array([a, b, -0.003])
            assert x[1] == pytest.approx(ta * (0.75 + x[2] / ts - x[0]), abs=1e-12)


@pytest.mark.slow
def test_towed_panel_loaded_by_the_ice_balances_energy_and_impulse(tmp_path, monkeypatch):
    """The towed tiny case (hull and panel at 0.5 m/s, the sheet notched to the bow) runs
    through the energy guard (residual within 1 % of the work in); the ice loads the panel,
    and the impulse the ice receives from the panel (summed over its particles) is minus the
    impulse handed to the panel's nodes, and the panel's load history integrates to it."""
    on_ice: dict[str, np.ndarray] = {}
    on_nodes: dict[str, np.ndarray] = {}
    resolve, take = SurfaceContact.resolve, SurfaceContact.take_impulse

    def resolve_spy(self, *args, **kwargs):
        step = resolve(self, *args, **kwargs)
        on_ice[self.name] = on_ice.get(self.name, 0.0) + step.row_impulse.sum(axis=0)
        return step

    def take_spy(self, *args, **kwargs):
        j = take(self, *args, **kwargs)
        on_nodes[self.name] = on_nodes.get(self.name, 0.0) + j.sum(axis=0)
        return j

    monkeypatch.setattr(SurfaceContact, "resolve", resolve_spy)
    monkeypatch.setattr(SurfaceContact, "take_impulse", take_spy)
    case = load_case(CASES / "icebreaker_panel_tiny.toml")
    summary = run_case(case, tmp_path / "towed", quiet=True)
    res = read_results(summary.results)
    e = res["histories"]["energy"]
    assert abs(e["residual"][-1]) <= 0.01 * e["supplied"][-1]
    panel = res["histories"]["loads/panel"]
    t = panel["time"]
    impulse = (panel["force"][1:] * np.diff(t)[:, None]).sum(axis=0)   # N s, on the panel
    assert np.linalg.norm(impulse) > 1e-3                               # loaded by the ice
    ice, nodes = on_ice["sheet-panel"], on_nodes["sheet-panel"]
    np.testing.assert_allclose(ice, -nodes, rtol=0, atol=1e-12 * np.abs(nodes).max())
    np.testing.assert_allclose(impulse, nodes, rtol=1e-9, atol=1e-12)
    monitor = res["histories"]["monitors/bay1_mid"]
    assert monitor["von_mises"].max() > 0.0                             # stressed plating


def _free_ship(tmp_path: Path, name: str, pulse: bool, end_time: float) -> dict:
    """Run the free-ship case (with or without its pressure pulse) to ``end_time`` (s)."""
    case = load_case(CASES / "icebreaker_free_ship_tiny.toml")
    hull, panel = case.structures
    if not pulse:
        panel = dataclasses.replace(panel, loads=())
    run = dataclasses.replace(case.run, end_time=end_time, output_interval=end_time)
    case = dataclasses.replace(case, run=run, structures=(hull, panel))
    return read_results(run_case(case, tmp_path / name, quiet=True).results)


@pytest.mark.slow
def test_free_ship_with_panel_at_rest_does_not_drift(tmp_path):
    """The free hull with the panel attached, in calm water with nothing on it: its centre of
    gravity moves less than 1 mm (here: nothing at all to round-off) and the panel hands it
    no impulse."""
    res = _free_ship(tmp_path, "rest", pulse=False, end_time=0.01)
    m = res["histories"]["motions/hull"]
    drift = np.linalg.norm(m["position"] - m["position"][0], axis=1).max()
    assert drift < 1e-3
    assert np.abs(m["attached_impulse"]).max() < 1e-12


@pytest.mark.slow
def test_panel_pulse_reaches_the_ship_through_its_supports(tmp_path):
    """A pressure pulse p = 20 kPa on the panel's plating (area A = 0.08 m x 0.04 m, pulse
    2 ms rise, 5 ms hold, 2 ms fall: t_eff = 7 ms) pushes along -n, the plating's outward
    normal: impulse J = -p A t_eff n = 0.448 N s. Momentum of ship + panel: m (v - v0) =
    J + (the ship's gravity + hydrostatic + thrust impulse), the panel's own elastic momentum
    at the end being small (0.2 % of J allowed). Without the hand-over through the supports the
    ship would not move at all. Energy: the run passes the guard, residual < 1e-6 of the work in."""
    res = _free_ship(tmp_path, "pulse", pulse=True, end_time=0.013)
    p = check_parameters(bow_panel.PARAMETERS, {"length": 1.5, "beam": 0.3})
    Q, _ = bow_panel.placement(p)
    J = -2.0e4 * p["panel_length"] * p["panel_breadth"] * 0.007 * Q[:, 2]
    m = res["histories"]["motions/hull"]
    case = load_case(CASES / "icebreaker_free_ship_tiny.toml")
    ship = build_structure(case.structures[0], tmp_path / "mesh", case.file)
    change = ship.mass * (m["velocity"][-1] - m["velocity"][0])
    np.testing.assert_allclose(change, J + m["external_impulse"][-1], rtol=0,
                               atol=2e-3 * np.linalg.norm(J))
    np.testing.assert_allclose(m["attached_impulse"][-1], J, rtol=0, atol=2e-3 * np.linalg.norm(J))
    e = res["histories"]["energy"]
    assert abs(e["residual"][-1]) <= 1e-6 * e["supplied"][-1]


def test_attached_structures_follow_their_ship_by_name():
    """A structure riding on a ship is stepped right after it, wherever the case lists the ship
    (the ship must reach t + h first: pdfem/motion/attached_frame.py); other structures keep
    the case order."""
    from types import SimpleNamespace as S

    from pdfem.run.build_structures import stepping_order

    cfgs = [S(name="panel", attached_to="hull"), S(name="wall", attached_to=None),
            S(name="hull", attached_to=None), S(name="deck", attached_to="hull")]
    assert stepping_order(cfgs) == [1, 2, 0, 3]
    ordered = [S(name="hull", attached_to=None), S(name="panel", attached_to="hull")]
    assert stepping_order(ordered) == [0, 1]


def test_attached_to_must_name_a_ship(tmp_path):
    """``attached_to`` naming no ship of the case is refused naming the file, the field and
    what is valid; so is it with a motion (both by the schema, before anything is meshed)."""
    from pdfem.case.schema import parse_case
    from pdfem.errors import InputError

    text = (CASES / "icebreaker_free_ship_tiny.toml").read_text()
    with pytest.raises(InputError) as err:
        parse_case(text.replace('attached_to = "hull"', 'attached_to = "hul"'), "bad.toml", CASES)
    msg = err.value.text()
    assert "bad.toml" in msg and "structure[1].attached_to" in msg and "hull" in msg
    with pytest.raises(InputError) as err:
        parse_case(text.replace('attached_to = "hull"', 'attached_to = "hull"\nmotion = '
                                '{ velocity = [1.0, 0.0, 0.0] }'), "bad.toml", CASES)
    assert "attached_to" in err.value.text()


def test_frame_path_kink_keeps_the_nodes_world_velocity(tmp_path):
    """A moving frame on a path whose velocity jumps from 0 to 0.5 m/s at t = 9e-6 s: in the
    step over the kink the supported nodes take the frame's new velocity, the free nodes keep
    their world velocity (0, to the elastic response of one step: < 5 % of the jump), and the drive's work is
    the kinetic-energy change of the elastic motion (1/2 m_free 0.5^2)."""
    from pdfem.motion.moving_frame import MovingFrame
    from pdfem.motion.frame_structure import FrameStructure
    from pdfem.fem.elasticity import ElasticMaterial

    case = load_case(CASES / "icebreaker_panel_tiny.toml")
    mesh = build_structure(case.structures[1], tmp_path, case.file)   # meshes the panel
    frame = MovingFrame(path=((0.0, 0.0, 0.0, 0.0), (9e-6, 0.0, 0.0, 0.0),
                              (1.0, 0.5 * (1.0 - 9e-6), 0.0, 0.0)))
    st = FrameStructure.from_file(tmp_path / "panel.msh", ElasticMaterial(7850.0, 4.2e9, 0.3),
                                  fixed_groups=["fixed"], contact_group="contact",
                                  element_order=1, frame=frame)
    assert mesh.n_nodes == st.n_nodes
    dt = 2e-6
    for _ in range(5):                                # to t = 1e-5 s, the kink in the last step
        st.step(dt)
    r, v = st.relative_motion()
    _, world = frame.to_world(st.solver.time, r, v)
    fixed = st.group_nodes("fixed")
    free = np.setdiff1d(np.arange(st.n_nodes), fixed)
    np.testing.assert_allclose(world[fixed], [[0.5, 0.0, 0.0]] * len(fixed), atol=1e-12)
    speed = np.linalg.norm(world[free], axis=1)
    # one step's elastic response to the supports' jump (here up to 3 %); without the jump of
    # u_e' the free nodes would move at the frame's 0.5 m/s at once
    assert speed.max() < 0.05 * 0.5
    m = st.dofmap.to_nodal(st.solver.m)[:, 0]
    kick = 0.5 * m[free].sum() * 0.5 ** 2
    assert st.frame_history()["drive_work"] == pytest.approx(kick, rel=1e-9)
