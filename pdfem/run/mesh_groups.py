"""The named groups a structure's case entry uses, checked against its mesh file before the
structure is built, so that a missing group is reported against its own field
(``structure[0].fixed_groups[1]``, ``.contact_group``, ``.supports[0].group``,
``.loads[0].group``) rather than against ``structure[0].mesh``.
"""

from __future__ import annotations

from pathlib import Path

from pdfem.case.schema import StructureConfig
from pdfem.errors import InputError


def physical_names(path: Path) -> dict[str, int] | None:
    """``{group name: dimension}`` of the ``$PhysicalNames`` section of a gmsh ``.msh`` file
    (ASCII or binary: that section is text), or ``None`` if the file has none or cannot be read
    (the mesh reader then reports the file)."""
    try:
        with open(path, "rb") as fh:
            for line in fh:
                if line.strip() == b"$PhysicalNames":
                    n = int(fh.readline())
                    names = {}
                    for _ in range(n):
                        dim, _tag, name = fh.readline().decode("utf-8", "replace").split(None, 2)
                        names[name.strip().strip('"')] = int(dim)
                    return names
                if line.startswith((b"$Nodes", b"$Entities")):
                    return None
    except (OSError, ValueError):
        return None
    return None


def group_fields(cfg: StructureConfig) -> list[tuple[str, str]]:
    """``(case field, group name)`` of every mesh group the entry names."""
    at = cfg.field
    out = [(f"{at}.fixed_groups[{k}]", g) for k, g in enumerate(cfg.fixed_groups)]
    out += [(f"{at}.supports[{k}].group", g) for k, (g, _) in enumerate(cfg.supports)]
    out += [(f"{load.field}.group", load.group) for load in cfg.loads]
    out.append((f"{at}.contact_group", cfg.contact_group))
    return out


def check_groups(cfg: StructureConfig, path: Path, file: str) -> None:
    """Refuse a group the structure's entry names that its mesh file lacks.

    Raises
    ------
    InputError
        Naming the group's field, the mesh file and the groups it has.
    """
    names = physical_names(path)
    if names is None:
        return
    for field, group in group_fields(cfg):
        if group not in names:
            raise InputError(file, field, f"the mesh {path} of structure '{cfg.name}' has no "
                             "group of that name; its groups are: "
                             + ", ".join(sorted(names)), group)
