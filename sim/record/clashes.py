"""The review recording's lists: the clash list, the event log and the summary.

`clashes/<column>`: one row per event, worst first (hard before soft, then
deepest), ranked on the `clash` sequence and at its worst time on
`sim_time` (so selecting a row's time jumps there): severity, the pair in
short names, the worst distance in scene units to 0.01 mm, status (against
a baseline run), type, phase, start, end, joint values where given, and
the pair's full paths; an entity per column, in the layout's order. `events`: one text entry at the start
and one at the end of each event, level by severity. `summary`: a markdown
document at t = 0 (settings, the clashes worst first, the allowed pairs and
the contacts attachment windows excused, the most worn place of each cable
and what it touches). The log is buffered and sent, like the
list, in columns when the recording is closed.

Not here: deciding events (`cablecheck.checker.events`) or wear (`cablecheck.checker.wear`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import rerun as rr

from cablecheck.record.columns import column, floats, strings, times as sim_time
from cablecheck.record.layout import CLASH_TIMELINE, clash_headers
from cablecheck.record.style import pair_text, short_pairs


@dataclass(frozen=True)
class Settings:
    """What the recording's properties and summary say about the run.

    Attributes:
      units: the scene's units ("m" or "mm").
      clearance: metres.
      scene_file: the scene file's path.
      version: the product version.
    """

    units: str
    clearance: float
    scene_file: str
    version: str


def send_log(rec: rr.RecordingStream, entries: list[tuple[float, str, str]]) -> None:
    """The event log: (time s, text, level) entries, one column, in time order."""
    if not entries:
        return
    entries = sorted(entries, key=lambda e: e[0])
    rec.send_columns("events", indexes=[sim_time(np.array([e[0] for e in entries]))],
                     columns=[column(rr.TextLog.descriptor_text(), strings([e[1] for e in entries])),
                              column(rr.TextLog.descriptor_level(), strings([e[2] for e in entries]))])


def distance_decimals(unit: float) -> int:
    """Decimals that give 0.01 mm (0.00001 m) in scene units of `unit` metres
    (2 in mm, 5 in m)."""
    return max(0, int(round(-np.log10(DISTANCE_STEP / unit))))


DISTANCE_STEP = 1e-5
"""The clash list's distances are rounded to this (metres): 0.01 mm."""


def clash_order(events: list) -> list[int]:
    """The clash list's order: hard before soft, then deepest (least
    distance) first, then earliest."""
    return sorted(range(len(events)), key=lambda k: (events[k].severity != "hard", float(events[k].min_distance),
                                                     float(events[k].t_worst)))


def send_clash_list(rec: rr.RecordingStream, events: list, joints: list[dict], unit: float, units: str,
                    status: list[str] | None = None, names=()) -> None:
    """The clash list: one row per event, worst first (:func:`clash_order`),
    indexed by its rank on the `clash` sequence and its worst time on
    `sim_time`; one entity per column (`clashes/<column>`, in the layout's
    order, see :data:`cablecheck.record.layout.CLASH_COLUMNS`): pairs by short names
    (:func:`cablecheck.record.style.short_names`, among `names` and the events'),
    the full paths in `a` and `b`; distances in scene units rounded to 0.01 mm.
    `status`: against a baseline run, per event; no such column without one."""
    if not events:
        return
    order = clash_order(events)
    ev = [events[k] for k in order]
    pairs = short_pairs(ev, names)
    digits = distance_decimals(unit)
    values = {"severity": strings([e.severity for e in ev]),
              "pair": strings(pairs),
              "worst_distance": floats(np.round([e.min_distance / unit for e in ev], digits)),
              "status": strings([status[k] for k in order]) if status is not None else None,
              "type": strings([e.type for e in ev]), "phase": strings([e.phase for e in ev]),
              "start": floats([e.t_start for e in ev]), "end": floats([e.t_end for e in ev]),
              "joints": strings([", ".join(f"{k} {v:.4g}" for k, v in joints[k].items()) or "-" for k in order]),
              "a": strings([e.a for e in ev]), "b": strings([e.b for e in ev])}
    index = [rr.TimeColumn(CLASH_TIMELINE, sequence=np.arange(1, len(ev) + 1)),
             sim_time(np.array([float(e.t_worst) for e in ev]))]
    headers = clash_headers(units, max(map(len, pairs)))
    for name, header in headers.items():
        if values[name] is not None:
            rec.send_columns(f"clashes/{name}", indexes=index, columns=[column(rr.ComponentDescriptor(header),
                                                                               values[name])])


