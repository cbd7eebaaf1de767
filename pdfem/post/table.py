"""The summary of a results file as text tables for the terminal (units in the headers).

:func:`format_summary` prints what :func:`pdfem.post.summary.summarize` computed: one section
per quantity (loads, contact pairs, reactions of ice regions, structures, reactions, monitors,
ice, energies).
"""

from __future__ import annotations

from pdfem.post.groups import AXES
from pdfem.post.shaft import shaft_lines


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
    w = _g(f["window"] * 1e3)
    rows = [[d, _g(f[d]["peak"]), _g(f[d]["time"]), _g(f[d]["mean"]), _g(f[d]["per_step_peak"]),
             _g(f[d]["per_step_time"])] for d in (*AXES, "magnitude")]
    lines += _table(["direction", f"peak [N] ({w} ms mean)", "at t [s]", "mean [N]",
                     "per-step peak [N] *", "at t [s]"], rows)
    lines.append(f"  peak: of the force averaged over {w} ms (converges with the step); "
                 "* one step's impulse / step:")
    lines.append("  grows as the step shrinks, not a design figure (docs/post.md)")
    if "max_contacts" in f:
        lines.append(f"  most particles in contact at once: {f['max_contacts']}")
    if f.get("area") is not None:
        lines.append(f"  patch area: {_g(f['area'])} m^2")
    lp = f.get("filtered")
    if lp:
        rows = [[d, _g(f[d]["per_step_peak"]), _g(lp[d]["peak"]), _g(lp[d]["time"])]
                for d in (*AXES, "magnitude")]
        lines.append(f"  peaks per step and low-passed (zero-phase Butterworth, "
                     f"{_g(lp['cutoff'])} Hz)")
        lines += _table(["direction", "per-step peak [N] *", "filtered peak [N]", "at t [s]"],
                        rows, "    ")
        lines.append(f"    largest residual |raw - filtered| (impacts): "
                     f"{_g(lp['residual']['peak'])} N at t = {_g(lp['residual']['time'])} s")
    return lines


def _ice_load_lines(s: dict) -> list[str]:
    """Patches, contact pressure and pressure-area envelope, load split by contact pair."""
    lines: list[str] = []
    for name, f in s.get("patches", {}).items():
        lines += ["", *_load_lines("Ice force on load patch", name, f)]
    for name, c in s.get("contact_pressure", {}).items():
        mp = c.get("max_pressure")
        if not mp:
            continue
        lines += ["", f"Contact pressure on '{name}' ({c['facets']} facets; mean over each frame "
                      "interval)",
                  f"  max facet pressure {_g(mp['value'])} Pa at t = {_g(mp['time'])} s, "
                  f"at {_loc(mp['location'])} m",
                  f"  largest contact area {_g(c['max_contact_area']['value'])} m^2 at "
                  f"t = {_g(c['max_contact_area']['time'])} s",
                  "  pressure-area envelope (patch grown from the peak facet):"]
        pa = c["pressure_area"]
        rows = [[_g(a), _g(p), _g(t)] for a, p, t in zip(pa["area"], pa["envelope"], pa["time"])
                if p is not None][::4]
        lines += _table(["area [m^2]", "pressure [Pa]", "at t [s]"], rows, "    ")
    for name, sp in s.get("load_split", {}).items():
        if len(sp["pairs"]) > 1:
            rows = [[k, _g(v["impulse"]), f"{100 * v['share']:.1f}"] for k, v in sp["pairs"].items()]
            lines += ["", f"Load on '{name}' by contact pair (main: '{sp['main']}'; {sp['note']})"]
            lines += _table(["pair", "impulse [N s]", "share [%]"], rows)
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
    lines += _ice_load_lines(s)
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
    lines += shaft_lines(s)
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
