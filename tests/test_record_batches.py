"""Many parts drawn as one entity (`cablecheck.record.batches`): which parts
are batched, and each instance where its part is: read back from a recording
and compared with the part's pose by another way (the pose's own axes, and
the same scene drawn one entity per part, MuJoCo's kinematics placing it)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import rerun as rr
from hypothesis import given, settings, strategies as st
from rerun.chunk import RrdReader

from cablecheck.build.built import PartModel
from cablecheck.cli.main import main
from cablecheck.record import batches as batching
from cablecheck.record.batches import BATCH_PARTS, batches, placement, shapes
from tests.helpers import examples, recorded_entities, recorded_rows as _rows

SHAPES = ("box", "sphere", "ellipsoid", "capsule", "cylinder")


def _part(name: str, shape: str, size=(0.01, 0.02, 0.03), keepout=False) -> PartModel:
    return PartModel(name, 0, "world", shape, np.array(size, float), None, None, keepout)


def _matrix(q) -> np.ndarray:
    """The rotation matrix of a quaternion (x, y, z, w), from its formula."""
    x, y, z, w = np.asarray(q, float) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def test_parts_are_batched_by_kind_assembly_level_and_motion():
    n = BATCH_PARTS
    parts = ([_part(f"frame/b{k}", "box") for k in range(n)]
             + [_part(f"frame/s{k}", "sphere" if k % 2 else "ellipsoid") for k in range(n)]
             + [_part(f"frame/c{k}", "capsule") for k in range(n - 1)]          # one short: each its own
             + [_part(f"other/b{k}", "box") for k in range(n)]
             + [_part(f"frame/m{k}", "mesh") for k in range(n)]
             + [_part(f"frame/k{k}", "box", keepout=True) for k in range(n)]
             + [_part(f"p{k}", "cylinder") for k in range(n)])
    moving = np.zeros(len(parts), bool)
    moving[n // 2:n] = True                                                     # half the frame's boxes move
    found = {b.path: b for b in batches(parts, moving, "world/parts")}
    assert set(found) == {"world/parts/other/_boxes", "world/parts/frame/_ellipsoids", "world/parts/_cylinders"}
    assert found["world/parts/frame/_ellipsoids"].archetype is rr.Ellipsoids3D
    assert list(found["world/parts/other/_boxes"].members) == list(range(3 * n - 1, 4 * n - 1))
    moving[:n] = True                                                           # now all move: one batch
    again = {b.path: b for b in batches(parts, moving, "world/parts")}
    assert again["world/parts/frame/_moving_boxes"].moving and not again["world/parts/other/_boxes"].moving
    # many small assemblies (a bracket of a base, an arm and a pin each): their kinds pooled at the root
    brackets = [_part(f"bracket{k}/{p}", shape) for k in range(n) for p, shape in
                (("base", "box"), ("arm", "box"), ("pin", "cylinder"))]
    pooled = {b.path: b for b in batches(brackets, np.zeros(len(brackets), bool), "world/parts")}
    assert set(pooled) == {"world/parts/_boxes", "world/parts/_cylinders"}
    assert len(pooled["world/parts/_boxes"].members) == 2 * n
    # on a frame, under the level they share; beside the frame's own boxes, in one batch with them
    framed = [_part(f"frame/{p.name}", p.shape) for p in brackets] + [_part(f"frame/b{k}", "box") for k in range(n)]
    found = {b.path: b for b in batches(framed, np.zeros(len(framed), bool), "world/parts")}
    assert set(found) == {"world/parts/frame/_boxes", "world/parts/frame/_cylinders"}
    assert len(found["world/parts/frame/_boxes"].members) == 3 * n


@settings(max_examples=examples(60), deadline=None)
@given(st.lists(st.tuples(st.sampled_from(["", "a", "a/b", "c"]), st.sampled_from([*SHAPES, "mesh", "plane"]),
                          st.booleans(), st.booleans()), min_size=20, max_size=120),
       st.integers(2, 6))
def test_every_batch_is_of_one_kind_and_motion_and_only_small_pools_are_left(drawn, threshold):
    """Drawn parts (assembly level, shape, moving, keep-out), any threshold: each part in one batch at
    most, paths distinct, a batch of one archetype and one motion, BATCH_PARTS or more; a part left out
    is a mesh, a plane, a keep-out, or one of fewer than the threshold of its kind and motion so left."""
    import cablecheck.record.batches as module
    old, module.BATCH_PARTS = module.BATCH_PARTS, threshold
    try:
        parts = [_part(f"{level}/p{k}" if level else f"p{k}", shape, keepout=keep)
                 for k, (level, shape, _, keep) in enumerate(drawn)]
        moving = np.array([go for _, _, go, _ in drawn], bool)
        found = batches(parts, moving, "world/parts")
    finally:
        module.BATCH_PARTS = old
    members = np.concatenate([b.members for b in found]) if found else np.zeros(0, int)
    assert len(set(members.tolist())) == len(members)
    assert len({b.path for b in found}) == len(found)
    kind = {"box": "boxes", "sphere": "ellipsoids", "ellipsoid": "ellipsoids", "capsule": "capsules",
            "cylinder": "cylinders"}
    for b in found:
        assert len(b.members) >= threshold
        assert {kind[parts[k].shape] for k in b.members} == {b.path.rsplit("_", 1)[1]}
        assert set(moving[b.members].tolist()) == {b.moving} and ("_moving_" in b.path) == b.moving
        assert not any(parts[k].keepout for k in b.members)
        level = b.path[len("world/parts/"):].rsplit("/", 1)[0] if b.path.count("/") > 2 else ""
        assert all(parts[k].name.startswith(level + "/") for k in b.members) if level else True
    left: dict = {}
    for k, part in enumerate(parts):
        if k not in members and part.shape in kind and not part.keepout:
            left.setdefault((kind[part.shape], bool(moving[k])), []).append(k)
    assert all(len(v) < threshold for v in left.values())


def _sample(shape: str, size: np.ndarray) -> np.ndarray:
    """Points of a part's shape in its own frame (its MuJoCo size), spanning it along every axis."""
    signs = np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1], indexing="ij")).reshape(3, -1).T
    if shape in ("box", "ellipsoid"):
        return signs * size[:3]
    if shape == "sphere":
        return signs * size[0]
    return signs * np.array([size[0], size[0], size[1]])          # capsule, cylinder: the axis's ends at +-size[1]


