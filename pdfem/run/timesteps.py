"""The time steps of a run: the coupling step and the substeps of the ice and the structures."""

from __future__ import annotations

import math
import warnings

from pdfem.case.schema import Case
from pdfem.coupling.coupler import substep_counts
from pdfem.errors import InputError
from pdfem.run.step_limits import check_ice_steps, check_structure_steps, check_substeps


def choose_time_steps(case: Case, bodies: list, structures: list) -> tuple[float, int, int]:
    """The coupling step (s) and the substeps of the ice and of the structures per step.

    The ice step is the case's ``time_step`` or safety_factor x the smallest stable ice step
    (:meth:`pdfem.pd.body.IceBody.stable_time_step`); the structure step is safety_factor x the
    smallest critical structure step (:meth:`pdfem.fem.base.Structure.critical_time_step`,
    ``inf`` for rigid bodies). The faster side subcycles
    (:func:`pdfem.coupling.coupler.substep_counts`, each side's step at most ``end_time``, so
    the faster side never takes more substeps than the run needs); ``run.substeps`` overrides
    the count. The coupling step is then shortened so that a whole number of steps ends the run.

    Raises
    ------
    InputError
        If ``run.time_step`` exceeds the stable ice step and the case does not set
        ``run.allow_unstable_time_step = true`` (with it: a warning); if either side would take
        more than :data:`pdfem.run.step_limits.MAX_STEPS` steps to the end time.
    """
    run = case.run
    stable = [b.stable_time_step() for b in bodies]
    critical = [s.critical_time_step() for s in structures]
    check_ice_steps(case, stable)
    check_structure_steps(case, structures, critical)
    ice = min(stable, default=math.inf)
    if run.time_step is not None:
        if not run.time_step <= ice:  # NaN: a stable step that overflowed
            worst = bodies[stable.index(ice)].name
            if not run.allow_unstable_time_step:
                raise InputError(case.file, "run.time_step",
                                 f"exceeds the stable step {ice:.4e} s of ice body '{worst}' "
                                 f"({run.time_step / ice:.2f} x), so the run would blow up; "
                                 f"choose time_step <= {ice:.4e} s, leave it out (automatic "
                                 "step), or set run.allow_unstable_time_step = true to run "
                                 "anyway", run.time_step)
            warnings.warn(f"{case.file}: run.time_step = {run.time_step:.3e} s exceeds the stable "
                          f"ice step {ice:.3e} s of '{worst}' (allowed by "
                          "run.allow_unstable_time_step); the run may blow up", stacklevel=3)
        ice = run.time_step
    else:
        ice *= run.safety_factor
    st = run.safety_factor * min(critical, default=math.inf)
    if not math.isfinite(ice) and not math.isfinite(st):
        if any(c.integrator == "implicit" for c in case.structures):
            raise InputError(case.file, "run.time_step", "an implicit structure has no "
                             "stability limit and the case has no ice to set the step: give "
                             "run.time_step (s), e.g. a twentieth of the period of the highest "
                             "mode the loads excite (period error (omega dt)^2 / 12)")
        ice = run.output_interval / 10  # rigid bodies only
    # a side slower than the whole run (a step of 1e150 s: ice of no stiffness) would otherwise
    # make the faster side take as many substeps (1e156) in its one step
    dt, n_ice, n_st = substep_counts(*(min(h, run.end_time) if math.isfinite(h) else h
                                       for h in (ice, st)), run.substeps)
    nsteps = max(1, math.ceil(run.end_time / dt - 1e-9))
    check_substeps(case, nsteps, n_ice, n_st)
    return run.end_time / nsteps, n_ice, n_st
