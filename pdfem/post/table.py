"""The summary of a results file as text tables for the terminal (units in the headers).

:func:`format_summary` prints what :func:`pdfem.post.summary.summarize` computed: one section
per quantity (loads, contact pairs, reactions of ice regions, structures, reactions, monitors,
ice, energies).
"""

from __future__ import annotations

from pdfem.post.groups import AXES


def _g(x: float | None) -> str:
    return "-" if x is None else f"{x:.4g}"


def _loc(v: list | None) -> str:
    return "-" if v is None else "(" + ", ".join(f"{c:.4g}" for c in v) + ")"


def _table(header: list[str], rows: list[list[str]], indent: str = "  ") -> list[str]:
    """Rows of text cells as aligned lines: first column left-aligned, the others right."""
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]

    def line(r: list[str]) -> str:
        return indent + "  ".join(c.ljust(w) if i == 0 else c.rjust(w)
                                  for i, (c, w) in enumerate(zip(r, widths)))
    return [line(header), *(line(r) for r in rows)]


def _load_lines(what: str, name: str, f: dict) -> list[str]:
    if f["samples"] == 0:
        return [f"{what} '{name}': no samples"]
    lines = [f"{what} '{name}' ({f['samples']} steps, t = {_g(f['start_time'])} to "
             f"{_g(f['end_time'])} s; mean = time average over the run)"]
    rows = [[d, _g(f[d]["peak"]), _g(f[d]["time"]), _g(f[d]["mean"])]
            for d in (*AXES, "magnitude")]
    lines += _table(["direction", "peak [N]", "at t [s]", "mean [N]"], rows)
    w = f.get("windowed")
    if w and w["peak"] is not None:
        lines.append(f"  peak of |F| averaged over {_g(w['window'] * 1e3)} ms: {_g(w['peak'])} N "
                     f"at t = {_g(w['time'])} s (converges with the time step; the per-step peak "
                     "does not)")
    if "max_contacts" in f:
        lines.append(f"  most particles in contact at once: {f['max_contacts']}")
    return lines


def format_summary(summary: dict) -> str:
    """The summary as text tables for the terminal (units in the headers).

    Parameters
    ----------
    summary
        :func:`pdfem.post.summary.summarize` of a results file.

    Returns
    -------
    str
        The tables, one section per quantity, without a trailing newline.
    """
    s = summary
    head = f"Results {s['file']}" if s.get("file") else "Results"
    if s.get("title"):
        head += f" - {s['title']}"
    lines = [head, f"  {s['frames']} frames, last at t = {_g(s['end_time'])} s"]
    if not s["loads"] and not s["structures"]:
        lines.append("  no structure in this run (ice only)")
    for name, f in s["loads"].items():
        lines += ["", *_load_lines("Ice force on structure", name, f)]
    for name, f in s["contacts"].items():
        lines += ["", *_load_lines("Ice force in contact pair", name, f)]
    for name, f in s.get("regions", {}).items():
        lines += ["", *_load_lines("Reaction of ice region (force on the ice)", name, f)]
    rows = []
    for name, st in s["structures"].items():
        vm = st.get("max_von_mises", {})
        ud = st.get("max_displacement", {})
        rows.append([name, st["kind"], _g(vm.get("value")), _g(vm.get("time")),
                     _loc(vm.get("location")), _g(ud.get("value")), _g(ud.get("time")),
                     _loc(ud.get("location"))])
    if rows:
        lines += ["", "Structures (from the output frames; locations in the reference "
                      "configuration: element centre, node)"]
        lines += _table(["structure", "kind", "max von Mises [Pa]", "at t [s]", "element at [m]",
                         "max |u| [m]", "at t [s]", "node at [m]"], rows)
    rows = [[f"{name}/{g}", _g(r["peak"]), _g(r["time"]), _loc(r["force_at_peak"])]
            for name, st in s["structures"].items() for g, r in st.get("reactions", {}).items()]
    if rows:
        lines += ["", "Reaction forces of the fixed groups (peak magnitude over the frames)"]
        lines += _table(["structure/group", "peak |R| [N]", "at t [s]", "R at peak [N]"], rows)
    rows = []
    for name, m in s["monitors"].items():
        pu, pv = m.get("peak_u", {}), m.get("peak_von_mises", {})
        rows.append([name, _g(pu.get("value")), _g(pu.get("time")), _g(pv.get("value")),
                     _g(pv.get("time"))])
    if rows:
        lines += ["", "Monitors (every coupling step)"]
        lines += _table(["monitor", "peak |u| [m]", "at t [s]", "peak von Mises [Pa]",
                         "at t [s]"], rows)
    rows = [[name, str(b["particles"]), _g(b.get("max_damage")), _g(b.get("mean_damage")),
             str(b.get("damaged_particles", "-"))] for name, b in s["ice"].items()]
    if rows:
        lines += ["", "Ice at the last frame (damage = broken fraction of the initial bonds)"]
        lines += _table(["body", "particles", "max damage [-]", "mean damage [-] (by volume)",
                         "damaged particles"], rows)
    if s["energy"]:
        lines += ["", f"Energies at t = {_g(s.get('energy_time'))} s"]
        lines += _table(["quantity", "value [J]"], [[k, _g(v)] for k, v in s["energy"].items()])
    return "\n".join(lines)
