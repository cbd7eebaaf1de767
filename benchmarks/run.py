"""Run pdfem's benchmark suite and print the figures as Markdown (for BENCHMARKS.md).

Usage: python benchmarks/run.py [--sizes 10000,100000,1000000] [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys


def machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, {platform.system()}"


def bench(what: str, n: int) -> dict:
    out = subprocess.run([sys.executable, "-m", "pdfem", "bench", what, "--n", str(n), "--json"],
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--sizes", default="10000,100000,1000000")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    rows = {"search": [bench("search", n) for n in sizes], "step": [bench("step", n) for n in sizes]}
    if args.json:
        print(json.dumps({"machine": machine(), **rows}))
        return
    print(f"Machine: {machine()}\n")
    print("| particles | pairs | cell search (s) | cKDTree (s) | speed-up | brute force (s) |")
    print("|---:|---:|---:|---:|---:|---:|")
    for r in rows["search"]:
        brute = f"{r['brute_s']:.3f}" if "brute_s" in r else "-"
        print(f"| {r['n_particles']:,} | {r['n_pairs']:,} | {r['cell_s']:.3f} | {r['ckdtree_s']:.3f} | "
              f"{r['speedup_vs_ckdtree']:.1f}x | {brute} |")
    print("\n| particles | pairs | threads | pair loop (M pair-steps/s) | full family (M pair-steps/s) | ratio |")
    print("|---:|---:|---:|---:|---:|---:|")
    for r in rows["step"]:
        print(f"| {r['n_particles']:,} | {r['n_pairs']:,} | {r['threads']} | {r['pair_steps_per_s'] / 1e6:.1f} | "
              f"{r['full_family_pair_steps_per_s'] / 1e6:.1f} | {r['speedup_pairs_vs_full_family']:.2f} |")


if __name__ == "__main__":
    main()
