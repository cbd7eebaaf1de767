"""``pdfem mesh MODEL [--set key=value ...] [-o FILE.msh] [--json]``: mesh a structure model."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from pdfem.cli.options import path_text
from pdfem.errors import EXIT_OK, InputError

NAME = "mesh"
HELP = "mesh a model of models/ (or a .py file) with gmsh"


def add_arguments(m: argparse.ArgumentParser) -> None:
    """The options of ``pdfem mesh``."""
    m.add_argument("model", help="model name (hull_panel, propeller_blade, indenters) or a .py file with build()")
    m.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="model parameter (SI units), repeatable")
    m.add_argument("-o", "--output", default=None, type=path_text,
                   help="output .msh file (default: <model>.msh)")
    m.add_argument("--json", action="store_true", help="print the mesh report as one JSON object")


def run(args: argparse.Namespace) -> int:
    """Mesh the model; exit status."""
    from pdfem.meshing.runner import mesh_model, parse_set
    from pdfem.run.outdir import check_out_dir
    params = parse_set(args.set)
    output = Path(args.output) if args.output else None
    if output is not None:
        if output.is_dir():
            raise InputError(None, "--output", "is a directory; give the .msh file to write",
                             args.output)
        try:  # its directory, checked like a run's --out
            check_out_dir(output.parent)
        except InputError as exc:
            raise InputError(None, "--output", exc.message, args.output) from None
    report = mesh_model(args.model, params, output)
    print(json.dumps(report.as_dict()) if args.json else report.text())
    return EXIT_OK


