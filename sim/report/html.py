"""The HTML report (`cablecheck run --html PATH`): one self-contained file for people who open no viewer.

:func:`html_report` lays out a run's report dict (the JSON report's own
values, so the two never disagree) with what the run kept for it
(`cablecheck.report.evidence.HtmlEvidence`): the summary (scene, complete or
not and why, counts, settings), the clash table worst first (hard before
soft, then deepest, then earliest, numbered as the recording's clash list):
severity, type, pair in short names (full paths in the tooltip and in
`data-a` / `data-b`), worst distance in scene units to 0.01 mm (0.00001 m),
time, start and end, place along the cable, status against a baseline run
and the reviewer's note where given; then per clash its picture (an
offscreen rendering at its worst state, `cablecheck.report.render`) and its
distance history; the clashes a baseline run had and this one resolved; and
each cable's wear profile (contact time, sliding, bend cycles along the
cable, one scale per measure for the whole run) and, with dynamics, its
twist and the largest torsional moment along it. Images are PNG as `data:`
URIs, the style sheet inline, no script, nothing fetched: the file opens
offline. :func:`write_html` writes it atomically, as the JSON report is.

This module measures and renders nothing; the plots are drawn with
matplotlib's Agg canvas from numbers the run handed on.
"""

from __future__ import annotations

import base64
import html
import io
import math
from pathlib import Path

import numpy as np

from cablecheck.record.style import short_names
from cablecheck.report.document import plain, write_text
from cablecheck.report.evidence import HtmlEvidence

DISTANCE_STEP = 1e-5
"""Distances are shown rounded to this (metres): 0.01 mm, as the recording's clash list."""

SLIDING_FLOOR = 1e-6
"""Sliding below this fraction of the run's most is not wear (as the recording's wear view)."""

_CSS = """
body{font:14px/1.45 system-ui,sans-serif;margin:24px auto;max-width:1180px;color:#222;padding:0 16px}
h1{font-size:22px;margin:0 0 4px} h2{font-size:18px;margin:28px 0 8px;border-bottom:1px solid #ccc}
h3{font-size:15px;margin:18px 0 6px}
table{border-collapse:collapse;margin:6px 0} th,td{border:1px solid #ccc;padding:3px 8px;text-align:left}
th{background:#f2f2f4} td.num{text-align:right;font-variant-numeric:tabular-nums}
.hard{color:#fff;background:#d42a2a;font-weight:600} .soft{background:#ffbe28;font-weight:600}
.ok{color:#1a7f37;font-weight:600} .bad{color:#c0262d;font-weight:600}
.status-new{background:#ffe0e0} .status-present{background:#fff3cc} .status-resolved{background:#ddf4dd}
.clash{display:flex;flex-wrap:wrap;gap:12px;align-items:flex-start} .clash img{border:1px solid #ccc}
.warn{background:#fff6d6;border:1px solid #e8c95c;padding:6px 10px;margin:6px 0}
.muted{color:#666} dl{display:grid;grid-template-columns:max-content auto;gap:2px 14px;margin:6px 0}
dt{color:#555} dd{margin:0}
"""


def _e(text) -> str:
    return html.escape(str(text), quote=True)


def distance_decimals(unit: float) -> int:
    """Decimals that give 0.01 mm in scene units of `unit` metres (2 in mm, 5 in m)."""
    return max(0, int(round(-math.log10(DISTANCE_STEP / unit))))


def distance_text(value: float | None, unit: float) -> str:
    """A distance in scene units as the table shows it."""
    return "-" if value is None else f"{value:.{distance_decimals(unit)}f}"


def clash_order(events: list[dict]) -> list[int]:
    """The report's events worst first: hard before soft, then deepest, then earliest."""
    return sorted(range(len(events)), key=lambda k: (events[k]["severity"] != "hard",
                                                     events[k]["min_distance"], events[k]["t_worst"]))


def _data_uri(png: bytes) -> str:
    return "data:image/png;base64," + base64.b64encode(png).decode("ascii")


