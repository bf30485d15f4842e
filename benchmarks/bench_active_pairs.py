"""Active part pairs: a part pair inside the clearance no longer forces full checks.

The door of ``tests/scenes/door.toml`` (two cables across a hinge; a hinge
pin through the frame's knuckles and the door's, overlapping them by
design) is run three ways, interleaved ``--repeats`` times so all see the
same machine:

- ``pin``: as written, with the skip rule (the pin pair checked on its own,
  a batch of states at a time);
- ``pin, full every step``: the same scene checked in full at every step
  (what the skip rule replaced: before, the pin pair forced a full check
  at every step);
- ``no pin``: the same door without its pin (the skip rule's best case).

Printed: check time per step (median of the repeats), full checks and
steps proven clear, MuJoCo's simulation time per step, and the ratios
side by side; then whether the door with its pin skips what the door
without it skips and whether its check takes no longer than the
simulation. Events and pairs of the first two must be identical.

Run: python benchmarks/bench_active_pairs.py [--repeats N]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
from pathlib import Path

from cablecheck.report.document import plain
from cablecheck.run.runner import RunOptions, run_scene
from cablecheck.scene.load import load_scene

DOOR = Path(__file__).resolve().parents[1] / "tests" / "scenes" / "door.toml"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="bench-active-"))
    text = DOOR.read_text()
    start = text.index('[[parts]]\nname = "hinge/pin"')
    no_pin = text[:start] + text[text.index("[[parts]]", start + 1):text.index("\n[[allow]]")] + "\n"
    (tmp / "no_pin.toml").write_text(no_pin)
    runs = {"pin": (DOOR, True), "pin, full every step": (DOOR, False), "no pin": (tmp / "no_pin.toml", True)}
    times: dict[str, list[float]] = {k: [] for k in runs}
    sim: dict[str, list[float]] = {k: [] for k in runs}
    last: dict[str, dict] = {}
    for _ in range(args.repeats):
        for name, (path, advance) in runs.items():
            rep = run_scene(load_scene(path), RunOptions(report=tmp / "r.json", record=None, advance=advance))
            times[name].append(rep["timing"]["check_ms_per_step"])
            sim[name].append(rep["timing"]["sim_ms_per_step"])
            last[name] = rep
    for key in ("events", "pairs", "allowed"):
        assert plain(last["pin"][key]) == plain(last["pin, full every step"][key]), key
    base = statistics.median(times["pin"])
    print(f"{'run':<22} {'check ms/step':>13} {'sim ms/step':>11} {'check/sim':>9} {'vs pin':>7}  full / proven clear")
    for name in runs:
        t, s = statistics.median(times[name]), statistics.median(sim[name])
        adv = last[name]["settings"]["advance"]
        counts = "-" if adv is None else f"{adv['full_checks']} / {adv['proven_clear_steps']}"
        print(f"{name:<22} {t:>13.3f} {s:>11.3f} {t / s:>9.2f} {t / base:>7.2f}  {counts}")
    same = last["pin"]["settings"]["advance"] == last["no pin"]["settings"]["advance"]
    ratio = statistics.median(times["pin"]) / statistics.median(sim["pin"])
    print(f"pin skips the steps the door without it skips: {'yes' if same else 'no'}; "
          f"pin check <= simulation: {'yes' if ratio <= 1.0 else 'no'} ({ratio:.2f})")


if __name__ == "__main__":
    main()