def summary_text(scene: str, settings: Settings, events: list, wear: list, unit: float,
                 complete: bool = True, allowed: tuple = (), excused: tuple = (), baseline=None) -> str:
    """The run's summary as markdown: settings, the clashes worst first, what
    was allowed (`[[allow]]`) and what the attachment windows excused, worst
    first, the most worn place of each cable and what it touches."""
    units = settings.units
    lines = [f"# {scene}", "",
             f"- scene file: `{settings.scene_file}`",
             f"- units: {units}, clearance {settings.clearance / unit:.4g} {units}",
             f"- cablecheck {settings.version}" + ("" if complete else " (run interrupted: incomplete)"), ""]
    if events:
        hard = sum(e.severity == "hard" for e in events)
        status = dict(zip(map(id, events), baseline.status)) if baseline is not None else {}
        lines += [f"## {len(events)} clash(es): {hard} hard, {len(events) - hard} soft", "",
                  "| # | severity | type | pair | phase | start s | end s | worst | at s |" + (" status |" if status else ""),
                  "|---|---|---|---|---|---|---|---|---|" + ("---|" if status else "")]
        for n, e in enumerate(sorted(events, key=lambda e: (e.severity != "hard", e.min_distance)), 1):
            lines.append(f"| {n} | {e.severity} | {e.type} | {pair_text(e.a, e.b)} | {e.phase} | "
                         f"{e.t_start:.3f} | {e.t_end:.3f} | {e.min_distance / unit:.4g} {units} | "
                         f"{e.t_worst:.3f} |" + (f" {status[id(e)].value} |" if status else ""))
    else:
        lines.append("## No interference")
    if baseline is not None:
        counts = baseline.counts()
        lines += ["", f"## Against `{baseline.path}`: {counts['new']} new, {counts['present']} still present, "
                      f"{counts['resolved']} resolved"]
        if baseline.resolved:
            lines += ["", "| resolved | type | pair | worst then | at s then |", "|---|---|---|---|---|"]
            for e in sorted(baseline.resolved, key=lambda e: e.min_distance):
                lines.append(f"| {e.severity} | {e.type} | {pair_text(e.a, e.b)} | {e.min_distance / unit:.4g} {units} | "
                             f"{e.t_worst:.3f} |")
    if allowed:
        lines += ["", f"## {len(allowed)} allowed pair(s) (never clashes)", "",
                  "| type | pair | worst | at s | reason |", "|---|---|---|---|---|"]
        for p in sorted(allowed, key=lambda p: p.min_distance):
            lines.append(f"| {p.type} | {pair_text(p.a, p.b)} | {p.min_distance / unit:.4g} {units} | "
                         f"{p.t:.3f} | {p.reason} |")
    if excused:
        lines += ["", f"## {len(excused)} contact(s) excused by attachment windows (never clashes)", "",
                  "| type | pair | window | worst | at s |", "|---|---|---|---|---|"]
        for x in sorted(excused, key=lambda x: x.min_distance):
            lines.append(f"| {x.type} | {pair_text(x.a, x.b)} | {x.window} | {x.min_distance / unit:.4g} {units} | "
                         f"{x.t:.3f} |")
    lines += ["", "## Wear (per arc-length bin of each cable)", ""]
    for w in wear:
        k = w.most_worn()
        cyc = int(np.argmax(w.bend_cycles)) if w.bend_cycles.size else None
        bend = ("" if cyc is None or w.bend_cycles[cyc] == 0 else
                f"; most bending cycles {w.bend_cycles[cyc]:g} at s = {w.s[cyc] / unit:.4g} {units}")
        if k is None:
            lines.append(f"- {w.name}: touches nothing" + bend)
        else:
            lines.append(f"- {w.name}: most worn at s = {w.s[k] / unit:.4g} {units} (of "
                         f"{w.length / unit:.4g}), touching {w.touches[k]}: in contact "
                         f"{w.contact_time[k]:.3g} s, slid {w.sliding[k] / unit:.3g} {units}" + bend)
    return "\n".join(lines) + "\n"
