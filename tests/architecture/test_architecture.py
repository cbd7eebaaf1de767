"""The structure rules of docs/architecture.md, checked on the source.

- no import cycles between pdfem's modules (type-checking imports included);
- no module imports another module's private (``_name``) names, and no code reads another
  object's private attributes (only ``self``'s and ``cls``'s);
- the numba kernels called from Python take at most 12 arguments (their row loops, inlined into
  ``prange`` bodies, keep their arrays one by one: numba loses writes through tuples of arrays
  there, pdfem/pd/bonds/pair_step_kernels.py);
- outside the layout and parallel code nothing branches on the rank count, on a
  ``distributed`` flag or on a missing communicator.

Reference: the issue's done-when list, made executable; the import graph is grimp's (the one
import-linter builds).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "pdfem"
MODULES = sorted(PACKAGE.rglob("*.py"))

PARALLEL_CODE = ("pdfem/parallel/", "pdfem/pd/layout/", "pdfem/run/parallel.py",
                 "pdfem/run/balance.py", "pdfem/run/preflight.py", "pdfem/run/sizing.py",
                 "pdfem/cli/info.py")
"""The layout and parallel code, where the rank count may be asked: the communicator and the
partitions, the ice bodies' layouts, the start-up of the ranks, the load balance, the sizing of
a run over ranks and the report of the MPI installation."""


def _cycles(graph) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.find_modules_directly_imported_by(v):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for m in sorted(graph.modules):
        if m not in index:
            visit(m)
    return out


def test_no_import_cycles():
    grimp = pytest.importorskip("grimp")  # installed with import-linter (the test extra)
    assert _cycles(grimp.build_graph("pdfem")) == []


def _relative(p: Path) -> str:
    return str(p.relative_to(ROOT))


def test_no_private_names_across_modules():
    imports, reads = [], []
    for path in MODULES:
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("pdfem"):
                imports += [f"{_relative(path)}:{node.lineno} {a.name}" for a in node.names
                            if a.name.startswith("_") and not a.name.startswith("__")]
            if isinstance(node, ast.Attribute) and node.attr.startswith("_") \
                    and not node.attr.startswith("__"):
                owner = node.value
                if not (isinstance(owner, ast.Name) and owner.id in ("self", "cls")):
                    reads.append(f"{_relative(path)}:{node.lineno} {ast.unparse(node)}")
    assert imports == []
    assert reads == []


def _is_kernel(node: ast.FunctionDef) -> tuple[bool, bool]:
    """(compiled by numba, inlined into its callers)."""
    decorators = [ast.unparse(d) for d in node.decorator_list]
    numba = any(("njit" in d or "twin" in d or "jit(" in d) for d in decorators)
    inline = any("inline" in d or "_INLINE" in d for d in decorators)
    return numba, inline


def test_kernels_take_few_arguments():
    over = []
    for path in MODULES:
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef):
                numba, inline = _is_kernel(node)
                if numba and not inline and len(node.args.args) > 12:
                    over.append(f"{_relative(path)} {node.name}: {len(node.args.args)}")
    assert over == []


RANK_BRANCH = re.compile(r"\.distributed\b|comm is None|comm is not None|"
                         r"comm\.size\s*[=!<>]=?|\.size\s*[=!<>]=?\s*1\b.*comm|n_ranks\s*[=!<>]")


def test_only_the_layout_and_parallel_code_ask_for_the_rank_count():
    found = []
    for path in MODULES:
        rel = _relative(path)
        if rel.startswith(PARALLEL_CODE):
            continue
        for k, line in enumerate(path.read_text().splitlines(), 1):
            code = line.split("#", 1)[0]
            if RANK_BRANCH.search(code) and ("if " in code or " and " in code or " or " in code
                                             or "else" in code):
                found.append(f"{rel}:{k}: {line.strip()}")
    assert found == []
