"""The cable model against closed-form answers, per element count: one command.

    python benchmarks/physics_validation.py [--out docs] [--quick] [--peer-only | --no-peer]

Runs every case of `cablecheck.bench.physics_cases` (catenary sag, small-deflection
cantilever, large-deflection elastica, hanging-chain first mode, U-cable
swing damping, a cantilever's first-mode damping in and across its sag plane, stretch under fast ends at 5 and 20 Hz, a bowed steel rod in
compression, the least strain of rods bowed between clamps, a perfectly
straight rod pushed past its buckling load, a plate lifted through a cable at rising speeds, a cable
resting on a floor and on a drum), prints one
table with the measured value, the closed-form reference, the error and the
cost (wall seconds per simulated second, measured in this run, side by side),
and writes it to <out>/physics_validation.csv, a plot to
<out>/physics_validation.png and, as markdown, into <out>/physics.md between
its validation-table markers. Well under a few minutes on one core.

Then the shared problems run on PyElastica too (benchmarks/elastica_peer.py:
cantilever first frequency, a released hose's tip path, a buckled rod, the
catenary, a twisted buckled rod, a twisted slack hose; the optional `peer`
extra, `pip install -e '.[peer]'`): one more
table, closed form, cablecheck (MuJoCo), PyElastica, the differences and the
CPU seconds of each, printed and written into <out>/physics.md between its
peer-table markers with the date, machine, load and command. Without
PyElastica its columns say "not installed". About 3 minutes of CPU more.

It does not decide what passes (tests/test_physics.py does); it shows where
each case stands and what resolution costs.
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from cablecheck.bench import physics_cases as validation  # noqa: E402  (the path above makes `sim` importable from a checkout)

sys.path.insert(0, str(Path(__file__).resolve().parent))
import elastica_peer as peer  # noqa: E402  (beside this file)

COLUMNS = ["case", "elements", "measured", "reference", "error_pct", "substeps", "wall_per_sim_s", "note"]


def _row(r: validation.Result, note: str = "") -> dict:
    return {"case": r.case, "elements": r.elements, "measured": r.measured,
            "reference": "" if r.reference is None else r.reference,
            "error_pct": "" if r.error is None else 100.0 * r.error,
            "substeps": r.substeps, "wall_per_sim_s": r.wall_per_sim_s,
            "note": "; ".join(filter(None, [note, ",".join(r.warnings)]))}


def run(quick: bool = False) -> list[dict]:
    counts = (10, 20, 40) if quick else (10, 20, 40, 80)
    rows = []
    for n in counts:
        rows.append(_row(validation.catenary(n), "sag m; limp 1 m over 0.8 m"))
    for n in (None,) + counts:
        r = validation.cantilever(n)
        rows.append(_row(r, "tip m; w L^4/8EI" + ("; default element count" if n is None else "")))
    for n in counts:
        rows.append(_row(validation.cantilever(n, large=True), "tip m; elastica (solve_bvp), wL^3/EI = 3.07"))
    for n in counts:
        r = validation.chain(n)
        rows.append(_row(r, f"period s; 2 pi/(1.2024 sqrt(g/L)); amplitude left after one period "
                            f"{r.extra['amplitude_left']:.3f}"))
    for d in (0.0, 0.02, 0.1):
        r = validation.u_swing(40, damping=d)
        rows.append(_row(r, f"swing Hz; damping {d:g}: measured damping ratio {r.extra['damping_ratio']:.4f}"))
    for kw, where in ((dict(), "in the sag plane"), (dict(across=True), "across the sag"),
                      (dict(gravity=False), "gravity off")):
        for d in ((0.02, 0.1) if "gravity" not in kw else (0.02,)):
            for n in counts:
                r = validation.ring_down(n, d, **kw)
                rows.append(_row(r, f"damping ratio of the first mode; 0.2 m cantilever, {where}; "
                                    f"{r.extra['omega']:.1f} rad/s (as held {r.extra['first_mode']:.1f}), "
                                    f"beta {r.extra['beta']:.3g} s"))
    for f in (5.0, 20.0):
        r = validation.fast_ends(f)
        rows.append(_row(r, f"max |strain|; worst element {r.extra['edge']:+.4f}; "
                            f"taut (stretch > 1 %): {r.extra['stretch'] > 0.01}"))
    for n in (None, 48):
        r = validation.bowed_rod(n)
        rows.append(_row(r, "strain (negative: shorter)"))
    for kw in (dict(), dict(damping=0.0), dict(elements=40, damping=0.0), dict(elements=80, damping=0.0),
               dict(rod=validation.WIRE), dict(rod=validation.WIRE, damping=0.0)):
        r = validation.bowed(**kw)
        rod = kw.get("rod", validation.ROD)
        e = r.extra
        rows.append(_row(r, f"least strain; {rod['length']:g} m rod, r {1000 * rod['radius']:g} mm, "
                            f"{rod['young']:.3g} Pa, bowed 2 % between clamps, gravity off"
                            f"{'; default element count' if 'elements' not in kw else ''}; damping {e['damping']:g} "
                            f"(step set by {e['reason']}); |strain| < 0.1 %: {abs(r.measured) < 1e-3}; "
                            f"end force {e['force']:.4g} N (elastica {e['force_ref']:.4g}), "
                            f"mid deflection {1000 * e['deflection']:.4g} mm ({1000 * e['deflection_ref']:.4g})"))
    for shortening in (0.01, 0.03, 0.05):
        r = validation.straight_buckling(shortening)
        e = r.extra
        rows.append(_row(r, f"mid deflection m; straight 0.5 m rod, clamped, end pushed in over 0.2 s, gravity "
                            f"off, elastica; end force {e['force']:.4g} N (elastica {e['force_ref']:.4g}); "
                            f"least strain {100 * e['least']:.3f} %, at the end {100 * e['final']:.4f} %; "
                            f"bowed towards {'+z' if e['side'][2] > 0 else '-z'} (imperfection -z)"))
    for speed in (1.0, 3.0, 5.0, 8.0):
        r = validation.plate(speed)
        rows.append(_row(r, f"1 = carried; 10 mm plate; warned before running: {r.extra['warned']}"))
    for half in (0.005, 0.001):
        r = validation.plate(3.0, half_thickness=half, radius=0.002)
        rows.append(_row(r, f"1 = carried; {2000 * half:g} mm plate, r 2 mm; warned before running: "
                            f"{r.extra['warned']}"))
    for shape, units in (("box", "m"), ("box", "mm"), ("plane", "m"), ("cylinder", "m")):
        for radius in (0.002, 0.004):
            r = validation.resting(radius, units, shape)
            rows.append(_row(r, f"gap / r (mean; least {r.extra['least']:+.5f}, largest {r.extra['largest']:+.5f}); "
                                f"r {1000 * radius:g} mm, units {units}"))
    return rows


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.5g}"
    return str(v)


def print_table(rows: list[dict]) -> None:
    widths = {c: max(len(c), *(len(_fmt(r[c])) for r in rows)) for c in COLUMNS[:-1]}
    print("  ".join(c.ljust(widths[c]) for c in COLUMNS[:-1]) + "  note")
    for r in rows:
        print("  ".join(_fmt(r[c]).ljust(widths[c]) for c in COLUMNS[:-1]) + "  " + r["note"])


def write(rows: list[dict], out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "physics_validation.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        for r in rows:
            w.writerow({k: _fmt(v) for k, v in r.items()})
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    for case in ("catenary sag", "cantilever tip", "elastica tip", "chain period"):
        pts = [(r["elements"], abs(r["error_pct"]), r["wall_per_sim_s"]) for r in rows
               if r["case"] == case and r["error_pct"] != "" and "default" not in r["note"]]
        if not pts:
            continue
        n, e, w = zip(*pts)
        a.loglog(n, [max(x, 1e-4) for x in e], "o-", label=case)
        b.loglog(n, w, "o-", label=case)
    a.set_xlabel("elements")
    a.set_ylabel("|error| %")
    a.set_title("Error against closed-form answers")
    a.axhline(1.0, color="0.7", lw=0.8)
    a.legend(fontsize=8)
    b.set_xlabel("elements")
    b.set_ylabel("wall s per simulated s")
    b.set_title("Cost (this machine, this run)")
    b.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "physics_validation.png", dpi=110)


BEGIN, END = "<!-- validation table: benchmarks/physics_validation.py -->", "<!-- end of validation table -->"


def markdown(rows: list[dict]) -> str:
    lines = ["| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    lines += ["| " + " | ".join(_fmt(r[c]) for c in COLUMNS) + " |" for r in rows]
    return "\n".join(lines)


def update_doc(rows: list[dict], doc: Path) -> bool:
    """Put the table between the markers of `doc`; False when it has none."""
    return update_block(doc, BEGIN, END, markdown(rows))


PEER_BEGIN, PEER_END = "<!-- peer table: benchmarks/physics_validation.py -->", "<!-- end of peer table -->"

PEER_COLUMNS = ["case", "closed form", "cablecheck (MuJoCo)", "PyElastica", "cablecheck vs closed form %",
                "cablecheck vs PyElastica %", "CPU s cablecheck", "CPU s PyElastica", "note"]


def _blank(v) -> str:
    return "" if v is None else _fmt(v)


def peer_cells(r: peer.PeerRow) -> list[str]:
    blank = _blank
    return [r.case, blank(r.closed_form), _fmt(r.cablecheck), _fmt(r.elastica), blank(r.vs_closed_pct),
            blank(r.vs_elastica_pct), f"{r.cpu_cablecheck:.2f}",
            r.cpu_elastica if isinstance(r.cpu_elastica, str) else f"{r.cpu_elastica:.2f}", r.note]


def print_peer(rows: list, warm: float | None) -> None:
    cells = [peer_cells(r) for r in rows]
    widths = [max(len(c), *(len(x[i]) for x in cells)) for i, c in enumerate(PEER_COLUMNS[:-1])]
    print(f"\nPeer: PyElastica {peer.version()}" + ("" if warm is None else f" (numba warm-up {warm:.1f} s CPU, not counted)"))
    print("  ".join(c.ljust(w) for c, w in zip(PEER_COLUMNS[:-1], widths)) + "  note")
    for x in cells:
        print("  ".join(v.ljust(w) for v, w in zip(x[:-1], widths)) + "  " + x[-1])


def _machine() -> str:
    import os
    import platform
    model = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{os.cpu_count()} cores, {model}, {platform.system()} {platform.release()}"


def _load() -> str:
    import subprocess
    try:
        out = subprocess.run(["uptime"], capture_output=True, text=True, timeout=5, check=False).stdout
        return out.split("load average:")[1].strip()
    except (OSError, IndexError, subprocess.SubprocessError):
        return "unknown"


def peer_markdown(rows: list, command: str, load_before: str, load_after: str, warm: float | None) -> str:
    from datetime import UTC, datetime

    import numpy
    n = ", ".join(f"{k} {v}" for k, v in peer.ELEMENTS.items())
    head = (f"Measured {datetime.now(UTC):%Y-%m-%d %H:%M} UTC by `{command}` on {_machine()}; load "
            f"(uptime, 1 / 5 / 15 min) {load_before} before, {load_after} after; PyElastica {peer.version()} "
            f"(elements: {n}; PositionVerlet at {peer.CFL:g} of the fastest wave's step"
            + ("" if warm is None else f"; numba warm-up {warm:.1f} s CPU, not counted") + f"), numpy {numpy.__version__}.")
    lines = [head, "", "| " + " | ".join(PEER_COLUMNS) + " |", "|" + "---|" * len(PEER_COLUMNS)]
    lines += ["| " + " | ".join(c.replace("|", "/") for c in peer_cells(r)) + " |" for r in rows]
    return "\n".join(lines)


def update_block(doc: Path, begin: str, end: str, body: str) -> bool:
    """Put `body` between the markers `begin` and `end` of `doc`; False when it has none."""
    if not doc.exists():
        return False
    text = doc.read_text()
    if begin not in text or end not in text:
        return False
    head, rest = text.split(begin, 1)
    tail = rest.split(end, 1)[1]
    doc.write_text(f"{head}{begin}\n{body}\n{end}{tail}")
    return True


def run_peer(out: Path, command: str) -> list:
    load = _load()
    warm = peer.warm_up() if peer.AVAILABLE else None
    rows = peer.rows()
    print_peer(rows, warm)
    if update_block(out / "physics.md", PEER_BEGIN, PEER_END, peer_markdown(rows, command, load, _load(), warm)):
        print(f"updated the peer table in {out / 'physics.md'}")
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parents[1] / "docs")
    parser.add_argument("--quick", action="store_true", help="fewer element counts")
    which = parser.add_mutually_exclusive_group()
    which.add_argument("--no-peer", action="store_true", help="skip the PyElastica comparison")
    which.add_argument("--peer-only", action="store_true", help="only the PyElastica comparison (its doc table)")
    args = parser.parse_args(argv)
    command = " ".join(["python benchmarks/physics_validation.py"] + list(sys.argv[1:] if argv is None else argv))
    t0 = time.perf_counter()
    if not args.peer_only:
        rows = run(args.quick)
        print_table(rows)
        write(rows, args.out)
        if update_doc(rows, args.out / "physics.md"):
            print(f"updated the table in {args.out / 'physics.md'}")
        print(f"\n{len(rows)} rows in {time.perf_counter() - t0:.0f} s; wrote {args.out / 'physics_validation.csv'} "
              f"and {args.out / 'physics_validation.png'}")
    if not args.no_peer:
        t1 = time.perf_counter()
        run_peer(args.out, command)
        print(f"peer table in {time.perf_counter() - t1:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
