"""``pdfem modes CASE.toml [--structure NAME] [--n K] [--out DIR] [--json]``: natural modes.

Builds the case's elastic structures exactly as ``pdfem run`` does (mesh models are meshed into
the output directory, default ``results/<case name>/``), computes the first K natural
frequencies (Hz) of each with its supports (:func:`pdfem.fem.modes.natural_modes`), prints one
table per structure and writes the mode shapes to ``DIR/modes.h5`` and ``DIR/modes.xdmf``
(:mod:`pdfem.output.modes`; open the .xdmf in ParaView and warp by ``mode_shape``). Rigid
structures and ships have no modes and are skipped; a case without an elastic structure, or
``--structure`` naming a rigid one, is refused (exit 2, nothing written). A structure attached
to a ship is taken on its supports with the hull held still. ``--json`` prints only
``{"structures": {NAME: {"frequencies_hz": [...], "n_nodes": ..., "n_elements": ...}}}``.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
from dataclasses import replace
from pathlib import Path

from pdfem.cli.options import path_text
from pdfem.errors import EXIT_OK, InputError

NAME = "modes"
HELP = "natural frequencies and mode shapes of a case's elastic structures"

DEFAULT_MODES = 10
"""Number of modes computed without ``--n``."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The options of ``pdfem modes``."""
    p.add_argument("case", help="case file (TOML, SI units)")
    p.add_argument("--structure", default=None, metavar="NAME",
                   help="only this structure (default: every elastic structure)")
    p.add_argument("--n", type=int, default=DEFAULT_MODES, metavar="K",
                   help=f"number of modes per structure (default {DEFAULT_MODES})")
    p.add_argument("--out", default=None, type=path_text,
                   help="output directory for modes.h5 / modes.xdmf (default: results/<case name>)")
    p.add_argument("--json", action="store_true", help="print the frequencies as one JSON object")


def _chosen(case, name: str | None) -> list:
    """The structure entries asked for (all, or the one named); refuses a choice without an
    elastic structure."""
    names = [s.name for s in case.structures]
    if name is not None and name not in names:
        raise InputError(None, "--structure", f"case {case.file} has no structure of that name; "
                         f"its structures are {', '.join(names) or 'none'}", name)
    chosen = [s for s in case.structures if name is None or s.name == name]
    if name is not None and chosen[0].kind != "elastic":
        raise InputError(case.file, f"{chosen[0].field}.kind", f"structure '{name}' is "
                         f"{chosen[0].kind}; only elastic structures have natural modes (pdfem "
                         "modes --structure NAME of an elastic structure)", chosen[0].kind)
    if not any(cfg.kind == "elastic" for cfg in chosen):
        kinds = ", ".join(f"'{c.name}' ({c.kind})" for c in chosen) or "none"
        raise InputError(case.file, None, "no elastic structure in this case: pdfem modes "
                         "needs a [[structure]] of kind = \"elastic\" (rigid bodies and ships "
                         f"have no natural modes; the case's structures: {kinds})")
    return chosen


def compute(case, out: Path, name: str | None, n: int, say) -> list:
    """Build the chosen elastic structures of ``case`` (meshing into ``out``) and their first
    ``n`` modes, as :class:`pdfem.output.modes.StructureModes`; ``say`` reports skips."""
    from pdfem.fem.modes import natural_modes
    from pdfem.output.modes import StructureModes
    from pdfem.run.build import check_mesh
    from pdfem.run.build_structures import build_structure
    from pdfem.run.outdir import check_out_dir
    chosen = _chosen(case, name)
    check_out_dir(out)  # the models are meshed into it
    result = []
    for cfg in chosen:
        if cfg.kind != "elastic":
            say(f"structure '{cfg.name}' is {cfg.kind}: it has no elastic modes, skipped")
            continue
        # a structure riding on a ship: its modes on its supports, the hull held still
        st = build_structure(replace(cfg, attached_to=None), out, case.file)
        check_mesh(st, cfg, case.file)
        n_free = int(st.solver.free.sum())
        if n >= n_free:
            raise InputError(None, "--n", f"structure '{cfg.name}' has {n_free} free degrees of "
                             f"freedom; ask for fewer than {n_free} modes", n)
        freqs, shapes = natural_modes(st, n)
        points, cells, cell_type = st.output_mesh()
        result.append(StructureModes(cfg.name, freqs, shapes[:, :len(points)], points, cells,
                                     cell_type))
    return result


def table(m) -> str:
    """The frequency table of one structure's modes."""
    lines = [f"structure '{m.name}': {len(m.points):,} nodes, {len(m.cells):,} {m.cell_type} "
             "elements", "  mode   frequency [Hz]"]
    lines += [f"  {i + 1:4d}   {f:14.6g}" for i, f in enumerate(m.frequencies_hz)]
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Compute and report the modes; exit status."""
    from pdfem.case.schema import load_case
    from pdfem.output.modes import write_modes
    if args.n < 1:
        raise InputError(None, "--n", "the number of modes must be a whole number of at least 1",
                         args.n)
    case = load_case(args.case)
    out = Path(args.out) if args.out else Path("results") / Path(args.case).stem
    if args.json:
        with contextlib.redirect_stdout(io.StringIO()):
            modes = compute(case, out, args.structure, args.n, lambda s: None)
            write_modes(out, modes)
        print(json.dumps({"structures": {m.name: {
            "frequencies_hz": [float(f) for f in m.frequencies_hz],
            "n_nodes": int(len(m.points)), "n_elements": int(len(m.cells))} for m in modes}}))
        return EXIT_OK
    modes = compute(case, out, args.structure, args.n, print)
    for m in modes:
        print(table(m))
        print()
    h5, xdmf = write_modes(out, modes)
    print(f"Mode shapes: {h5} (HDF5); open {xdmf} in ParaView (one frame per mode, "
          "warp by 'mode_shape').")
    return EXIT_OK