def _figure(width: float, height: float):
    """A matplotlib figure on the Agg canvas (no pyplot, no display)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg  # matplotlib loads only when plotting
    from matplotlib.figure import Figure  # (as above)

    fig = Figure(figsize=(width, height), dpi=100)
    FigureCanvasAgg(fig)
    return fig


def _png_of(fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()


def history_png(t: np.ndarray, d: np.ndarray, event: dict, clearance: float, units: str) -> bytes | None:
    """The pair's distance over time (scene units) with the clearance, contact
    and the event's interval; None without samples."""
    if len(t) == 0:
        return None
    fig = _figure(4.6, 3.0)
    ax = fig.add_subplot()
    ax.axvspan(event["t_start"], event["t_end"], color="#d42a2a" if event["severity"] == "hard" else "#ffbe28",
               alpha=0.18, lw=0, label="clash")
    ax.axhline(clearance, color="#888", ls="--", lw=1, label="clearance")
    ax.axhline(0.0, color="#444", lw=0.8, label="touching")
    gaps = np.diff(t) > 0.05          # no line across a long stretch with no samples
    for piece_t, piece_d in zip(np.split(t, np.flatnonzero(gaps) + 1), np.split(d, np.flatnonzero(gaps) + 1)):
        ax.plot(piece_t, piece_d, color="#1f77b4", lw=1.4, marker="." if len(piece_t) < 4 else None)
    ax.plot([event["t_worst"]], [event["min_distance"]], "o", color="#ff00e6", ms=6, label="worst")
    span = max(float(t[-1] - t[0]), 0.02)
    ax.set_xlim(max(float(t[0]) - 0.3 * span, 0.0), float(t[-1]) + 0.3 * span)
    ax.set_xlabel("t (s)")
    ax.set_ylabel(f"distance ({units})")
    ax.set_title("distance history (known while the pair is near)", fontsize=9)
    ax.legend(fontsize=7, loc="upper right", framealpha=0.8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return _png_of(fig)


def wear_png(cable: dict, limits: dict[str, float], floor: float, units: str) -> bytes:
    """A cable's wear profile along its length: contact time, sliding (below
    `floor` shown as nothing) and bend cycles, each on the run's one scale."""
    w = cable["wear"]
    s = np.asarray(w["s"] or [], float)
    fig = _figure(6.4, 4.2)
    axes = fig.subplots(3, 1, sharex=True)
    sliding = np.asarray(w["sliding"] or [], float)
    sliding = np.where(sliding > floor, sliding, 0.0)
    rows = (("contact_time", np.asarray(w["contact_time"] or [], float), "contact (s)", "#1f77b4"),
            ("sliding", sliding, f"sliding ({units})", "#d62728"),
            ("bend_cycles", np.asarray(w["bend_cycles"] or [], float), "bend cycles", "#2ca02c"))
    width = np.diff(np.append(s, cable["length"])) if len(s) else s
    for ax, (key, values, label, colour) in zip(axes, rows):
        if len(s):
            ax.bar(s, values, width=width, align="edge", color=colour)
        ax.set_ylim(0, limits[key] * 1.05 if limits[key] > 0 else 1.0)
        ax.set_ylabel(label, fontsize=8)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel(f"along the cable from its start ({units})")
    axes[-1].set_xlim(0, cable["length"])
    fig.suptitle(f"{cable['name']}: wear (one scale for the run)", fontsize=10)
    fig.tight_layout()
    return _png_of(fig)


def twist_png(cable: dict, units: str) -> bytes:
    """The largest torsional moment along a cable (the simulated rod's twist, per interior vertex)."""
    t = cable["twist"]
    s = np.asarray(t["s"], float)
    moment = np.asarray(t["max_moment"], float)
    fig = _figure(6.4, 1.9)
    ax = fig.subplots()
    width = np.diff(np.append(s, cable["length"])) if len(s) else s
    ax.bar(s, moment, width=width, align="center", color="#9467bd")
    ax.set_ylabel("torsion (N m)", fontsize=8)
    ax.set_xlabel(f"along the cable from its start ({units})")
    ax.set_xlim(0, cable["length"])
    ax.grid(alpha=0.3)
    fig.suptitle(f"{cable['name']}: largest torsional moment over the run", fontsize=10)
    fig.tight_layout()
    return _png_of(fig)


def _twist_line(c: dict, units: str) -> str:
    """What the report says of a cable's twist, in words ("" when it has none to say)."""
    if c.get("max_twist") is None:
        return ""
    line = f"; twist up to {c['max_twist']:.3g} degrees end to end"
    twist = c.get("twist")
    if twist and len(twist["max_moment"]) and c.get("max_twist_moment"):
        k = int(np.argmax(twist["max_moment"]))
        line += f", torsion up to {c['max_twist_moment']:.3g} N m at {twist['s'][k]:.4g} {units} along it"
    return line


def _why_incomplete(r: dict) -> str:
    if r.get("physics_error"):
        return f"the simulation diverged: {r['physics_error'].get('message')}"
    if r.get("error"):
        return f"the run failed: {r['error']['type']}: {r['error']['message']}"
    if r.get("interrupted"):
        return f"interrupted ({r['interrupted']})"
    return "stopped before its end"


def _summary(r: dict, render_warnings: list[str]) -> str:
    s, st = r["summary"], r["settings"]
    units = r["units"]
    done = ('<span class="ok">complete</span>' if r["complete"] else
            f'<span class="bad">incomplete</span>: {_e(_why_incomplete(r))}')
    rows = [("scene file", st.get("scene_file")), ("units", units),
            ("run", None), ("clashes", f"{s['hard']} hard, {s['soft']} soft ({s['static']} static, "
                                         f"{s['dynamic']} dynamic); {s.get('excused', 0)} excused at attachments"),
            ("steps", f"{st.get('steps')} simulated, {st.get('checked_steps')} checked, to t = "
                      f"{st.get('t_end', 0) or 0:.3f} s of {st.get('duration')} s"),
            ("clearance", f"{st.get('clearance')} {units}"), ("method", st.get("method")),
            ("allowed pairs", len(r.get("allowed", [])))]
    if "baseline" in r:
        b = r["baseline"]
        rows.append(("against", f"{b['report']}: {b.get('new', 0)} new, {b.get('present', 0)} still present, "
                                f"{b.get('resolved', 0)} resolved"))
    if "review" in r:
        rows.append(("reviewer's notes", f"{r['review']['file']}: {r['review']['notes']} note(s), "
                                         f"{r['review']['on_events']} on clashes"))
    if r.get("validation"):
        v = r["validation"]
        agreement = v.get("agreement")
        rows.append(("MuJoCo agrees", "-" if agreement is None else
                     f"{100 * agreement:.2f} % of {v['pair_steps']} (step, pair) classifications"))
    rows.append(("recording", r.get("recording") or "none"))
    rows.append(("versions", f"cablecheck {st.get('version')}, MuJoCo {r.get('mujoco')}"))
    out = ["<dl>"]
    for k, v in rows:
        out.append(f"<dt>{_e(k)}</dt><dd>{done if k == 'run' else _e(v)}</dd>")
    out.append("</dl>")
    warnings = ([f"MuJoCo: {k} x {v}" for k, v in (r.get("warnings") or {}).items()]
                + list(r.get("physics_warnings") or []) + list(r.get("part_warnings") or []) + render_warnings)
    for w in warnings:
        out.append(f'<div class="warn">{_e(w)}</div>')
    return "\n".join(out)


def _clash_table(r: dict, order: list[int], short: dict[str, str]) -> str:
    events, units = r["events"], r["units"]
    unit = 1e-3 if units == "mm" else 1.0
    status = any("status" in e for e in events)
    review = any("review" in e for e in events)
    head = ["#", "severity", "type", "pair", f"worst distance ({units})", "t worst (s)", "start - end (s)",
            f"along cable ({units})", "phase"]
    if status:
        head.append("status")
    if review:
        head.append("reviewer's note")
    out = ['<table id="clashes"><thead><tr>' + "".join(f"<th>{_e(h)}</th>" for h in head) + "</tr></thead><tbody>"]
    for n, k in enumerate(order, 1):
        e = events[k]
        pair = short[e["a"]] if e["a"] == e["b"] else f"{short[e['a']]} / {short[e['b']]}"
        full = e["a"] if e["a"] == e["b"] else f"{e['a']} / {e['b']}"
        cells = [f'<td class="num"><a href="#clash-{n}">{n}</a></td>',
                 f'<td class="severity {_e(e["severity"])}">{_e(e["severity"])}</td>',
                 f'<td class="type">{_e(e["type"])}</td>',
                 f'<td class="pair" title="{_e(full)}">{_e(pair)}</td>',
                 f'<td class="num distance">{distance_text(e["min_distance"], unit)}</td>',
                 f'<td class="num time">{e["t_worst"]:.3f}</td>',
                 f'<td class="num">{e["t_start"]:.3f} - {e["t_end"]:.3f}</td>',
                 f'<td class="num">{e["s"]:.{max(distance_decimals(unit) - 1, 0)}f}</td>',
                 f'<td>{_e(e["phase"])}</td>']
        if status:
            st = e.get("status", "")
            cells.append(f'<td class="status status-{_e(st)}">{_e(st)}</td>')
        if review:
            note = e.get("review")
            cells.append('<td class="review">' + ("-" if note is None else
                                                   f"{_e(note['status'])}: {_e(note['comment'])}") + "</td>")
        out.append(f'<tr class="clash-row" data-event="{k}" data-a="{_e(e["a"])}" data-b="{_e(e["b"])}" '
                   f'data-min-distance="{e["min_distance"]!r}">' + "".join(cells) + "</tr>")
    out.append("</tbody></table>")
    return "\n".join(out)


def _resolved(r: dict) -> str:
    rows = (r.get("baseline") or {}).get("resolved_events") or []
    if not rows:
        return ""
    unit = 1e-3 if r["units"] == "mm" else 1.0
    out = ["<h2>Resolved since the baseline run</h2>", '<table id="resolved"><thead><tr><th>type</th><th>pair</th>'
           f"<th>worst distance then ({_e(r['units'])})</th><th>t worst then (s)</th></tr></thead><tbody>"]
    for e in rows:
        out.append(f'<tr><td>{_e(e.get("type"))}</td><td>{_e(e.get("a"))} / {_e(e.get("b"))}</td>'
                   f'<td class="num">{distance_text(e.get("min_distance"), unit)}</td>'
                   f'<td class="num">{(e.get("t_worst") or 0):.3f}</td></tr>')
    out.append("</tbody></table>")
    return "\n".join(out)


def _clash_sections(r: dict, order: list[int], short: dict[str, str], evidence: HtmlEvidence | None) -> str:
    events, units = r["events"], r["units"]
    unit = 1e-3 if units == "mm" else 1.0
    out = []
    for n, k in enumerate(order, 1):
        e = events[k]
        pair = e["a"] if e["a"] == e["b"] else f"{e['a']} / {e['b']}"
        out.append(f'<h3 id="clash-{n}">#{n} <span class="{_e(e["severity"])}">&nbsp;{_e(e["severity"])}&nbsp;'
                   f'</span> {_e(e["type"])} {_e(pair)}</h3>')
        where = ", ".join(f"{x:.{distance_decimals(unit)}f}" for x in e["where"])
        facts = [f"worst {distance_text(e['min_distance'], unit)} {units} at t = {e['t_worst']:.3f} s "
                 f"(below the clearance {e['t_start']:.3f} - {e['t_end']:.3f} s, {e['phase']})",
                 f"at ({where}) {units}, {e['s']:.4g} {units} along {e['a']}"]
        if e.get("joints"):
            facts.append("joints: " + ", ".join(f"{j} {v:.4g}" for j, v in e["joints"].items()))
        if e.get("status"):
            facts.append(f"status: {e['status']}")
        if e.get("review"):
            facts.append(f"reviewer: {e['review']['status']}: {e['review']['comment']}")
        body = ['<div class="clash">']
        pic = None if evidence is None else evidence.pictures.png[k] if k < len(evidence.pictures.png) else None
        if pic is not None:
            body.append(f'<img class="spot" alt="clash #{n} at its worst time" src="{_data_uri(pic)}">')
        else:
            body.append('<p class="muted">(no picture: see the warnings above)</p>')
        if evidence is not None and k < len(evidence.clashes):
            c = evidence.clashes[k]
            png = history_png(np.asarray(c.t), np.asarray(c.distance) / unit, e, r["settings"]["clearance"], units)
            if png is not None:
                body.append(f'<img class="history" alt="distance history of clash #{n}" src="{_data_uri(png)}">')
        body.append("</div>")
        out.append("<ul>" + "".join(f"<li>{_e(f)}</li>" for f in facts) + "</ul>" + "".join(body))
    return "\n".join(out)


def _wear(r: dict) -> str:
    cables = r.get("cables") or []
    if not cables:
        return ""
    units = r["units"]

    def top(key: str) -> float:
        values = [v for c in cables for v in (c["wear"][key] or []) if v is not None]
        return float(max(values)) if values else 0.0

    limits = {k: top(k) for k in ("contact_time", "sliding", "bend_cycles")}
    floor = SLIDING_FLOOR * limits["sliding"]
    out = ["<h2>Wear along each cable</h2>",
           f'<p class="muted">One scale per measure for the whole run: contact up to {limits["contact_time"]:.4g} s, '
           f'sliding up to {limits["sliding"]:.4g} {_e(units)} (at most {floor:.2g} {_e(units)} counts as none), '
           f'bend cycles up to {limits["bend_cycles"]:.4g}.</p>']
    for c in cables:
        worn = c["wear"].get("most_worn")
        line = (f"most worn at {worn['s']:.4g} {units} along it: against {worn['touches']}, "
                f"{worn['contact_time']:.3g} s in contact, slid {worn['sliding']:.3g} {units}"
                if worn else "touched nothing")
        strain = c.get("max_strain")
        bend = c.get("min_bend_radius")
        out.append(f'<h3>{_e(c["name"])}</h3><p>length {c["length"]:.4g} {_e(units)}, largest strain '
                   f'{"-" if strain is None else f"{100 * strain:.3g} %"}, least bend radius '
                   f'{"-" if bend is None else f"{bend:.4g} {units}"}; {_e(line)}{_e(_twist_line(c, units))}</p>')
        out.append(f'<img class="wear" alt="wear of {_e(c["name"])}" '
                   f'src="{_data_uri(wear_png(c, limits, floor, units))}">')
        if c.get("twist") and c.get("max_twist_moment"):
            out.append(f'<img class="wear" alt="torsion along {_e(c["name"])}" '
                       f'src="{_data_uri(twist_png(c, units))}">')
    return "\n".join(out)


def html_report(report: dict, evidence: HtmlEvidence | None = None) -> str:
    """The HTML report of a run's report dict and what the run kept for it (module docstring)."""
    r = plain(report)
    events = r.get("events") or []
    order = clash_order(events)
    names = [*(e["a"] for e in events), *(e["b"] for e in events), *(c["name"] for c in r.get("cables") or [])]
    short = short_names(names)
    render_warnings = list((r.get("html") or {}).get("warnings") or [])
    if evidence is None and events:
        render_warnings.append("no clash pictures or distance histories: the run kept none")
    title = f"cablecheck: {r['scene']}"
    parts = [
        "<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{_e(title)}</title><style>{_CSS}</style></head><body>",
        f"<h1>{_e(r['scene'])}: clash report</h1>", _summary(r, render_warnings),
        f"<h2>Clashes ({len(events)})</h2>",
        _clash_table(r, order, short) if events else '<p id="no-clashes">No clash: nothing came below the clearance.</p>',
        _resolved(r), _clash_sections(r, order, short, evidence), _wear(r),
        f'<p class="muted">Written by cablecheck {_e(r["settings"].get("version"))}; the JSON report holds every '
        "number.</p></body></html>"]
    return "\n".join(p for p in parts if p) + "\n"


def write_html(report: dict, path: Path, evidence: HtmlEvidence | None = None) -> None:
    """Write the HTML report to `path` atomically (no temporary file is left)."""
    write_text(html_report(report, evidence), Path(path))
