"""Fixtures shared by the whole suite.

``gmsh_box`` writes a gmsh mesh of an axis-aligned box with named volume and face groups
(:func:`support.meshes.write_box`), which the FE, rigid-body and coupling tests mesh.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import pytest

from support.meshes import write_box


@pytest.fixture(scope="session")
def gmsh_box() -> Callable[..., Path]:
    """:func:`write_box`: writes a gmsh mesh of a box with named volume and face groups."""
    return write_box