def _recorded(shape: str, row: dict, i: int) -> tuple[np.ndarray, np.ndarray]:
    """Instance i of a batch's static row: its centre and rotation (a capsule's from its first end), and
    its size as MuJoCo gives it."""
    archetype = {"box": "Boxes3D", "sphere": "Ellipsoids3D", "ellipsoid": "Ellipsoids3D",
                 "capsule": "Capsules3D", "cylinder": "Cylinders3D"}[shape]
    rot = _matrix(row[f"{archetype}:quaternions"][i])
    if shape == "capsule":
        half = row["Capsules3D:lengths"][i] / 2
        centre = np.array(row["Capsules3D:translations"][i]) + rot[:, 2] * half
        return centre, rot, np.array([row["Capsules3D:radii"][i], half, 0.0])
    if shape == "cylinder":
        return (np.array(row["Cylinders3D:centers"][i]), rot,
                np.array([row["Cylinders3D:radii"][i], row["Cylinders3D:lengths"][i] / 2, 0.0]))
    return np.array(row[f"{archetype}:centers"][i]), rot, np.array(row[f"{archetype}:half_sizes"][i])


@settings(max_examples=examples(40), deadline=None)
@given(shape=st.sampled_from(SHAPES), seed=st.integers(0, 2**31), far=st.sampled_from([0.0, 1e3]),
       unit=st.sampled_from([1.0, 1e-3]))
