"""Meshing structures with gmsh: the model-script API, the runner and mesh-quality checks.

A structure model is a Python script with a ``build(**params)`` function (see ``models/``). Model
scripts import their helpers from here::

    from pdfem.meshing import MeshReport, check_parameters, finish_mesh, gmsh_session, ...

:mod:`pdfem.meshing.runner` runs model scripts and gmsh; :mod:`pdfem.meshing.quality` checks the
elements of a mesh.
"""

from pdfem.meshing.runner import (MeshReport, ModelParameterError, check_parameters, finish_mesh,
                                  generate_mesh, gmsh_session, require, require_choice,
                                  require_element_budget, require_positive, require_range,
                                  set_mesh_size)

__all__ = ["MeshReport", "ModelParameterError", "check_parameters", "finish_mesh", "generate_mesh",
           "gmsh_session", "require", "require_choice", "require_element_budget",
           "require_positive", "require_range", "set_mesh_size"]
