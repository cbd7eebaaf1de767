"""Meshing structures with gmsh: the model-script API, the runner and mesh-quality checks.

A structure model is a Python script with ``PARAMETERS`` and a ``build(path, **params)``
function (see ``models/``). Model scripts import their helpers from here::

    from pdfem.meshing import MeshReport, check_parameters, finish_mesh, gmsh_session, ...

The modules: :mod:`~pdfem.meshing.parameters` (the parameter table validated by pydantic,
``require_*`` checks, :class:`ModelParameterError`), :mod:`~pdfem.meshing.session` (a headless
gmsh session, element size, meshing), :mod:`~pdfem.meshing.finish` (check, orient and write the
mesh), :mod:`~pdfem.meshing.report` (:class:`MeshReport`), :mod:`~pdfem.meshing.runner`
(finding and running model scripts: ``pdfem mesh``) and :mod:`~pdfem.meshing.quality` (element
measures and :class:`MeshQualityError`).
"""

from pdfem.meshing.finish import finish_mesh
from pdfem.meshing.parameters import (MAX_SURFACE_TRIANGLES, ModelParameterError, check_parameters,
                                      coerce_parameters, parameter_model, parse_set, require,
                                      require_choice, require_element_budget, require_positive,
                                      require_range)
from pdfem.meshing.quality import MeshQualityError
from pdfem.meshing.report import MeshReport
from pdfem.meshing.session import generate_mesh, gmsh_session, set_mesh_size

__all__ = ["MAX_SURFACE_TRIANGLES", "MeshQualityError", "MeshReport", "ModelParameterError",
           "check_parameters", "coerce_parameters", "finish_mesh", "generate_mesh", "gmsh_session",
           "parameter_model", "parse_set", "require", "require_choice", "require_element_budget",
           "require_positive", "require_range", "set_mesh_size"]
