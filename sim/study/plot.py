"""A study's outputs: results.csv, study.json and study.png.

`write_outputs` writes, into the study's folder, the rows as a CSV table
(one row per variant: id, the varied values, then `cablecheck.study.result.COLUMNS`),
the same as JSON with the study's settings, each variant's report and
recording path and the answer (variants free of hard events, the length
window), and a plot of each varied value against hard / soft counts, worst
distance, max strain and min bend radius (matplotlib, Agg backend: no
display needed). Every file is written atomically.

This module does not run variants (see `cablecheck.study.execute`) or decide the answer
(see `cablecheck.study.result`).
"""

from __future__ import annotations

import csv
import io
import json
import os
import tempfile
from dataclasses import asdict
from pathlib import Path
from typing import Any

from cablecheck.study.definition import Study, format_value, varied_cables
from cablecheck.study.result import CABLE_COLUMNS, COLUMNS, Row, Status, Window, best_row

SCHEMA = "cablecheck.study/1"

PLOTTED = (("hard", "hard events"), ("soft", "soft events"), ("worst_distance", "worst distance"),
           ("max_strain", "max strain"), ("min_bend_radius", "min bend radius"))
"""Row fields drawn in study.png, with their axis labels (lengths in scene units)."""


def write_outputs(folder: Path, study: Study, rows: list[Row], *, complete: bool, units: str,
                  window: Window | None, settings: dict[str, Any]) -> dict[str, Path]:
    """Write results.csv, study.json and study.png into `folder`; return their paths."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = {"csv": folder / "results.csv", "json": folder / "study.json", "png": folder / "study.png"}
    if _mapped(study):
        paths["map"] = folder / "study_map.png"
    _atomic_text(paths["csv"], results_csv(study, rows))
    _atomic_text(paths["json"], json.dumps(study_json(study, rows, complete=complete, units=units,
                                                      window=window, settings=settings),
                                           indent=1, allow_nan=False) + "\n")
    plot(paths["png"], study, rows, units, window)
    if "map" in paths:
        plot_map(paths["map"], study, rows, units)
    return paths


def load_matplotlib():
    """matplotlib's pyplot on the Agg backend (no display), loaded on first
    use: 0.3-0.4 s, which a study spends on a core its variants leave idle
    (`cablecheck.study.execute.run_batch`'s `spare`) before it plots."""
    import matplotlib  # slow to load: only when a plot is drawn

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _numeric(values) -> bool:
    return all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in values)


def _mapped(study: Study) -> bool:
    """Two number keys: the runs also drawn as a map of the two."""
    return len(study.vary) == 2 and all(_numeric(v.values) for v in study.vary)


def plot_map(path: Path, study: Study, rows: list[Row], units: str) -> None:
    """study_map.png: the two varied keys as axes, each run a dot coloured
    by its least margin (with requirements; else its worst distance), the
    runs that keep every requirement ringed, failed runs crossed, the best
    starred."""
    plt = load_matplotlib()

    done = [r for r in rows if r.status is Status.DONE]
    field, label = ("margin", f"least margin ({units})") if study.requirements else \
        ("worst_distance", f"worst distance ({units})")
    fig, ax = plt.subplots(figsize=(6.0, 4.8))
    shown = [r for r in done if getattr(r, field) is not None]
    if shown:
        values = [getattr(r, field) for r in shown]
        top = max(abs(v) for v in values) or 1.0
        dots = ax.scatter([float(r.values[0]) for r in shown], [float(r.values[1]) for r in shown], c=values,
                          cmap="RdYlGn", vmin=-top, vmax=top, s=50, edgecolors="k", linewidths=0.4)
        fig.colorbar(dots, ax=ax, label=label)
    kept = [r for r in done if r.satisfied]
    if kept:
        ax.scatter([float(r.values[0]) for r in kept], [float(r.values[1]) for r in kept], s=140,
                   facecolors="none", edgecolors="tab:green", linewidths=1.2, label="keeps every requirement")
    bad = [r for r in rows if r.status is not Status.DONE]
    if bad:
        ax.scatter([float(r.values[0]) for r in bad], [float(r.values[1]) for r in bad], marker="x",
                   color="k", label="failed or not run")
    best = best_row(rows) if (study.requirements or study.goal) else None
    if best is not None:
        ax.plot([float(best.values[0])], [float(best.values[1])], "*", color="tab:blue", markersize=16,
                label="best")
    ax.set_xlabel(study.vary[0].key, fontsize=8)
    ax.set_ylabel(study.vary[1].key, fontsize=8)
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7, loc="best")
    ax.set_title(f"study {study.name}: {len(done)} of {len(rows)} runs", fontsize=10)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    write_atomic(Path(path), buf.getvalue())


