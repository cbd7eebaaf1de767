"""The step benchmark of two installations side by side: the ratio of their pair-loop speeds.

Runs ``pdfem bench step --n N --json`` alternately with this installation's interpreter and
another one's (an older checkout installed in its own virtual environment), ``--rounds``
times each, from a neutral directory, and reports each figure's median and the ratio new / old
of the medians: the same machine and load for both, so the ratio is what the change did.

    python -m pdfem.benchmarks.ab_step --old /path/to/old/venv/bin/python [--n 1000000]
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile

FIGURES = ("pair_steps_per_s", "pair_steps_per_s_best", "lean_pair_steps_per_s",
           "ice_law_pair_steps_per_s", "full_family_pair_steps_per_s")


def _bench(python: str, n: int) -> dict:
    code = ("import sys; from pdfem.cli.main import main; "
            f"sys.exit(main(['bench', 'step', '--n', '{n}', '--json']))")
    out = subprocess.run([python, "-c", code], capture_output=True, text=True, check=True,
                         cwd=tempfile.gettempdir())
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", required=True, help="the other installation's python")
    ap.add_argument("--n", type=int, default=1_000_000)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args(argv)
    runs = {"new": [], "old": []}
    for _ in range(args.rounds):
        runs["old"].append(_bench(args.old, args.n))
        runs["new"].append(_bench(sys.executable, args.n))
    out = {"n": args.n, "rounds": args.rounds}
    for key in FIGURES:
        new = statistics.median(r[key] for r in runs["new"])
        old = statistics.median(r[key] for r in runs["old"])
        out[key] = {"new": new, "old": old, "ratio": new / old}
    out["load_average"] = [r["load_average"] for r in runs["new"] + runs["old"]]
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
