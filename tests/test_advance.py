"""Conservative advancement (cablecheck.checker.advance) changes no answer.

Every example scene is run with the skip rule and checking every step in
full; events and pairs must be identical, and validation compares exactly
the fully checked steps. The bound itself is tested module by module
(tests/test_advance_*.py).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from helpers import examples, seeds
from hypothesis import given, settings, strategies as st

from cablecheck.checker.advance import Advancement
from cablecheck.run.runner import RunOptions, run_scene
from cablecheck.scene.load import load_scene

SCENES = sorted((Path(__file__).resolve().parents[1] / "scenes").glob("*.toml"))
SKIP_CHECK_S = 2.0
SKIP_CHECK_S_ROBOT_CELL = 1.0   # checked in full it costs 7 ms a step; its arm moves throughout


def _strip(rows):
    return [{k: (np.asarray(v).tolist() if isinstance(v, np.ndarray) else v) for k, v in r.items()} for r in rows]


def _skipping_and_in_full(scene, tmp_path):
    """`scene` run with the skip rule and with every step checked in full:
    both reports, after asserting their events and pairs are the same."""
    fast = run_scene(scene, RunOptions(report=tmp_path / "a.json", record=None))
    full = run_scene(scene, RunOptions(report=tmp_path / "b.json", record=None, advance=False))
    assert _strip(fast["events"]) == _strip(full["events"])
    assert _strip(fast["pairs"]) == _strip(full["pairs"])
    return fast, full


@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.stem)
def test_skipping_changes_no_answer(path: Path, tmp_path):
    # the first SKIP_CHECK_S of each example: long enough for its motions to
    # bring its pairs near and apart (the robot cell's first second: its arm
    # moves from the start and its two pairs stay near)
    scene = load_scene(path)
    limit = SKIP_CHECK_S_ROBOT_CELL if path.stem == "robot_cell" else SKIP_CHECK_S
    scene = dataclasses.replace(scene, duration=min(scene.duration, limit))
    fast, full = _skipping_and_in_full(scene, tmp_path)
    assert fast["summary"] == full["summary"]
    for a, b in zip(fast["cables"], full["cables"]):
        assert a["max_strain"] == b["max_strain"] and a["min_bend_radius"] == b["min_bend_radius"]
    adv = fast["settings"]["advance"]
    assert full["settings"]["advance"] is None
    if adv is not None:
        assert adv["full_checks"] + adv["proven_clear_steps"] == fast["settings"]["checked_steps"]
        if path.stem in ("arm", "keepout_bolt", "drawer_pinch"):
            # a pair inside the clearance for long stretches: checked on its own, the rest skipped
            assert adv["proven_clear_steps"] > adv["full_checks"]
    if "validation" in fast:                                  # MuJoCo compared at every checked step
        assert fast["validation"]["compared_steps"] == fast["settings"]["checked_steps"]
        assert fast["validation"] == full["validation"]


def test_drawer_skips_steps(tmp_path):
    scene = load_scene(SCENES[[p.stem for p in SCENES].index("drawer")])
    rep = run_scene(scene, RunOptions(report=tmp_path / "a.json", record=None))
    assert rep["settings"]["advance"]["proven_clear_steps"] > 0


def test_attached_part_moves_while_far_part_approaches(tmp_path):
    """The drawer (carrying the cable's end) moves out while a probe on its
    own body comes down onto the cable's middle: per-centre gaps in each
    part's own frame must still catch the probe."""
    text = (SCENES[[p.stem for p in SCENES].index("drawer")]).read_text()
    text = text.replace("duration = 4.0", "duration = 1.5") + '''
[[bodies]]
name = "probe"
pos = [0, 0, 0]

[[parts]]
name = "probe/block"
body = "probe"
shape = "box"
size = [20, 20, 20]
pos = [130, 0, 200]

[[motion]]
body = "probe"
keys = [ { t = 0.0, pos = [0, 0, 0] },
         { t = 1.5, pos = [0, 0, -125] } ]
'''
    path = tmp_path / "probe.toml"
    path.write_text(text)
    scene = load_scene(path)
    fast, full = _skipping_and_in_full(scene, tmp_path)
    assert any(e["b"] == "probe/block" for e in _strip(full["events"]))
    assert fast["settings"]["advance"]["proven_clear_steps"] > 0


def test_sliding_cable_cable_contact(tmp_path):
    """The crossing's second lead carried along the first: the contact slides
    along "power" while the skipped steps evaluate the active pair on their
    own; the answers are those of checking every step in full."""
    text = (SCENES[[p.stem for p in SCENES].index("crossing")]).read_text()
    text = text.replace("duration = 0.4", "duration = 0.8")
    text = text.replace('start = { pos = [0, -120, 100] }', 'start = { body = "carriage", pos = [0, -120, 100] }')
    text = text.replace('end = { pos = [0, 120, 100] }', 'end = { body = "carriage", pos = [0, 120, 100] }')
    text += '''
[[bodies]]
name = "carriage"

[[motion]]
body = "carriage"
keys = [ { t = 0.0, pos = [0, 0, 0] }, { t = 0.8, pos = [60, 0, 0] } ]
'''
    path = tmp_path / "sliding.toml"
    path.write_text(text)
    scene = load_scene(path)
    fast, full = _skipping_and_in_full(scene, tmp_path)
    assert [e["type"] for e in full["events"]] == ["cable-cable"]
    adv = fast["settings"]["advance"]
    assert adv["proven_clear_steps"] > adv["full_checks"]


def _random_scene_text(seed: int) -> str:
    """A small random scene in mm: two cables between a fixed point and a
    moving body, random primitives on the world and on two moving bodies
    (one a keep-out), random keyframes; contact off so the cables pass
    through parts and each other (every kind of pair comes and goes)."""
    rng = np.random.default_rng(seed)
    shapes = [("box", 3), ("sphere", 1), ("capsule", 2), ("cylinder", 2)]
    text = f'''[scene]
name = "random-{seed}"
units = "mm"
duration = 0.6
settle = 0.3

[effects]
contact = []

[check]
clearance = {rng.uniform(1.0, 4.0):.3f}
'''
    for b in range(2):
        text += f'\n[[bodies]]\nname = "b{b}"\n'
        moves = np.vstack([np.zeros(3), rng.uniform(-60, 60, (2, 3))])       # bodies start at the origin
        keys = ", ".join(f"{{ t = {t:.2f}, pos = [{x:.1f}, {y:.1f}, {z:.1f}] }}"
                         for t, (x, y, z) in zip((0.0, 0.3, 0.6), moves))
        text += f'\n[[motion]]\nbody = "b{b}"\nkeys = [ {keys} ]\n'
    for k in range(5):
        kind, n = shapes[int(rng.integers(len(shapes)))]
        size = ", ".join(f"{v:.1f}" for v in rng.uniform(5, 25, n))
        pos = ", ".join(f"{v:.1f}" for v in rng.uniform(-80, 80, 3) + [0, 0, 60])
        body = ["world", "b0", "b1"][k % 3]
        text += (f'\n[[parts]]\nname = "p{k}"\nbody = "{body}"\nshape = "{kind}"\nsize = [{size}]\n'
                 f'pos = [{pos}]\nkeepout = {"true" if k == 4 else "false"}\n')
    for c in range(2):
        a = rng.uniform(-120, 120, 3) + [0, 0, 80]
        e = rng.uniform(-120, 120, 3) + [0, 0, 80]
        length = float(np.linalg.norm(e - a)) * rng.uniform(1.05, 1.4)
        text += (f'\n[[cables]]\nname = "c{c}"\nradius = {rng.uniform(2, 5):.2f}\n'
                 f'start = {{ pos = [{a[0]:.1f}, {a[1]:.1f}, {a[2]:.1f}] }}\n'
                 f'end = {{ body = "b{c}", pos = [{e[0]:.1f}, {e[1]:.1f}, {e[2]:.1f}] }}\n'
                 f'length = {length:.1f}\nsegments = {int(rng.integers(12, 30))}\nyoung = 1.0e7\n'
                 f'density = 1500\n')
    return text


@pytest.mark.parametrize("seed", seeds(3))
def test_random_scenes_skip_without_changing_answers(seed: int, tmp_path):
    path = tmp_path / "random.toml"
    path.write_text(_random_scene_text(seed))
    scene = load_scene(path)
    fast, full = _skipping_and_in_full(scene, tmp_path)
    for a, b in zip(fast["cables"], full["cables"]):
        assert a["max_strain"] == b["max_strain"] and a["min_bend_radius"] == b["min_bend_radius"]


def _turning_bodies(rng: np.random.Generator, spread: float, turn: float) -> str:
    """Two [[bodies]], b0 and b1, within `spread` mm of the axis at 60 mm up, each turning through two
    random euler keys of up to `turn` degrees over 0.5 s (a turning scene's bodies)."""
    text = ""
    for b in range(2):
        x, y = rng.uniform(-spread, spread), rng.uniform(-spread, spread)
        text += f'\n[[bodies]]\nname = "b{b}"\npos = [{x:.1f}, {y:.1f}, 60.0]\n'
        turns = np.vstack([np.zeros(3), rng.uniform(-turn, turn, (2, 3))])
        keys = ", ".join(f"{{ t = {t:.2f}, euler = [{x:.1f}, {y:.1f}, {z:.1f}] }}"
                         for t, (x, y, z) in zip((0.0, 0.25, 0.5), turns))
        text += f'\n[[motion]]\nbody = "b{b}"\nkeys = [ {keys} ]\n'
    return text


def _one_cable(rng: np.random.Generator) -> str:
    """A turning scene's cable c0 between two random points, 10 % longer than its chord."""
    a, e = rng.uniform(-120, 120, 3) + [0, 0, 60], rng.uniform(-120, 120, 3) + [0, 0, 60]
    return (f'\n[[cables]]\nname = "c0"\nradius = 3.0\nstart = {{ pos = [{a[0]:.1f}, {a[1]:.1f}, {a[2]:.1f}] }}\n'
            f'end = {{ pos = [{e[0]:.1f}, {e[1]:.1f}, {e[2]:.1f}] }}\n'
            f'length = {float(np.linalg.norm(e - a)) * 1.1:.1f}\nsegments = 12\n')


def _turning_scene_text(seed: int) -> str:
    """A small random scene in mm whose bodies turn: primitives (many of
    them solids of revolution) on the world and on two bodies turning about
    random axes through points near them, so part pairs sweep past each
    other, come within the clearance and overlap; one cable; contact off."""
    rng = np.random.default_rng(seed)
    shapes = [("box", 3), ("sphere", 1), ("capsule", 2), ("cylinder", 2), ("cylinder", 2)]
    text = (f'[scene]\nname = "turning-{seed}"\nunits = "mm"\nduration = 0.5\nsettle = 0.1\n\n'
            f'[effects]\ncontact = []\n\n[check]\nclearance = {rng.uniform(2.0, 5.0):.3f}\n')
    text += _turning_bodies(rng, 30, 90)
    for k in range(6):
        kind, n = shapes[int(rng.integers(len(shapes)))]
        size = ", ".join(f"{v:.1f}" for v in rng.uniform(4, 20, n))
        pos = ", ".join(f"{v:.1f}" for v in rng.uniform(-35, 35, 3) + [0, 0, 60 if k % 3 == 0 else 0])
        body = ["world", "b0", "b1"][k % 3]
        text += f'\n[[parts]]\nname = "p{k}"\nbody = "{body}"\nshape = "{kind}"\nsize = [{size}]\npos = [{pos}]\n'
    return text + _one_cable(rng)


@pytest.mark.parametrize("seed", seeds(1))
def test_turning_part_pairs_skip_without_changing_answers(seed: int, tmp_path):
    """Part pairs bounded relative to each other and modulo turns about a
    solid's axis (which alone prove about a thousand pair-states clear in
    these two scenes): on bodies turning about random axes, the events and
    pairs, part-part ones among them, are those of checking every step in
    full. (The bound's own brute-force tests are in test_advance_partpairs.)"""
    path = tmp_path / "turning.toml"
    path.write_text(_turning_scene_text(seed))
    scene = load_scene(path)
    fast, full = _skipping_and_in_full(scene, tmp_path)
    assert any(p["type"] == "part-part" for p in full["pairs"])
    assert fast["settings"]["advance"]["proven_clear_steps"] > 0


DOOR = Path(__file__).resolve().parent / "scenes" / "door.toml"


def _door_variants(tmp_path) -> dict[str, Path]:
    """The door scene as written (pin allowed), without its [[allow]] pairs
    (the pin overlaps: hard part-part events) and without the pin."""
    text = DOOR.read_text()
    plain = text[:text.index("\n[[allow]]")] + "\n"
    start = plain.index('[[parts]]\nname = "hinge/pin"')
    no_pin = plain[:start] + plain[plain.index("[[parts]]", start + 1):]
    out = {"door": DOOR}
    for name, body in (("no_allow", plain), ("no_pin", no_pin)):
        (tmp_path / f"{name}.toml").write_text(body)
        out[name] = tmp_path / f"{name}.toml"
    return out


def test_door_hinge_pin_never_forces_full_checks(tmp_path):
    """A hinge pin through its knuckles, one of them on the moving door:
    a part pair inside the clearance for the whole run, checked on its own.
    The door skips exactly the steps the same door without the pin skips,
    and its answers are those of checking every step in full."""
    runs = {}
    for name, path in _door_variants(tmp_path).items():
        scene = dataclasses.replace(load_scene(path), duration=0.5)   # half its swing: CI's time
        fast = run_scene(scene, RunOptions(report=tmp_path / f"{name}.json", record=None))
        if name != "no_pin":
            full = run_scene(scene, RunOptions(report=tmp_path / f"{name}-full.json", record=None, advance=False))
            for key in ("events", "pairs", "allowed", "summary", "validation"):
                assert _strip(fast[key]) == _strip(full[key]) if isinstance(fast[key], list) \
                    else fast[key] == full[key], key
        runs[name] = fast
    skip = {name: rep["settings"]["advance"] for name, rep in runs.items()}
    assert skip["door"] == skip["no_allow"] == skip["no_pin"]
    # the door panel swinging away from the frame's post: its boxes stay apart
    # at every state (cablecheck.checker.advance.partpairs), no full check past the first
    assert skip["door"]["full_checks"] == 1
    # the pin: allowed in the scene as written, hard part-part events without the allow pairs
    pin = {(p["a"], p["b"]) for p in runs["door"]["allowed"]}
    assert pin == {("hinge/knuckle_lower", "hinge/pin"), ("hinge/knuckle_upper", "hinge/pin"),
                   ("hinge/pin", "door/knuckle")}
    assert all(p["min_distance"] < 0 and p["reason"] for p in runs["door"]["allowed"])
    hard = {(e["a"], e["b"]) for e in runs["no_allow"]["events"] if e["type"] == "part-part"}
    assert hard == pin and not any(e["type"] == "part-part" for e in runs["door"]["events"])
    cable = lambda rep: [e for e in rep["events"] if e["type"] != "part-part"]
    assert _strip(cable(runs["door"])) == _strip(cable(runs["no_allow"]))


@pytest.mark.parametrize("seed", seeds(1))
def test_sparse_part_gaps_change_no_answer(seed: int, tmp_path, monkeypatch):
    """The sparse centre-part gaps (forced on these small scenes) give the
    answers of checking every step in full, and skip steps as the dense table
    does where no centre moved farther than FAR_HORIZONS horizons."""
    path = tmp_path / "random.toml"
    path.write_text(_random_scene_text(seed))
    scene = load_scene(path)
    dense = run_scene(scene, RunOptions(report=tmp_path / "d.json", record=None))
    monkeypatch.setattr(Advancement, "SPARSE_ENTRIES", 0)
    fast, _ = _skipping_and_in_full(scene, tmp_path)
    a, d = fast["settings"]["advance"], dense["settings"]["advance"]
    assert a["proven_clear_steps"] <= d["proven_clear_steps"]
    assert a["proven_clear_steps"] >= 0.9 * d["proven_clear_steps"]


def test_sparse_part_gaps_on_the_drawer(tmp_path, monkeypatch):
    """The sparse gaps on the drawer: the same answers; they skip at most
    what the dense table skips (a centre past their cap ends a run: the
    cable rides the drawer out farther than FAR_HORIZONS horizons), and
    nearly as much."""
    scene = load_scene(SCENES[[p.stem for p in SCENES].index("drawer")])
    dense = run_scene(scene, RunOptions(report=tmp_path / "d.json", record=None))
    monkeypatch.setattr(Advancement, "SPARSE_ENTRIES", 0)
    sparse = run_scene(scene, RunOptions(report=tmp_path / "a.json", record=None))
    assert _strip(sparse["events"]) == _strip(dense["events"])
    assert _strip(sparse["pairs"]) == _strip(dense["pairs"])
    a, d = sparse["settings"]["advance"], dense["settings"]["advance"]
    assert a["full_checks"] + a["proven_clear_steps"] == d["full_checks"] + d["proven_clear_steps"]
    assert 0.99 * d["proven_clear_steps"] <= a["proven_clear_steps"] <= d["proven_clear_steps"]




def test_harness_pairs_checked_on_their_own(tmp_path, monkeypatch):
    """A small harness (9 cables threaded through 60 parts, a few parts and
    part pairs inside the clearance, the cables falling onto the parts, one
    carriage moving): a centre whose bound against a part fails, or a pair
    of cable blocks, is checked on its own (promoted) instead of forcing a
    full check of every cable against every part. The answers are those of
    checking every step in full, with far fewer full checks than without
    promotion."""
    from cablecheck.bench.harness import harness_scene, write_scene
    from cablecheck.run import stepcheck

    data = harness_scene(9, 60, segments=12, duration=0.2)
    scene = load_scene(write_scene(data, tmp_path / "harness.toml"))
    fast = run_scene(scene, RunOptions(report=tmp_path / "a.json", record=None))
    full = run_scene(scene, RunOptions(report=tmp_path / "b.json", record=None, advance=False))
    for key in ("events", "pairs", "summary", "validation"):
        assert _strip(fast[key]) == _strip(full[key]) if isinstance(fast[key], list) else fast[key] == full[key], key
    assert fast["events"]
    monkeypatch.setattr(stepcheck, "PROMOTE_SHARE", 0.0)
    monkeypatch.setattr(stepcheck, "PROMOTE_MIN", 0)
    strict = run_scene(scene, RunOptions(report=tmp_path / "c.json", record=None))
    assert _strip(strict["events"]) == _strip(fast["events"])
    a, s = fast["settings"]["advance"], strict["settings"]["advance"]
    assert a["full_checks"] + a["proven_clear_steps"] == s["full_checks"] + s["proven_clear_steps"]
    assert a["full_checks"] < 0.75 * s["full_checks"]


def _rich_scene_text(seed: int, folder: Path) -> str:
    """A random scene in mm far from the origin with every kind of part
    (the five primitives, a mesh, a keep-out) on the world and on two
    bodies, one sliding fast (up to about 1 m/s) and one turning past
    180 degrees; three cables with ends on the world and on the bodies,
    one clipped to the sliding body, one end naming the part it is
    fastened to; contact on or off."""
    import trimesh

    rng = np.random.default_rng(seed)
    o = rng.uniform(-5000, 5000, 3)                       # the scene's own origin, far from the world's
    mesh = trimesh.creation.icosphere(subdivisions=1, radius=12.0) if seed % 2 else \
        trimesh.creation.annulus(r_min=6.0, r_max=14.0, height=10.0)
    mesh.export(folder / "part.stl")
    contact = '["cable-structure"]' if seed % 3 == 0 else "[]"
    text = (f'[scene]\nname = "rich-{seed}"\nunits = "mm"\nduration = 0.3\nsettle = 0.1\n\n'
            f'[effects]\ncontact = {contact}\n\n[check]\nclearance = {rng.uniform(2.0, 6.0):.3f}\n')

    def v(x):
        return ", ".join(f"{c:.2f}" for c in x)

    text += f'\n[[bodies]]\nname = "slide"\npos = [{v(o)}]\n'
    moves = o + np.vstack([np.zeros(3), rng.uniform(-120, 120, (2, 3))])
    keys = ", ".join(f"{{ t = {t:.2f}, pos = [{v(x)}] }}" for t, x in zip((0.0, 0.15, 0.3), moves))
    text += f'\n[[motion]]\nbody = "slide"\ninterpolation = "linear"\nkeys = [ {keys} ]\n'
    text += f'\n[[bodies]]\nname = "turn"\npos = [{v(o + [0, 0, 40])}]\n'
    turns = ", ".join(f"{{ t = {t:.2f}, pos = [{v(o + [0, 0, 40])}], euler = [0, 0, {a:.1f}] }}"
                      for t, a in ((0.0, 0.0), (0.2, float(rng.choice([200.0, -270.0]))), (0.3, 90.0)))
    text += f'\n[[motion]]\nbody = "turn"\nkeys = [ {turns} ]\n'
    kinds = [("box", 3), ("sphere", 1), ("capsule", 2), ("cylinder", 2), ("ellipsoid", 3), ("mesh", 0)]
    names = []
    for k, (kind, n) in enumerate(kinds + [kinds[int(rng.integers(5))]]):
        body = ["world", "slide", "turn"][int(rng.integers(3))]
        pos = rng.uniform(-50, 50, 3) + (o if body == "world" else 0)
        name = f"a{k % 2}/p{k}"
        names.append(name)
        text += f'\n[[parts]]\nname = "{name}"\nbody = "{body}"\nshape = "{kind}"\npos = [{v(pos)}]\n'
        text += f'euler = [{v(rng.uniform(-180, 180, 3))}]\n'
        text += 'file = "part.stl"\n' if kind == "mesh" else f'size = [{v(rng.uniform(4, 18, n))}]\n'
        if k == 6:
            text += "keepout = true\n"
    for c in range(3):
        a = o + rng.uniform(-90, 90, 3)
        e = rng.uniform(-90, 90, 3)
        end_body = ["world", "slide", "turn"][c]
        e_world = e + (o if end_body == "world" else 0)
        fastened = f', part = "{names[int(rng.integers(len(names)))]}"' if c == 2 else ""
        text += (f'\n[[cables]]\nname = "c{c}"\nradius = {rng.uniform(2, 5):.2f}\n'
                 f'start = {{ pos = [{v(a)}]{fastened} }}\nend = {{ body = "{end_body}", pos = [{v(e_world)}] }}\n'
                 f'segments = {int(rng.integers(14, 26))}\nyoung = 1.0e7\n')
        if c == 1:
            text += f'clips = [ {{ body = "slide", pos = [{v(0.5 * (a - o + e))}] }} ]\n'
    return text


@settings(max_examples=examples(1), deadline=None)       # about 7-10 s an example on one core (CI's budget: one)
@given(seed=st.integers(0, 2**31 - 1))
def test_rich_random_scenes_skip_without_changing_answers(seed: int, tmp_path_factory):
    """Every kind of part (meshes and keep-outs among them) on fast and
    turning bodies, ends and clips on them, far from the origin: the skip
    rule's events, pairs, excused contacts and MuJoCo comparison are those
    of checking every step in full."""
    folder = tmp_path_factory.mktemp("rich")
    path = folder / "rich.toml"
    path.write_text(_rich_scene_text(seed, folder))
    fast, full = _skipping_and_in_full(load_scene(path), folder)
    assert _strip(fast["excused"]) == _strip(full["excused"])
    assert fast.get("validation") == full.get("validation")


def _turning_mesh_scene_text(seed: int, folder: Path) -> str:
    """`_turning_scene_text` with mesh parts: L-shaped links (two boxes, one
    mesh, not convex) and icospheres on the world and on two turning bodies,
    so pairs of meshes sweep past each other near the clearance."""
    import trimesh

    rng = np.random.default_rng(seed)
    el = trimesh.util.concatenate([trimesh.creation.box([30, 8, 8]),
                                   trimesh.creation.box([8, 30, 8]).apply_translation([11, 11, 0])])
    el.export(folder / "el.stl")
    trimesh.creation.icosphere(subdivisions=1, radius=9.0).export(folder / "ball.stl")
    text = (f'[scene]\nname = "turning-mesh-{seed}"\nunits = "mm"\nduration = 0.5\nsettle = 0.1\n\n'
            f'[effects]\ncontact = []\n\n[check]\nclearance = {rng.uniform(2.0, 5.0):.3f}\n')
    text += _turning_bodies(rng, 20, 60)
    for k in range(6):
        file = ["el.stl", "ball.stl"][int(rng.integers(2))]
        pos = ", ".join(f"{v:.1f}" for v in rng.uniform(-30, 30, 3) + [0, 0, 60 if k % 3 == 0 else 0])
        body = ["world", "b0", "b1"][k % 3]
        text += f'\n[[parts]]\nname = "p{k}"\nbody = "{body}"\nshape = "mesh"\nfile = "{file}"\npos = [{pos}]\n'
    # a body that never moves, its part sunk into a part on the world: a pair whose records never change
    text += ('\n[[bodies]]\nname = "still"\npos = [80.0, 0.0, 0.0]\n'
             '\n[[parts]]\nname = "base"\nshape = "box"\nsize = [20.0, 20.0, 5.0]\npos = [80.0, 0.0, 4.0]\n'
             '\n[[parts]]\nname = "foot"\nbody = "still"\nshape = "mesh"\nfile = "ball.stl"\npos = [0.0, 0.0, 16.0]\n')
    return text + _one_cable(rng)


@pytest.mark.parametrize("seed", seeds(2))
def test_active_mesh_part_pairs_bounded_from_their_distances_change_no_answer(seed: int, tmp_path):
    """Mesh part pairs whose boxes stay within the clearance (active) are bounded from their measured
    distances between full checks and measured again where the bound fails, and a pair within the
    clearance whose parts do not move keeps its records (`StepChecks._active_part_records`): on meshes
    turning past each other beside a ball sunk into a block, the events and pairs, part-part ones among
    them, are those of checking every step in full."""
    path = tmp_path / "turning.toml"
    path.write_text(_turning_mesh_scene_text(seed, tmp_path))
    scene = load_scene(path)
    fast, full = _skipping_and_in_full(scene, tmp_path)
    assert any(p["type"] == "part-part" for p in full["pairs"])
    assert any({p["a"], p["b"]} == {"base", "foot"} and p["min_distance"] < 0 for p in full["pairs"])
