"""Helpers shared by the tests: launching the console script and MPI ranks, meshing boxes.

``tests/`` is on ``sys.path`` (``pythonpath`` in ``pyproject.toml``), so a test imports them as
``from support.cli import run_pdfem``.
"""
