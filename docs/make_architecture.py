"""Draw docs/architecture.png: cablecheck's sub-packages and the path a scene takes.

Run from the repository root: python docs/make_architecture.py
"""
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.patches import FancyArrowPatch, FancyBboxPatch

BOXES = {  # name: (x, y, width, height, second line, colour)
    "cli": (4.3, 7.2, 4.1, 0.9, "cablecheck run | check | sweep | study | bench", "#d9d9d9"),
    "scene": (0.2, 4.6, 2.2, 1.1, "TOML -> frozen Scene\n(SI units, checked)", "#cfe2f3"),
    "build": (3.0, 4.6, 2.4, 1.1, "MuJoCo models (MjSpec),\nfrozen Built, static build", "#cfe2f3"),
    "run": (6.0, 4.6, 2.6, 1.1, "settle, step, check batches,\nskip rule, divergence", "#cfe2f3"),
    "report": (9.4, 5.3, 2.4, 0.9, "RunOutcome -> JSON report,\n--baseline, --review", "#cfe2f3"),
    "record": (9.4, 4.0, 2.4, 0.9, "frames -> rerun clash\nreview (.rrd)", "#cfe2f3"),
    "detection": (3.6, 2.4, 2.6, 1.0, "MuJoCo's own contacts\n(detection model)", "#fce5cd"),
    "checker": (7.6, 2.4, 3.0, 1.0, "geometry, no MuJoCo: interference,\nskip rule, events, validation, wear", "#d9ead3"),
    "study": (0.2, 7.2, 3.0, 0.9, "variants on Dask, each run as run does", "#ead1dc"),
    "bench": (9.2, 7.2, 2.6, 0.9, "timing tables, harness scenes", "#ead1dc"),
}


def centre(name, side):
    x, y, w, h = BOXES[name][:4]
    return {"l": (x, y + h / 2), "r": (x + w, y + h / 2), "t": (x + w / 2, y + h),
            "b": (x + w / 2, y)}[side]


ARROWS = [  # (from, side, to, side, label)
    ("scene", "r", "build", "l", "Scene"),
    ("build", "r", "run", "l", "Built"),
    ("run", "r", "report", "l", ""),
    ("run", "r", "record", "l", ""),
    ("run", "b", "detection", "t", "states"),
    ("run", "b", "checker", "t", "states"),
    ("detection", "r", "checker", "l", "contacts"),
    ("cli", "b", "run", "t", ""),
    ("cli", "l", "study", "r", ""),
    ("cli", "r", "bench", "l", ""),
    ("study", "b", "scene", "t", "variant scenes"),
]


def main() -> None:
    fig, ax = plt.subplots(figsize=(12, 8.4))
    for name, (x, y, w, h, text, colour) in BOXES.items():
        ax.add_patch(FancyBboxPatch((x, y), w, h, boxstyle="round,pad=0.05", fc=colour, ec="black"))
        ax.text(x + w / 2, y + h - 0.22, f"cablecheck.{name}" if name != "cli" else "cablecheck.cli",
                ha="center", va="center", fontsize=11, weight="bold")
        ax.text(x + w / 2, y + (h - 0.3) / 2, text, ha="center", va="center", fontsize=8.5)
    for a, sa, b, sb, label in ARROWS:
        p, q = centre(a, sa), centre(b, sb)
        ax.add_patch(FancyArrowPatch(p, q, arrowstyle="-|>", mutation_scale=14, lw=1.3))
        if label:
            ax.text((p[0] + q[0]) / 2, (p[1] + q[1]) / 2 + 0.12, label, ha="center", fontsize=8.5,
                    style="italic", bbox=dict(fc="white", ec="none", pad=0.5))
    ax.text(6.0, 1.5, "sim/ installs as cablecheck, checker/ as cablecheck.checker; blue: the stages a scene "
            "passes through, left to right.\nOrange: MuJoCo's cross-check; green: pure geometry on numpy "
            "arrays; pink: built on the stages (a study runs variants, bench measures); grey: the command line.",
            ha="center", va="center", fontsize=9)
    ax.set_xlim(0, 12)
    ax.set_ylim(1.0, 8.4)
    ax.set_axis_off()
    ax.set_title("cablecheck: the rooms and the data path", fontsize=13)
    out = Path(__file__).with_name("architecture.png")
    fig.savefig(out, dpi=110, bbox_inches="tight")
    print(out)


if __name__ == "__main__":
    main()