def results_csv(study: Study, rows: list[Row]) -> str:
    """The CSV text: header id, the vary keys, COLUMNS; one line per row (empty cells for None)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    cables = varied_cables(study)
    w.writerow(["id", *(v.key for v in study.vary), *COLUMNS,
                *(f"margin: {q.label}" for q in study.requirements),
                *(f"{name}: {c}" for name in cables for c in CABLE_COLUMNS)])
    for r in rows:
        margins = r.margins or (None,) * len(study.requirements)
        per = [r.cable(name) for name in cables]
        w.writerow([r.id, *(format_value(x) for x in r.values),
                    *(_cell(getattr(r, c)) for c in COLUMNS), *(_cell(m) for m in margins),
                    *(_cell(None if x is None else getattr(x, c)) for x in per for c in CABLE_COLUMNS)])
    return buf.getvalue()


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, Status):
        return value.value
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    return str(value)


def study_json(study: Study, rows: list[Row], *, complete: bool, units: str, window: Window | None,
               settings: dict[str, Any]) -> dict:
    """The study.json document."""
    out_rows = []
    best = best_row(rows) if (study.requirements or study.goal) else None
    for r in rows:
        d = asdict(r)
        d["status"] = r.status.value
        d["values"] = {v.key: x for v, x in zip(study.vary, r.values)}
        out_rows.append(d)
    return {
        "schema": SCHEMA,
        "study": study.name,
        "study_file": str(study.path),
        "scene": str(study.scene_path),
        "units": units,
        "mode": study.mode.value,
        "vary": [{"key": v.key, "scene_key": v.path, "values": list(v.values)} for v in study.vary],
        "complete": complete,
        "settings": settings,
        "rows": out_rows,
        "free_of_hard": [r.id for r in rows if r.status is Status.DONE and r.hard == 0],
        "window": None if window is None else {**asdict(window), "clean": list(window.clean),
                                               "quiet": list(window.quiet), "key": study.vary[0].key},
        "search": {"method": study.search.method.value, "budget": study.search.budget},
        "requirements": [q.label for q in study.requirements],
        "goal": None if study.goal is None else study.goal.label,
        "runs": sum(r.status is not Status.NOT_RUN for r in rows),
        # no answer from a study that did not finish
        "best": None if best is None or not complete else {
            "id": best.id, "values": {v.key: x for v, x in zip(study.vary, best.values)},
            "margin": best.margin, "satisfied": best.satisfied, "objective": best.objective},
    }


def plot(path: Path, study: Study, rows: list[Row], units: str, window: Window | None = None) -> None:
    """study.png: one column per varied key, one row of axes per plotted field.

    A key with number values is the x axis as it is; any other (arrays,
    strings) is drawn against the value's position in its list, labelled
    with the values. A length window is shaded with its recommendation
    marked; the least margin has the requirements' line; the best run is
    starred."""
    plt = load_matplotlib()
    from matplotlib.ticker import MaxNLocator  # slow to load: only when a plot is drawn

    done = [r for r in rows if r.status is Status.DONE]
    ncol = len(study.vary)
    plotted = PLOTTED + ((("margin", "least margin"),) if study.requirements else ())
    best = best_row(rows) if (study.requirements or study.goal) else None
    searched = study.search.method.value == "optimise"
    fig, axes = plt.subplots(len(plotted), ncol, figsize=(4.2 * ncol, 2.0 * len(plotted)),
                             squeeze=False, sharex="col")
    for j, v in enumerate(study.vary):
        numeric = all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v.values)
        labels = [format_value(x) for x in v.values]
        xs = [(float(r.values[j]) if numeric else labels.index(format_value(r.values[j]))) for r in done]
        for i, (field, label) in enumerate(plotted):
            ax = axes[i][j]
            pts = sorted((x, getattr(r, field)) for x, r in zip(xs, done)
                         if getattr(r, field) is not None)
            if pts:
                ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-" if ncol == 1 and not searched else "o",
                        markersize=4)
            if window is not None and j == 0 and window.shortest is not None and window.longest is not None \
                    and window.shortest <= window.longest:
                ax.axvspan(window.shortest, window.longest, color="tab:green", alpha=0.12,
                           label="window" if i == 0 else None)
                if window.recommended is not None:
                    ax.axvline(window.recommended, color="tab:green", linewidth=1.2,
                               label="recommended" if i == 0 else None)
                if i == 0:
                    ax.legend(fontsize=6, loc="best")
            if field == "worst_distance":   # below the line: hard contact
                ax.axhline(0.0, color="tab:red", linestyle=":", linewidth=1)
            if field == "margin":        # below the line a requirement fails
                ax.axhline(0.0, color="tab:red", linestyle="--", linewidth=1, label="requirement")
            if best is not None and getattr(best, field) is not None:
                bx = float(best.values[j]) if numeric else labels.index(format_value(best.values[j]))
                ax.plot([bx], [getattr(best, field)], "*", color="tab:green", markersize=11,
                        label="best" if i == 0 else None)
                if i == 0:
                    ax.legend(fontsize=6, loc="best")
            if field in ("hard", "soft"):
                ax.yaxis.set_major_locator(MaxNLocator(integer=True))
                ax.set_ylim(-0.3, max([1] + [p[1] for p in pts]) + 0.3)
            unit = f" ({units})" if field in ("worst_distance", "min_bend_radius", "margin") else ""
            if j == 0:
                ax.set_ylabel(label + unit, fontsize=8)
            ax.grid(alpha=0.3)
            ax.tick_params(labelsize=7)
        bottom = axes[-1][j]
        bottom.set_xlabel(v.key, fontsize=8)
        if numeric:
            bottom.xaxis.set_major_locator(MaxNLocator(6))
        else:
            bottom.set_xticks(range(len(labels)), labels, rotation=30, fontsize=6)
    failed = len(rows) - len(done)
    fig.suptitle(f"study {study.name}: {len(done)} of {len(rows)} variants"
                 + (f" ({failed} failed or not run)" if failed else ""), fontsize=10)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    write_atomic(Path(path), buf.getvalue())


def _atomic_text(path: Path, text: str) -> None:
    write_atomic(path, text.encode("utf-8"))


def write_atomic(path: Path, content: bytes) -> None:
    """Write `content` to `path` through a temporary file in the same folder."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(content)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