def test_each_instance_lies_where_its_part_is(tmp_path_factory, shape, seed, far, unit):
    """Every point of every part, placed by the recorded instance, is where the part's own pose puts it
    (metres or millimetres, near the origin or a kilometre out)."""
    rng = np.random.default_rng(seed)
    n = BATCH_PARTS
    parts = [_part(f"frame/p{k}", shape, rng.uniform(0.002, 0.05, 3)) for k in range(n)]
    q = rng.normal(size=(n, 4))
    poses = np.tile(np.eye(4), (n, 1, 1))
    poses[:, :3, :3] = [_matrix(v) for v in q]
    poses[:, :3, 3] = far + rng.uniform(-1, 1, (n, 3))
    (batch,) = batches(parts, np.zeros(n, bool), "world/parts")
    record = tmp_path_factory.mktemp("b") / "b.rrd"
    rec = rr.RecordingStream("batches")
    rec.save(record)
    rec.send_columns(batch.path, indexes=[], columns=shapes(batch.archetype, parts, unit)
                     + placement(batch.archetype, parts, poses[None], unit))
    rec.flush()
    rec.disconnect()
    (row,) = _rows(record, "/" + batch.path)
    assert row[f"{batch.archetype.__name__}:labels"] == [p.name for p in parts]
    for i, part in enumerate(parts):
        centre, rot, size = _recorded(shape, row, i)
        local = _sample(shape, part.size)
        want = local @ poses[i, :3, :3].T + poses[i, :3, 3]
        got = (_sample(shape, size * unit) @ rot.T + centre * unit)
        assert np.allclose(got, want, rtol=0, atol=1e-6 * max(1.0, far) + 1e-6 * np.abs(local).max())


TOML = """
[scene]
name = "many-clips"
units = "mm"
duration = 0.2
settle = 0.0

[effects]
contact = []

[check]
clearance = 2.0

[[bodies]]
name = "carriage"
pos = [0, 0, 0]

[[cables]]
name = "lead"
radius = 3.0
start = {{ pos = [-200, 0, 100] }}
end = {{ pos = [200, 0, 100] }}
length = 401.0
segments = 20

[[motion]]
body = "carriage"
keys = [ {{ t = 0.0, pos = [0, 0, 0] }}, {{ t = 0.2, pos = [30, 10, 0], euler = [0, 0, 40] }} ]
{parts}
"""


BLOCKS = [(-300.0 + 15 * k, -80.0, 20.0) for k in range(40)] + [(-150.0 + 60 * k, 0.0, 100.0) for k in range(6)]
"""The frame's blocks (mm): 40 clear of the cable, 6 it runs through."""


def _scene(tmp_path: Path) -> Path:
    """A carriage carrying 40 parts of every kind, each turned its own way, and the frame's blocks."""
    rng = np.random.default_rng(7)
    parts = []
    for k in range(40):
        shape = SHAPES[k % len(SHAPES)]
        size = {"box": 3, "ellipsoid": 3, "sphere": 1}.get(shape, 2)
        parts.append(f'[[parts]]\nname = "carriage/clip{k:02d}"\nbody = "carriage"\nshape = "{shape}"\n'
                     f"size = {json.dumps(np.round(rng.uniform(2, 6, size), 2).tolist())}\n"
                     f"pos = {json.dumps(np.round(rng.uniform(-150, 150, 3) * [1, 1, 0.2], 1).tolist())}\n"
                     f"euler = {json.dumps(np.round(rng.uniform(-90, 90, 3), 1).tolist())}\n")
    for k, pos in enumerate(BLOCKS):
        parts.append(f'[[parts]]\nname = "frame/block{k:02d}"\nshape = "box"\nsize = [4, 4, 4]\npos = {list(pos)}\n')
    path = tmp_path / "many.toml"
    path.write_text(TOML.format(parts="\n".join(parts)))
    return path


def _lone_size(shape: str, row: dict) -> np.ndarray:
    """A part's size (MuJoCo's) from its own entity's static shape row."""
    if shape == "box":
        return np.array(row["Boxes3D:half_sizes"][0])
    if shape in ("sphere", "ellipsoid"):
        return np.array(row["Ellipsoids3D:half_sizes"][0])
    if shape == "capsule":
        return np.array([row["Capsules3D:radii"][0], row["Capsules3D:lengths"][0] / 2, 0.0])
    return np.array([row["Cylinders3D:radii"][0], row["Cylinders3D:lengths"][0] / 2, 0.0])


def _batch_path(root: str, level: str, shape: str, moving: bool = False) -> str:
    return f"/{root}/{level}/_" + ("moving_" if moving else "") + {"box": "boxes", "sphere": "ellipsoids", "ellipsoid": "ellipsoids",
                                   "capsule": "capsules", "cylinder": "cylinders"}[shape]


