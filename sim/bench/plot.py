"""`bench.png`: the bench's discretisation, physics, scale and side-by-side
tables as one 2 x 2 figure (matplotlib, Agg backend: no display needed).

It reads the finished tables only; it measures nothing and writes no CSV
(`cablecheck.bench.table`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from cablecheck.bench.table import Table


def plot(tables: dict[str, Table], path: Path) -> Path:
    """A 2 x 2 PNG: discretisation, physics, scale and side by side."""
    import matplotlib  # slow to load: only when the bench draws its plot

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 2, figsize=(11, 8), dpi=72)
    t = tables["discretisation"]
    a = ax[0, 0]
    for k, (label, ms, err, miss) in enumerate(zip(t.column("config"), t.column("ms_large"),
                                                   t.column("worst_error_mm"), t.column("missed"))):
        a.scatter(ms, err, s=40)
        a.annotate(f"{label} ({miss} missed)", (ms, err), fontsize=8,
                   xytext=(6, 10 - 12 * (k % 3)), textcoords="offset points")
    a.set_xscale("log")
    a.set_xlabel("ms per check on the large scene (ms_large)")
    a.set_ylabel("worst distance error, mm")
    a.set_title("Discretisation vs exact geometry")
    t = tables["physics"]
    a = ax[0, 1]
    for ref, marker in (("catenary", "o"), ("cantilever", "s")):
        for dt in sorted({r[3] for r in t.rows if r[0] == ref}):
            rows = [r for r in t.rows if r[0] == ref and r[3] == dt]
            a.plot([r[5] for r in rows], [abs(r[4]) for r in rows], marker=marker,
                   label=f"{ref}, dt {dt:g} ms")
            for r in rows:
                a.annotate(str(r[1]), (r[5], abs(r[4])), fontsize=7, xytext=(3, 3), textcoords="offset points")
    a.set_xscale("log")
    a.set_yscale("log")
    a.set_xlabel("ms wall per simulated second (labels: elements)")
    a.set_ylabel("|error| %")
    a.set_title("Physics resolution vs analytic references")
    a.legend(fontsize=7)
    t = tables["scale"]
    a = ax[1, 0]
    for axis, col in (("cables", "points"), ("parts", "parts")):
        rows = [r for r in t.rows if r[0] == axis]
        x = [r[t.columns.index(col)] for r in rows]
        a.plot(x, [r[4] for r in rows], "o-", label=f"points, vs {col}")
        a.plot(x, [r[5] for r in rows], "s--", label=f"exact, vs {col}")
    a.set_xscale("log")
    a.set_yscale("log")
    a.set_xlabel("cable points / parts (the other axis fixed)")
    a.set_ylabel("ms per check")
    a.set_title("Scale")
    a.legend(fontsize=7)
    t = tables["side_by_side"]
    a = ax[1, 1]
    labels, ours, other = [], [], []
    for r in t.rows:
        if r[6] is None or r[5] == "fcl query only" or r[5].startswith("detect"):
            continue
        labels.append(f"{r[0]}\n{r[1]} vs {r[5].split()[0]}")
        ours.append(r[4])
        other.append(r[6])
    y = np.arange(len(labels))
    a.barh(y - 0.2, ours, 0.4, label="checker")
    a.barh(y + 0.2, other, 0.4, label="other (fcl / mj_collision)")
    a.set_yticks(y, labels, fontsize=6)
    a.set_xscale("log")
    a.set_xlabel("ms per check / per collision pass")
    a.set_title("Side by side")
    a.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path
