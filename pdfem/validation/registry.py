"""The registry of validation cases: one line per case module of :mod:`pdfem.validation.cases`.

To add a case: write its case file ``models/validation/<file>.toml`` and a module
``pdfem/validation/cases/<module>.py`` exporting ``CASES`` (a tuple of
:class:`~pdfem.validation.case.ValidationCase`), then add the module's name to ``MODULES``.
"""

from __future__ import annotations

from importlib import import_module

from pdfem.validation.case import ValidationCase

MODULES: tuple[str, ...] = (
    "wave_speed",          # bar_wave_speed.toml: wave speed in a fixed-free bar
    "elastic_constants",   # lps_block_tension.toml: E and nu of the LPS
    "cantilever",          # cantilever_frequency*.toml: first bending frequency (explicit, implicit)
    "coupled_impact",      # coupled_impact*.toml: momentum and energy in an impact (explicit, implicit)
    "loop_agreement",      # sphere_ice_loops.toml: pair loop vs full-family loop
    "rigid_wall",          # bar_rigid_wall.toml, bar_elastic_wall_implicit.toml: duration and force
    "panel_reaction",      # panel_pressure_reaction.toml: support reaction p A
    "plate",               # plate_clamped.toml, plate_simply_supported.toml: f1 and deflection
    "panel_modes",         # panel_modes.toml: demo panel f1..f5 vs the mesh refined 2x
    "coupled_step",        # demo_step_sweep.toml: energy and ice load at several steps
    "compression",         # ice_prism_compression*.toml: peak and residual strength, 2 dx
    "edge_crushing",       # ice_edge_crushing.toml: crushing regime against a rigid wall
    "bending",             # ice_beam_bending_*.toml: flexural strength, 3- and 4-point, dx, dx/2
    "floating",            # floating_draught.toml, floating_heave.toml: draught, heave period
    "winkler",             # floating_plate_winkler.toml: P / w0 and l of a plate on water
    "ship",                # ship_rest.toml, ship_heave.toml, ship_pitch.toml: drift, periods
    "attached",            # ship_attached_plate*.toml: a ship carrying a plate at rest, pulled
    "spinning",            # spinning_bar*.toml: radial stress, flapwise frequency (Southwell)
    "root_stress",         # spinning_bar_root_stress.toml, propeller_root_stress.toml: nominal root stress
    "shaft_energy",        # shaft_energy*.toml: shaft + ice work and angular impulse (explicit, implicit)
    "milling",             # propeller_milling_tiny.toml: impulse balance, torque spectrum at Z n
    "icebreaking",         # icebreaker_tiny.toml: resistance vs Lindqvist, pieces under the hull
)
"""The case modules, in the order of the report."""


def all_cases() -> tuple[ValidationCase, ...]:
    """Every registered validation case, in registry order.

    Raises
    ------
    ValueError
        If two cases share a name.
    """
    cases = tuple(c for m in MODULES for c in import_module(f"pdfem.validation.cases.{m}").CASES)
    names = [c.name for c in cases]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ValueError(f"validation case names must be unique: {', '.join(twice)}")
    return cases
