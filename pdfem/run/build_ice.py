"""Ice bodies from validated case entries: fill the shape, find bonds, apply regions.

Each region in the case (fixed, prescribed velocity, no-fail, cracks) must select something;
fixed and prescribed regions carry their names (for their reaction histories) into the body;
one that selects no particle (or cuts no bond) is a user error, reported with its field name.
Under MPI (a communicator of several ranks given) a body is built split over the ranks, each
building only its part (:mod:`pdfem.pd.layout.setup`); the regions then apply to each
rank's part, and the checks count over all ranks.
The case's material section becomes the kernels' :class:`~pdfem.pd.materials.lps.IceMaterial`
here (:func:`ice_material`), so that the case schema does not depend on the physics.
"""

from __future__ import annotations

import numpy as np

from pdfem.case.config import IceConfig, RunConfig
from pdfem.case.ice import IceMaterialSection
from pdfem.errors import InputError
from pdfem.geometry.path import DisplacementPath
from pdfem.parallel.comm import SerialComm
from pdfem.pd.body import IceBody
from pdfem.pd.failure import failure_law
from pdfem.pd.bonds.influence import isotropy_gain
from pdfem.pd.materials.lps import IceMaterial, tensile_from_flexural


def ice_material(m: IceMaterialSection, dx: float | None = None,
                 depth: float | None = None) -> IceMaterial:
    """The LPS material of a case's ``material`` section.

    ``critical_stretch`` or a strength, when given, replaces ``fracture_energy``. A
    ``flexural_strength`` becomes the kernels' tensile strength through
    :func:`pdfem.pd.materials.lps.tensile_from_flexural`, which needs the lattice spacing ``dx``
    (m) and the body's depth ``depth`` (m, its z extent: the thickness of a sheet, the depth
    of a beam loaded along z); ``docs/ice_strength.md``.
    """
    tensile = m.tensile_strength
    if m.flexural_strength is not None:
        if dx is None or depth is None:
            raise ValueError("a flexural strength needs the spacing dx and the body's depth")
        tensile = tensile_from_flexural(m.flexural_strength, dx, depth)
    by_energy = m.critical_stretch is None and tensile is None
    return IceMaterial(density=m.density, youngs_modulus=m.youngs_modulus,
                       poisson_ratio=m.poisson_ratio,
                       fracture_energy=m.fracture_energy if by_energy else None,
                       critical_stretch=m.critical_stretch, tensile_strength=tensile,
                       compressive_strength=m.compressive_strength,
                       friction_angle=m.friction_angle, crushed_friction=m.crushed_friction,
                       transition_rate=m.transition_rate,
                       rate_exponent=m.rate_exponent)


def build_ice_body(cfg: IceConfig, run: RunConfig, file: str = "<case>", comm=SerialComm()):
    """Build the ice body that ``cfg`` describes.

    Parameters
    ----------
    cfg
        A validated ``[[ice]]`` entry.
    run
        The run settings (PD loop, gravity).
    file
        Case-file name for error messages.
    comm
        The communicator: on several ranks every rank builds only its part of the body
        (:meth:`pdfem.pd.body.IceBody.from_shape`; collective).

    Returns
    -------
    IceBody
        The body (this process's part) at rest in its reference state (initial velocity
        applied), forces not yet computed.
    """
    try:
        isotropy_gain(cfg.horizon / cfg.dx)
    except ValueError as exc:
        raise InputError(file, f"{cfg.field}.horizon_factor", str(exc),
                         cfg.horizon / cfg.dx) from None
    lo, hi = cfg.shape.bounds()
    try:
        material = ice_material(cfg.material, cfg.dx, float(hi[2] - lo[2]))
    except ValueError as exc:
        raise InputError(file, f"{cfg.field}.material.flexural_strength", str(exc)) from None
    try:
        law = failure_law(cfg.material.failure, material, cfg.horizon)
        body = IceBody.from_shape(cfg.name, cfg.shape, material, cfg.dx, cfg.horizon,
                                  comm=comm, loop=run.pd_loop, failure=law)
    except ValueError as exc:
        raise InputError(file, f"{cfg.field}.shape", str(exc)) from None
    n = body.n_global
    if n < 2:
        raise InputError(file, f"{cfg.field}.dx", f"the shape holds {n} particle(s) at this spacing; "
                         "choose a smaller dx", cfg.dx)
    body.gravity = np.asarray(run.gravity, dtype=np.float64)
    body.v[:] = np.asarray(cfg.initial_velocity)
    apply_regions(body, cfg, file, lambda k: int(body.layout.allsum(np.int64(k))))
    return body


def apply_regions(body, cfg: IceConfig, file: str, total=int) -> None:
    """No-fail regions, pre-cracks, fixed and prescribed regions of ``cfg`` on ``body`` (a whole
    body, or a rank's part with ``total`` summing a count over the ranks: a region must select
    a particle, a crack cut a bond, somewhere in the body)."""

    def select(region, field: str) -> np.ndarray:
        mask = region.contains(body.x0)
        if total(mask.sum()) == 0:
            lo, hi = region.bounds()
            raise InputError(file, field, "this region contains no particle of the body "
                             f"(region bounds {np.round(lo, 6).tolist()} to {np.round(hi, 6).tolist()} m); "
                             "check its coordinates against the ice shape")
        return mask

    for region, field in cfg.no_fail:
        body.nofail[select(region, field)] = 1
    for crack in cfg.cracks:
        if total(body.cut_crack(crack.point, crack.normal, crack.box.min, crack.box.max)) == 0:
            raise InputError(file, crack.field, "this crack cuts no bond; the plane through 'point' "
                             "with 'normal' must pass through the ice inside 'box'")
    for fixed in cfg.fixed:
        body.fix(select(fixed.region, fixed.field), name=fixed.name)
    for bc in cfg.prescribed_velocity:
        path = None if bc.path is None else DisplacementPath(bc.path)
        body.add_velocity_constraint(select(bc.region, f"{bc.field}.region"), bc.velocity,
                                     bc.ramp_time, path=path, name=bc.name)
