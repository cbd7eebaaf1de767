"""Finding and running model scripts: what ``pdfem mesh MODEL [--set key=value ...]
[-o FILE.msh]`` and the ``mesh`` key of a case's ``[[structure]]`` do.

A model is a module of ``pdfem.models`` named by its name, or any ``.py`` file, that exposes

    PARAMETERS: dict[str, tuple[default, unit, description]]
    build(path, **params) -> MeshReport

(see :mod:`pdfem.meshing` for the helpers a model uses). :func:`parse_set` splits ``--set``
strings; :func:`mesh_model` converts them to the parameters' types
(:func:`pdfem.meshing.parameters.coerce_parameters`) and runs the model's ``build``.

A model script is Python code and is executed (imported, then its ``build`` called) with the
user's permissions. An exception it raises, or a ``sys.exit`` it calls, is reported as bad
input (:class:`~pdfem.meshing.parameters.ModelParameterError`, exit 2) naming the script and the
line (:func:`script_error`).
"""

from __future__ import annotations

import importlib
import importlib.util
import pkgutil
import sys
import traceback
from pathlib import Path
from types import ModuleType
from typing import Any

from pdfem.errors import InputError
from pdfem.meshing.parameters import ModelParameterError, coerce_parameters, parse_set
from pdfem.meshing.report import MeshReport

__all__ = ["available_models", "resolve_model", "mesh_model", "parse_set"]


def available_models() -> list[str]:
    """Names of the model modules in ``pdfem.models`` (those that define ``build``)."""
    import pdfem.models as pkg

    names = []
    for info in pkgutil.iter_modules(pkg.__path__):
        if info.name.startswith("_") or info.ispkg:
            continue
        try:
            mod = importlib.import_module(f"pdfem.models.{info.name}")
        except Exception:  # a broken module is not offered as a model
            continue
        if callable(getattr(mod, "build", None)):
            names.append(info.name)
    return sorted(names)


def resolve_model(name_or_path: str | Path) -> ModuleType:
    """Find a model: a bare name in ``pdfem.models``, or a path to a ``.py`` file.

    Parameters
    ----------
    name_or_path
        ``"hull_panel"`` -> ``pdfem.models.hull_panel``; ``"my/model.py"`` -> that file,
        imported under a private module name.

    Returns
    -------
    module
        The model module; it defines ``build`` (and normally ``PARAMETERS``).

    Raises
    ------
    ModelParameterError
        (``param == "model"``) an unknown name (the message lists the available names), a
        missing file, or a module without ``build``.
    """
    text = str(name_or_path)
    is_path = isinstance(name_or_path, Path) or text.endswith(".py") or "/" in text or "\\" in text
    if is_path:
        path = Path(text).expanduser()
        if not path.is_file():
            raise ModelParameterError("model", text, "no such model file")
        if path.suffix != ".py":
            raise ModelParameterError("model", text, "a model file must be a Python script (.py)")
        modname = f"pdfem_user_model_{abs(hash(str(path.resolve())))}"
        spec = importlib.util.spec_from_file_location(modname, path)
        if spec is None or spec.loader is None:
            raise ModelParameterError("model", text, "cannot be imported as a Python module")
        module = importlib.util.module_from_spec(spec)
        sys.modules[modname] = module
        try:
            spec.loader.exec_module(module)
        except InputError:
            sys.modules.pop(modname, None)
            raise
        except (Exception, SystemExit) as exc:  # an exit would end pdfem mid-set-up
            sys.modules.pop(modname, None)
            raise script_error(text, path, exc) from None
    else:
        names = available_models()
        if text not in names:
            raise ModelParameterError("model", text, "unknown model; available models are: "
                                      + ", ".join(names) + " (or give a path to a .py file)")
        module = importlib.import_module(f"pdfem.models.{text}")
    if not callable(getattr(module, "build", None)):
        raise ModelParameterError("model", text, "the model module defines no build(path, **params) function")
    return module


def mesh_model(model: str | Path, params: dict[str, Any] | None = None, out: Path | str | None = None) -> MeshReport:
    """Build a model's mesh: what ``pdfem mesh MODEL [--set key=value ...] [-o FILE]`` does.

    Parameters
    ----------
    model
        A model name in ``pdfem.models`` or a path to a ``.py`` file (see :func:`resolve_model`).
    params
        Parameter values, usually the strings from ``--set`` (see :func:`parse_set`); they are
        converted to the types of the model's ``PARAMETERS`` defaults.
    out
        Output ``.msh`` file; default ``<model>.msh`` in the current directory.

    Returns
    -------
    MeshReport

    Raises
    ------
    ModelParameterError
        Unknown model, unknown parameter (listing the valid ones), a bad value, or a model
        script that raised (naming the script and its line).
    MeshQualityError
        The mesh has inverted or zero-volume elements.
    """
    module = resolve_model(model)
    raw = dict(params or {})
    parameters = getattr(module, "PARAMETERS", None)
    if parameters is not None:
        typed = coerce_parameters(parameters, raw)
    else:
        typed = raw
    stem = Path(str(model)).stem
    path = Path(out) if out is not None else Path.cwd() / f"{stem}.msh"
    try:
        return module.build(path, **typed)
    except InputError:
        raise
    except (Exception, SystemExit) as exc:
        raise script_error(str(model), Path(module.__file__ or str(model)), exc) from None


def script_error(model: str, script: Path, exc: BaseException) -> ModelParameterError:
    """A model script's exception as an input error naming the script and the line of it
    where the exception arose (the innermost frame in the script; a model script is Python
    code that pdfem executes)."""
    frames = [f for f in traceback.extract_tb(exc.__traceback__)
              if Path(f.filename).resolve() == script.resolve()]
    where = f", line {frames[-1].lineno}" if frames else ""
    line = f" ({frames[-1].line.strip()})" if frames and frames[-1].line else ""
    if isinstance(exc, SyntaxError) and exc.lineno:  # raised by the parser, not from a frame
        where, line = f", line {exc.lineno}", f" ({(exc.text or '').strip()})"
    if isinstance(exc, SystemExit):
        code = "" if exc.code is None else repr(exc.code)
        return ModelParameterError("model", model, f"the model script {script}{where} "
                                   f"called sys.exit({code}): pdfem imports a model script and "
                                   "calls its build(path, **params), which must return (or "
                                   "raise an exception saying what is wrong), not exit")
    return ModelParameterError("model", model, f"the model script {script}{where}{line} "
                               f"raised {type(exc).__name__}: {exc}; fix the script or its "
                               "parameters")
