"""The package layout keeps its promises: layers import downwards only, the benchmarks are
imported by the bench command alone, and every module is small, with a docstring.

Reference: the layering and module-size rules of docs/architecture.md (the import-linter
contracts in pyproject.toml are the machine-checked form of its data-flow picture).
"""

from __future__ import annotations

import ast
import statistics
import subprocess
import sys
from pathlib import Path

from support.cli import tool

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "pdfem"
MODULES = sorted(PACKAGE.rglob("*.py"))


def _code_lines(path: Path) -> int:
    """Lines of code: not blank, not only a comment, not part of a docstring."""
    text = path.read_text()
    doc = set()
    for node in ast.walk(ast.parse(text)):
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr) \
                and isinstance(body[0].value, ast.Constant) and isinstance(body[0].value.value, str):
            doc.update(range(body[0].lineno, body[0].end_lineno + 1))
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) \
                and isinstance(node.value.value, str):  # attribute docstrings
            doc.update(range(node.lineno, node.end_lineno + 1))
    return sum(1 for k, line in enumerate(text.splitlines(), 1)
               if k not in doc and line.strip() and not line.strip().startswith("#"))


def test_import_contracts_kept():
    """import-linter (the test extra) finds every contract of pyproject.toml kept."""
    out = subprocess.run([tool("lint-imports"), str(ROOT / "pyproject.toml")], cwd=ROOT, capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-2000:]
    assert "0 broken" in out.stdout


def test_only_the_bench_command_imports_the_benchmarks():
    offenders = []
    for path in MODULES:
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            if any(n.startswith("pdfem.benchmarks") for n in names):
                offenders.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert all(o.startswith("pdfem/cli/bench.py") for o in offenders), offenders


def test_commands_other_than_bench_leave_the_benchmarks_unimported():
    code = ("import sys, contextlib, io\nfrom pdfem.cli.main import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            "    assert main(['info', '--json']) == 0\n"
            "    main(['--help'])\n"
            "print(sorted(m for m in sys.modules if m.startswith('pdfem.benchmarks')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=300, cwd=ROOT.parent)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip().splitlines()[-1] == "[]"


def test_modules_are_small_and_say_what_they_are_for():
    sizes = {p: _code_lines(p) for p in MODULES}
    big = {str(p.relative_to(ROOT)): n for p, n in sizes.items() if n > 400}
    assert not big, f"modules over 400 lines of code: {big}"
    assert statistics.median(sizes.values()) < 100
    undocumented = [str(p.relative_to(ROOT)) for p in MODULES
                    if ast.get_docstring(ast.parse(p.read_text())) is None]
    assert not undocumented, f"modules without a docstring: {undocumented}"


def test_every_subpackage_is_installed():
    import tomllib
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {".".join(p.parent.relative_to(ROOT).parts) for p in PACKAGE.rglob("__init__.py")}
    assert found <= listed, f"packages missing from pyproject.toml: {sorted(found - listed)}"


def _is_slow(decorator: ast.expr) -> bool:
    """``@pytest.mark.slow``."""
    return isinstance(decorator, ast.Attribute) and decorator.attr == "slow"


def test_tests_mirror_the_package_and_the_fast_tier_touches_every_package():
    """Every subpackage of pdfem (and models/) has its folder tests/<name>/, and each folder
    holds at least one test outside the slow tier, so ``pytest -m "not slow"`` touches every
    package (README: the fast tier)."""
    packages = sorted(p.parent.name for p in PACKAGE.glob("*/__init__.py")) + ["models"]
    tests = ROOT / "tests"
    missing, slow_only = [], []
    for name in packages:
        files = sorted((tests / name).glob("test_*.py"))
        if not files:
            missing.append(name)
            continue
        fast = 0
        for path in files:
            tree = ast.parse(path.read_text())
            if any(isinstance(n, ast.Assign) and any(getattr(t, "id", "") == "pytestmark"
                                                     for t in n.targets) for n in tree.body):
                continue  # a module-wide mark: counted as slow
            fast += sum(1 for n in tree.body if isinstance(n, ast.FunctionDef)
                        and n.name.startswith("test_")
                        and not any(_is_slow(d) for d in n.decorator_list))
        if not fast:
            slow_only.append(name)
    assert not missing, f"packages without tests/<name>/: {missing}"
    assert not slow_only, f"packages whose tests are all slow: {slow_only}"

