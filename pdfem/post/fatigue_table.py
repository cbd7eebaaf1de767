"""The fatigue block of ``pdfem post --sn`` as a text table and as a CSV rainflow histogram.

:func:`format_fatigue` prints :func:`pdfem.post.fatigue.fatigue_summary` for the terminal;
:func:`write_fatigue_csv` writes its range histograms. SI units: Pa, s.
"""

from __future__ import annotations

import os


def _g(x: float | None) -> str:
    return "-" if x is None else f"{x:.4g}"


def format_fatigue(block: dict) -> str:
    """The fatigue block as text: curve, then per monitor damage, life and range histogram.

    Parameters
    ----------
    block
        :func:`pdfem.post.fatigue.fatigue_summary`.

    Returns
    -------
    str
        The lines, without a trailing newline.
    """
    c = block["curve"]
    curve = f"m = {c['m']:g}, {c['stress']:.4g} Pa endured {c['cycles']:.4g} cycles"
    if "m2" in c:
        curve += f", m2 = {c['m2']:g} below {c['knee_range']:.4g} Pa ({c['knee']:.4g} cycles)"
    lines = [f"Fatigue (rainflow, ASTM E1049; Miner sum; S-N curve {curve}; "
             f"log10 a = {c['log10_a_MPa']:.4g} for MPa; stress counted: {block['stress']})"]
    for name, f in block["monitors"].items():
        life = f["life_events"]
        lines += ["", f"  monitor '{name}': {f['cycles']:g} cycles, largest range "
                  f"{_g(f['max_range'])} Pa, damage {_g(f['damage'])} per simulated history, "
                  f"{_g(f['damage_total'])} for {f['events']:g} of them; life "
                  + (f"{_g(life)} histories" if life is not None else "infinite (no damage)")]
        rows = [(f"{h['range_low']:.4g} - {h['range_high']:.4g}", f"{h['cycles']:g}",
                 _g(h["mean"]), _g(h["damage"])) for h in f["histogram"] if h["cycles"]]
        header = ("range [Pa]", "cycles", "mean [Pa]", "damage")
        widths = [max(len(r[i]) for r in [header, *rows]) for i in range(4)]
        lines += ["    " + "  ".join(c.ljust(w) if i == 0 else c.rjust(w)
                                     for i, (c, w) in enumerate(zip(r, widths)))
                  for r in [header, *rows]]
    return "\n".join(lines)


def write_fatigue_csv(block: dict, path: str | os.PathLike) -> None:
    """Write the rainflow range histograms of the fatigue block to a CSV file.

    One header line, then one line per monitor and range bin: ``monitor``, ``range_low
    [Pa]``, ``range_high [Pa]``, ``cycles`` (half cycles count 0.5), ``mean [Pa]`` (their
    count-weighted mean stress, empty if none), ``damage`` (Miner sum of the bin, one history).
    """
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write("monitor,range_low [Pa],range_high [Pa],cycles,mean [Pa],damage\n")
        for name, f in block["monitors"].items():
            for h in f["histogram"]:
                mean = "" if h["mean"] is None else f"{h['mean']:.17g}"
                fh.write(f"{name},{h['range_low']:.17g},{h['range_high']:.17g},"
                         f"{h['cycles']:.17g},{mean},{h['damage']:.17g}\n")
