"""The ``pdfem`` command line.

    pdfem run [CASE.toml] [--out DIR] [--restart CHECKPOINT] [--quiet] [--json]
    pdfem post RESULTS.h5 [--plots DIR] [--csv FILE] [--json]
    pdfem sweep CASE.toml --set KEY=V1,V2,... [--out DIR] [--jobs N] [--slurm]
    pdfem sweep --collect DIR [--plot OUTPUT:INPUT]
    pdfem mesh MODEL [--set key=value ...] [-o FILE.msh] [--json]
    pdfem modes CASE.toml [--structure NAME] [--n K] [--out DIR] [--json]
    pdfem validate [--quick] [--report DIR] [--json] [--case NAME ...]
    pdfem schema [--markdown]
    pdfem bench {search,step,mpi,partition} [--n N] [--json]
    pdfem info [--json]
    pdfem --version

Each command is a module of :mod:`pdfem.cli` (its docstring says what it does).

Exit status: 0 success, 2 bad input (the message names file and field), 3 a run stopped by a
detected instability, 4 a run stopped by a signal (SIGTERM, SIGUSR1, Ctrl-C) with a checkpoint
to restart from, 1 anything else (a results or checkpoint file that cannot be written: one
paragraph, no traceback). With ``--json`` standard output holds exactly one JSON object and
nothing else. A reader that closes standard output early (``pdfem post --json | head``) ends
the command quietly with exit 1 (its output was not all delivered; no traceback): the
``BrokenPipeError`` is caught and standard output pointed at /dev/null, as the Python
documentation's "Note on SIGPIPE" does (the run itself, if any, has written its results).
"""

from __future__ import annotations

import argparse
import os
import sys
import traceback
import warnings

from pdfem import __version__
from pdfem.errors import (EXIT_BAD_INPUT, EXIT_FAILURE, EXIT_INSTABILITY, EXIT_OK, InputError,
                          InstabilityError, OutputError)

from pdfem.cli import bench, info, mesh, modes, post, run, schema, sweep, validate

COMMANDS = (run, post, sweep, mesh, modes, validate, schema, bench, info)
"""The commands, each a module with ``NAME``, ``HELP``, ``add_arguments(parser)`` and
``run(args) -> exit status``; a new command is one new module plus its entry here."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # argparse's own errors are bad input too: exit 2, no traceback
        self.print_usage(sys.stderr)
        raise InputError(None, None, f"{self.prog}: {message}")


def _parser() -> argparse.ArgumentParser:
    p = _Parser(prog="pdfem", description="Ice loads on structures: peridynamic ice, finite-element structures. SI units.")
    p.add_argument("--version", action="version", version=f"pdfem {__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for command in COMMANDS:
        command.add_arguments(sub.add_parser(command.NAME, help=command.HELP))
    return p


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``pdfem`` console script; returns the exit status."""
    try:
        args = _parser().parse_args(argv)
        with warnings.catch_warnings():
            warnings.simplefilter("default")
            warnings.showwarning = lambda msg, *a, **k: print(f"warning: {msg}", file=sys.stderr)
            status = {c.NAME: c.run for c in COMMANDS}[args.command](args)
            sys.stdout.flush()  # a closed pipe shows here, not at the interpreter's exit
            return status
    except BrokenPipeError:
        _stdout_to_devnull()
        return EXIT_FAILURE
    except InputError as exc:
        print(exc.text(), file=sys.stderr)
        return EXIT_BAD_INPUT
    except InstabilityError as exc:
        print(f"Run stopped: {exc}", file=sys.stderr)
        return EXIT_INSTABILITY
    except OutputError as exc:  # a full disk, a file-size limit, an I/O error: no traceback
        print(f"pdfem: {exc}", file=sys.stderr)
        return EXIT_FAILURE
    except KeyboardInterrupt:
        print("interrupted; results written so far are kept", file=sys.stderr)
        return EXIT_FAILURE
    except SystemExit as exc:  # --help / --version
        return int(exc.code or 0) if isinstance(exc.code, int) else EXIT_OK
    except Exception:
        traceback.print_exc()
        print("pdfem: an internal error stopped the run (exit 1); results written so far are kept.",
              file=sys.stderr)
        return EXIT_FAILURE


def _stdout_to_devnull() -> None:
    """Point standard output at /dev/null after its reader went away (``pdfem post --json |
    head``), so that the interpreter's last flush at exit finds no closed pipe (Python
    documentation, signal module, "Note on SIGPIPE"). In-process callers whose stdout has no
    file descriptor (a test's capture) keep theirs."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, fd)
    os.close(devnull)


def _entry() -> None:  # pragma: no cover
    sys.exit(main())


if __name__ == "__main__":  # pragma: no cover
    _entry()
