"""The most steps a run may take to its end time, and the field a run of more is refused by.

A run of more than :data:`MAX_STEPS` steps on either side (the ice, the structures) could not
finish: a coupling step of the smallest case costs about 2 ms (measured: 8 ice particles over
a structure of 4 hexahedra, 216 steps in 0.43 s) and writes a history row, and a substep of
either side tens of microseconds at the least, so 10^9 steps are days to weeks of wall time.
The longest case in ``models/`` takes 47,000 ice steps.
Such a count comes from a step that is far too small (an explicit ``run.time_step``, a small
``run.safety_factor``, a material whose wave speed no solid has, a ``run.substeps`` too large)
or from an ``end_time`` far too long; the refusal (exit 2) names the first of these whose usual
value would give a run of at most :data:`MAX_STEPS` steps, and ``run.end_time`` if none would.
A stable step that is zero or not a number (an underflow, an overflow) counts as infinitely many
steps. Units: SI (s, m/s, Pa, kg/m^3).
"""

from __future__ import annotations

import math

from pdfem.case.schema import Case
from pdfem.errors import InputError

MAX_STEPS = 10**9
"""Most steps either side of a run (ice, structures) may take to ``end_time``."""

MAX_WAVE_SPEED = 2.0e4
"""m/s, above the bar wave speed sqrt(E / density) of every solid: diamond, the stiffest (E about
1.05e12 Pa, density 3515 kg/m^3), has 1.7e4 m/s; steel 5.2e3, ice 2.1e3. A material faster
than this is named as the cause of a step too small."""


def step_count(end_time: float, step: float) -> float:
    """Steps of ``step`` (s) to ``end_time`` (s); ``inf`` for a step that is not > 0 (zero or
    NaN from an underflow or an overflow)."""
    return end_time / step if step > 0.0 else math.inf


def wave_speed(youngs_modulus: float, density: float) -> float:
    """The bar wave speed sqrt(E / density) (m/s), ``inf`` when the quotient overflows."""
    return math.sqrt(youngs_modulus / density)  # a float quotient overflows to inf


def _material(field: str, youngs_modulus: float, density: float,
              step: float) -> tuple[str, str] | None:
    """(field, advice) naming the material at ``field`` if no solid has its wave speed, or if
    the ``step`` it gives is not > 0 (its stiffness over mass overflowed)."""
    c = wave_speed(youngs_modulus, density)
    if c <= MAX_WAVE_SPEED and step > 0.0:
        return None
    return (f"{field}.material",
            f"its youngs_modulus = {youngs_modulus:.4g} Pa and density = {density:.4g} kg/m^3 give "
            f"a wave speed sqrt(E / density) of {c:.3g} m/s (no solid is faster than "
            f"{MAX_WAVE_SPEED:.0e} m/s: diamond has 1.7e4, steel 5.2e3, ice 2.1e3); check both "
            "values (Pa, kg/m^3)")


def _refuse(case: Case, what: str, step: float, blame: tuple[str, str]) -> InputError:
    """The refusal: ``what`` would take too many steps of ``step`` (s); ``blame`` is the field
    and the advice."""
    run = case.run
    field, advice = blame
    value = {"run.time_step": run.time_step, "run.safety_factor": run.safety_factor,
             "run.end_time": run.end_time}.get(field, ...)
    steps = (f"{step_count(run.end_time, step):.3g} steps of {step:.3g} s" if step > 0.0 else
             f"infinitely many steps (its step is {step:g} s: an underflow or an overflow)")
    return InputError(case.file, field,
                      f"the {what} would take {steps} to end_time = {run.end_time:g} s, more "
                      f"than the {MAX_STEPS:.0e} a run can finish (days of wall time and as many "
                      f"history rows); {advice}", value)


def _safety_factor(case: Case, stable: float) -> tuple[str, str] | None:
    """(field, advice) naming ``run.safety_factor`` if the usual 0.8 x ``stable`` (s) would
    give at most :data:`MAX_STEPS` steps."""
    end = case.run.end_time
    if step_count(end, 0.8 * stable) > MAX_STEPS:
        return None
    return ("run.safety_factor", f"choose safety_factor >= {end / MAX_STEPS / stable:.3g} "
                                 "(usual: 0.8, the default)")


def _end_time(step: float, larger: str) -> tuple[str, str]:
    return ("run.end_time", f"choose end_time <= {MAX_STEPS * step:.3g} s, or {larger}")


