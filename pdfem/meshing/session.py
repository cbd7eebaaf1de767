"""A headless gmsh session for model scripts, with one element size everywhere and gmsh's
meshing failures turned into clear errors (:class:`~pdfem.meshing.quality.MeshQualityError`)."""

from __future__ import annotations

import contextlib
import signal
import threading
from typing import Any, Iterator

from pdfem.meshing.quality import MeshQualityError


@contextlib.contextmanager
def gmsh_session(name: str = "model") -> Iterator[Any]:
    """A headless gmsh session: yields the ``gmsh`` module, always finalises it.

    Calls ``gmsh.initialize(interruptible=False)`` (safe outside the main thread), silences the
    terminal output and selects MSH 4.1 (ASCII) for writing. gmsh has one global state per
    process, so sessions cannot be nested. gmsh's library puts its own SIGTERM handler in place
    of Python's (measured with gmsh 4: it prints "Terminated" and exits, while
    ``signal.getsignal`` still names Python's handler); the main thread's handler is put back
    when the session ends, so a run's stop on SIGTERM (:mod:`pdfem.run.stop`) still works.

    Parameters
    ----------
    name
        Name of the gmsh model that is added.

    Raises
    ------
    RuntimeError
        gmsh is already initialised (a session is open).
    """
    import gmsh

    if gmsh.isInitialized():
        raise RuntimeError("a gmsh session is already open in this process; sessions cannot be nested")
    main = threading.current_thread() is threading.main_thread()
    term = signal.getsignal(signal.SIGTERM) if main else None
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.Verbosity", 2)
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.option.setNumber("Mesh.Binary", 0)
        gmsh.option.setNumber("Mesh.SaveAll", 0)
        gmsh.option.setNumber("Mesh.ElementOrder", 1)
        gmsh.model.add(name)
        yield gmsh
    finally:
        gmsh.finalize()
        if term is not None:  # None: a handler not installed from Python, left as it is
            signal.signal(signal.SIGTERM, term)


def set_mesh_size(max_size: float, min_size: float = 0.0, curvature: int = 0) -> None:
    """Mesh the open session's model with one target element size, set by options only.

    Sizes from the geometry's points and extended from the boundary are switched off, so the
    elements are ``max_size`` everywhere except where ``curvature`` refines them.

    Parameters
    ----------
    max_size
        Largest (target) element edge length, m.
    min_size
        Smallest element edge length, m (a floor for the curvature refinement).
    curvature
        Elements per 2 pi of curvature (gmsh's ``Mesh.MeshSizeFromCurvature``); 0: off.
    """
    import gmsh

    gmsh.option.setNumber("Mesh.MeshSizeMin", min_size)
    gmsh.option.setNumber("Mesh.MeshSizeMax", max_size)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", curvature)


def generate_mesh(dim: int) -> None:
    """``gmsh.model.mesh.generate(dim)`` in the open session; a gmsh failure becomes a
    :class:`MeshQualityError` (bad input: usually the element size for the geometry)."""
    import gmsh

    try:
        gmsh.model.mesh.generate(dim)
    except Exception as exc:  # gmsh raises a bare Exception with its last error message
        raise MeshQualityError(f"gmsh could not mesh the model ({exc}); another element_size may work") from None
