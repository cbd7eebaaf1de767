"""Supports of an elastic structure: the Dirichlet DOFs, prescribed values and reactions.

Three kinds, all on the FE nodes of a named mesh group (midside nodes included):

- clamped groups (``fixed_groups``): all three displacement components held at zero;
- component supports (``supports``): only the named components (``"x"``, ``"y"``, ``"z"``)
  held at zero, e.g. rollers or symmetry planes (u_x = 0 on a plane x = const);
- prescribed groups: all three components follow a given displacement (m) in time.

The reaction (N) of a support is the force it exerts on the structure,
``K u + C v + M a - f_ext`` summed over the group's nodes, per component; the components a
support does not hold are reported as 0.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np

from pdfem.fem.elasticity import DofMap

COMPONENTS = {"x": 0, "y": 1, "z": 2}


def component_indices(components: Sequence[str] | str, group: str = "") -> tuple[int, ...]:
    """Sorted component indices (0 = x, 1 = y, 2 = z) of names such as ``["x", "z"]``.

    Raises
    ------
    ValueError
        If a name is not x, y or z, or the list is empty.
    """
    if isinstance(components, str):
        components = [components]
    bad = [c for c in components if c not in COMPONENTS]
    if bad or not components:
        raise ValueError(f"support '{group}': components must be a non-empty list of \"x\", "
                         f"\"y\", \"z\" (got {list(components)!r})")
    return tuple(sorted({COMPONENTS[c] for c in components}))


def support_table(fixed_groups: Sequence[str], supports: Mapping[str, Sequence[str]] | None,
                  prescribed: Mapping | None) -> dict[str, tuple[int, ...]]:
    """``{group: held components}`` of all supports (clamped and prescribed: all three)."""
    table: dict[str, set[int]] = {}
    for g in list(fixed_groups) + list(prescribed or {}):
        table.setdefault(g, set()).update((0, 1, 2))
    for g, comps in (supports or {}).items():
        table.setdefault(g, set()).update(component_indices(comps, g))
    return {g: tuple(sorted(c)) for g, c in table.items()}


def constrained_dofs(dofmap: DofMap, group_nodes: Callable[[str], np.ndarray],
                     table: Mapping[str, tuple[int, ...]]) -> np.ndarray:
    """Sorted unique int64 Dirichlet DOFs of the support ``table`` (:func:`support_table`)."""
    parts = [dofmap.dofs_of(group_nodes(g), comps) for g, comps in table.items()]
    return np.unique(np.concatenate(parts)) if parts else np.zeros(0, dtype=np.int64)


def prescribed_values(fixed: np.ndarray, dofmap: DofMap, group_nodes: Callable[[str], np.ndarray],
                      prescribed: Mapping) -> Callable[[float], np.ndarray]:
    """Callable ``t -> values (m) on the Dirichlet DOFs`` for prescribed groups.

    ``prescribed`` maps a group to a (3,) displacement (m) or a callable ``t -> (3,)``; the
    other Dirichlet DOFs get 0.

    Raises
    ------
    ValueError
        If a displacement is not a (3,) vector or a callable.
    """
    parts = []
    for group, disp in prescribed.items():
        if not callable(disp) and np.asarray(disp, dtype=np.float64).shape != (3,):
            raise ValueError("a prescribed displacement must be a (3,) vector or a callable "
                             "t -> (3,)")
        for c in range(3):
            pos = np.searchsorted(fixed, dofmap.dofs_of(group_nodes(group), (c,)))
            parts.append((pos, c, disp))

    def values(t: float) -> np.ndarray:
        out = np.zeros(fixed.size)
        for pos, c, disp in parts:
            d = disp(t) if callable(disp) else disp
            out[pos] = float(np.asarray(d, dtype=np.float64).reshape(3)[c])
        return out

    return values


def support_reaction(residual: np.ndarray, dofmap: DofMap, nodes: np.ndarray,
                     components: Sequence[int] = (0, 1, 2)) -> np.ndarray:
    """(3,) reaction (N) of a support at ``nodes``: the nodal ``residual`` (N, per DOF) summed,
    with the components the support does not hold set to 0."""
    r = dofmap.to_nodal(residual)[np.asarray(nodes, dtype=np.int64)].sum(axis=0)
    out = np.zeros(3)
    out[list(components)] = r[list(components)]
    return out