def check_ice_steps(case: Case, stable: list[float]) -> None:
    """Refuse a run whose ice (or, without ice, its given ``run.time_step``) would take more than
    :data:`MAX_STEPS` steps (module docstring).

    Parameters
    ----------
    case
        The validated case.
    stable
        The stable step (s) of each ice body of ``case``, in its order.

    Raises
    ------
    InputError
        Naming ``run.time_step``, ``run.safety_factor``, the material of the body with the
        smallest step or ``run.end_time``, with the valid range.
    """
    run = case.run
    k = min(range(len(stable)), key=lambda j: stable[j] if stable[j] > 0.0 else -1.0,
            default=None)
    auto = run.safety_factor * stable[k] if k is not None else math.inf
    step = run.time_step if run.time_step is not None else auto
    if step_count(run.end_time, step) <= MAX_STEPS:
        return
    least = run.end_time / MAX_STEPS
    if run.time_step is not None and (k is None or step_count(run.end_time, auto) <= MAX_STEPS):
        raise _refuse(case, "run" if k is None else "ice", step, (
            "run.time_step", f"choose time_step >= end_time / {MAX_STEPS:.0e} = {least:.3g} s"
                             + (", or a shorter end_time" if k is None else
                                f", or leave it out (the automatic step is {auto:.3g} s)")))
    cfg = case.ice[k]
    blame = (_safety_factor(case, stable[k])
             or _material(cfg.field, cfg.material.youngs_modulus, cfg.material.density, step)
             or _end_time(step, f"a larger {cfg.field}.dx (m; the stable step is about dx / "
                                "wave speed)"))
    raise _refuse(case, f"ice of body '{cfg.name}' ({cfg.field})", step, blame)


def _damping(field: str, beta: float, critical: float, safety: float,
             end_time: float) -> tuple[str, str] | None:
    """(field, advice) naming the damping at ``field`` if its ``beta`` (s) is what makes the
    ``critical`` step (s) too small: without it the step would be ``sqrt(dt (dt + 2 beta))``
    (from ``dt = 2 / (w (sqrt(1 + xi^2) + xi))``, ``xi = beta w / 2``); a step that is 0 with
    damping is put down to it."""
    if beta <= 0.0:
        return None
    undamped = math.sqrt(critical * (critical + 2.0 * beta)) if critical > 0.0 else 0.0
    if critical > 0.0 and step_count(end_time, safety * undamped) > MAX_STEPS:
        return None
    return (f"{field}.damping.beta",
            f"its stiffness-proportional damping beta = {beta:.3g} s shrinks the critical step "
            + (f"from about {undamped:.3g} s " if undamped > 0.0 else "") + "(the highest "
            "mode's damping ratio is beta / the undamped step); choose a beta (s) well below "
            "the undamped critical step")


def check_structure_steps(case: Case, structures: list, critical: list[float]) -> None:
    """Refuse a run whose structures would take more than :data:`MAX_STEPS` steps of
    ``run.safety_factor`` x their critical step (module docstring).

    Parameters
    ----------
    case
        The validated case.
    structures
        The built structures (their ``name``).
    critical
        The critical step (s) of each structure (``inf``: no limit).

    Raises
    ------
    InputError
        Naming ``run.safety_factor``, the material or the damping of the structure with the
        smallest step, or ``run.end_time``.
    """
    run = case.run
    if not structures:
        return
    k = min(range(len(critical)), key=lambda j: critical[j] if critical[j] > 0.0 else -1.0)
    step = run.safety_factor * critical[k]
    if step_count(run.end_time, step) <= MAX_STEPS:
        return
    cfg = {c.name: c for c in case.structures}[structures[k].name]
    material = _material(cfg.field, cfg.youngs_modulus, cfg.density, math.inf)
    blame = (_safety_factor(case, critical[k]) or material
             or _damping(cfg.field, cfg.damping_beta, critical[k], run.safety_factor,
                         run.end_time)
             or _material(cfg.field, cfg.youngs_modulus, cfg.density, step)
             or _end_time(step, f"larger elements in {cfg.field}.mesh (the critical step is "
                                "about element size / wave speed)"))
    raise _refuse(case, f"structure '{cfg.name}' ({cfg.field})", step, blame)


def check_substeps(case: Case, coupling_steps: int, ice: int, structure: int) -> None:
    """Refuse a ``run.substeps`` that makes the faster side take more than :data:`MAX_STEPS`
    steps: ``coupling_steps`` x its substeps per coupling step.

    Raises
    ------
    InputError
        Naming ``run.substeps`` (or ``run.end_time`` when it is automatic) and its bound.
    """
    run = case.run
    total = coupling_steps * max(ice, structure)
    if total <= MAX_STEPS:
        return
    side = "ice" if ice >= structure else "structures"
    text = (f"{max(ice, structure):,} substeps of the {side} in each of {coupling_steps:,} "
            f"coupling steps make {total:.3g} steps to end_time = {run.end_time:g} s, more than "
            f"the {MAX_STEPS:.0e} a run can finish (days of wall time)")
    if run.substeps:
        raise InputError(case.file, "run.substeps", text + f"; choose substeps <= "
                         f"{max(1, MAX_STEPS // coupling_steps):,}, or 0 (automatic)",
                         run.substeps)
    raise InputError(case.file, "run.end_time", text + "; choose a shorter end_time (s)",
                     run.end_time)