def test_a_scene_of_many_parts_draws_each_where_it_is_drawn_alone(tmp_path: Path, monkeypatch):
    """The same run recorded twice: batched (8 parts to a batch), and one entity per part (the threshold out of reach,
    each part placed by its entity's transform, MuJoCo's kinematics moving it). At every fourth frame
    each moving instance's points are its lone entity's; the frame's blocks are where the scene file
    puts them."""
    scene = _scene(tmp_path)
    batched, alone = tmp_path / "batched.rrd", tmp_path / "alone.rrd"
    monkeypatch.setattr(batching, "BATCH_PARTS", 8)                     # the carriage's 8 parts of each kind
    assert main(["run", str(scene), "--record", str(batched), "--quiet", "--fail-on", "never"]) == 0
    monkeypatch.setattr(batching, "BATCH_PARTS", 10**9)
    assert main(["run", str(scene), "--record", str(alone), "--quiet", "--fail-on", "never"]) == 0
    assert json.loads(batched.with_suffix(".json").read_text())["complete"]
    entities = {c.entity_path for c in RrdReader(batched).stream()}
    assert not any(e.startswith(("/world/parts/carriage/clip", "/world/parts/frame/block")) for e in entities)
    (blocks,) = _rows(batched, "/world/parts/frame/_boxes")[:1]
    assert blocks["Boxes3D:labels"] == [f"frame/block{k:02d}" for k in range(len(BLOCKS))]
    assert np.allclose(blocks["Boxes3D:centers"], BLOCKS, atol=1e-9)
    checked = 0
    lone_rows = recorded_entities(alone, "/world/parts/carriage/")
    for shape in ("box", "ellipsoid", "capsule", "cylinder"):
        rows = _rows(batched, _batch_path("world/parts", "carriage", shape, moving=True))
        static = next(r for r in rows if r["t"] is None)
        names = static[next(k for k in static if k.endswith(":labels"))]
        timed = [r for r in rows if r["t"] is not None and any(k.endswith(":quaternions") and v for k, v in r.items())]
        assert len(timed) > 4
        for row in timed[::4]:
            merged = {**static, **{k: v for k, v in row.items() if v is not None}}
            for i, name in enumerate(names):
                kind = SHAPES[int(name[-2:]) % len(SHAPES)]
                centre, rot, size = _recorded(kind, merged, i)
                lone = lone_rows["/world/parts/" + name]
                pose = next(r for r in lone if r["t"] is not None and r["t"] == pytest.approx(row["t"], abs=1e-12)
                            and r.get("Transform3D:translation"))
                mat = np.array(pose["Transform3D:mat3x3"]).reshape(3, 3).T      # rerun: column by column
                local = _sample(kind, _lone_size(kind, next(r for r in lone if r["t"] is None)))
                want = local @ mat.T + pose["Transform3D:translation"]
                assert np.allclose(_sample(kind, size) @ rot.T + centre, want, atol=1e-3), (name, row["t"])
                checked += 1
    assert checked > 40


def test_the_wear_map_batches_the_touched_parts_where_they_stand(tmp_path: Path, monkeypatch):
    """With the threshold at 3, the blocks the cable runs through are one entity of the wear map, each at
    the scene file's place; the blocks clear of it are not drawn there."""
    monkeypatch.setattr(batching, "BATCH_PARTS", 3)
    record = tmp_path / "w.rrd"
    assert main(["run", str(_scene(tmp_path)), "--record", str(record), "--quiet", "--fail-on", "never"]) == 0
    (row,) = _rows(record, "/wear_map/parts/frame/_boxes")
    names = row["Boxes3D:labels"]
    assert len(names) >= 3 and all(int(n[-2:]) >= 40 for n in names)          # only blocks the cable runs through
    assert np.allclose(row["Boxes3D:centers"], [BLOCKS[int(n[-2:])] for n in names], atol=1e-9)
    assert row["Boxes3D:colors"] and row["Boxes3D:half_sizes"] == [[4.0, 4.0, 4.0]] * len(names)
