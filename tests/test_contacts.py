"""MuJoCo's contacts mapped back to scene names (cablecheck.detection.contacts)."""

from __future__ import annotations

from pathlib import Path

from cablecheck.build.stages import build
from cablecheck.run.loop import Simulation
from cablecheck.scene.load import load_scene

SCENES = Path(__file__).resolve().parents[1] / "scenes"

PARTS = """
[scene]
name = "touching"
units = "mm"
duration = 0.01
settle = 0.0

[effects]
dynamics = false
contact = []

[[bodies]]
name = "slider"

[[parts]]
name = "frame/block"
shape = "box"
size = [20, 20, 20]
pos = [0, 0, 0]

[[parts]]
name = "slider/zone"
body = "slider"
shape = "box"
size = [20, 20, 20]
pos = [30, 0, 0]
keepout = true

[[cables]]
name = "lead"
radius = 3.0
start = { pos = [-60, 0, 22] }
end = { pos = [60, 0, 22] }
length = 120.0
segments = 12
"""


def _contacts(scene, every=1):
    built = build(scene, detect=True)
    sim = Simulation(built)
    sim.reset()
    sim.settle()
    return [sim.detector.detect_qpos(state.qpos) for state in list(sim.steps(contacts=False))[::every]]


def test_kinds_and_names(tmp_path):
    path = tmp_path / "touching.toml"
    path.write_text(PARTS)
    c = _contacts(load_scene(path))[0]
    got = {(k, a, b) for k, a, b in zip(c.kind, c.a, c.b)}
    # the lead lies 2 mm above both boxes (its radius 3 mm): cable-structure and keep-out
    assert ("cable-structure", "lead", "frame/block") in got
    assert ("keepout", "lead", "slider/zone") in got
    # the two boxes overlap by 10 mm, a part in a keep-out part: the detection model collides the
    # cables alone (validation compares cable pairs only), so no contact has no cable on it
    assert not any(c.elem_a[i] == -1 and c.elem_b[i] == -1 for i in range(len(c.dist)))
    cable = [i for i, a in enumerate(c.a) if a == "lead"]
    # 12 elements and the short held edge at each clamped end (cablecheck.build.cableplan.clamp_edges)
    assert all(0 <= c.elem_a[i] < 14 and c.elem_b[i] == -1 for i in cable)
    assert abs(c.dist[cable].min() + 0.001) < 1e-6       # 2 mm above the tops minus the 3 mm radius
    # the same kinds and names as codes into the reader's table
    assert c.codes.shape == (len(c.dist), 3)
    assert list(c.table.kinds[c.codes[:, 0]]) == list(c.kind)
    assert list(c.table.names[c.codes[:, 1]]) == list(c.a) and list(c.table.names[c.codes[:, 2]]) == list(c.b)


def test_cable_pairs_put_a_cable_first():
    crossing = _contacts(load_scene(SCENES / "crossing.toml"), every=50)
    assert any({(k, frozenset((a, b))) for k, a, b in zip(c.kind, c.a, c.b)}
               >= {("cable-cable", frozenset(("power", "signal")))} for c in crossing)
    coil = _contacts(load_scene(SCENES / "coil_self.toml"), every=50)
    selfs = [(a, b, ea, eb) for c in coil for k, a, b, ea, eb in zip(c.kind, c.a, c.b, c.elem_a, c.elem_b)
             if k == "self"]
    assert selfs and all(a == b == "lead" and ea >= 0 and eb >= 0 for a, b, ea, eb in selfs)
    for c in crossing + coil:
        assert [tuple(x) for x in zip(c.table.kinds[c.codes[:, 0]], c.table.names[c.codes[:, 1]],
                                      c.table.names[c.codes[:, 2]])] == list(zip(c.kind, c.a, c.b))


def test_raw_contacts_are_mujocos_arrays_and_vertices_read_as_elements():
    """What `raw` copies is MuJoCo's contact arrays as they are; `elem` gives
    -2 - vertex where MuJoCo names a flex vertex (a cable on a plane), and
    naming a batch of copies reads the same as naming each on its own."""
    import mujoco
    import numpy as np

    from cablecheck.detection.contacts import ContactReader

    scene = load_scene(SCENES / "coil_self.toml")        # a coil lying on a plane, touching itself
    built = build(scene)
    sim = Simulation(built)
    sim.reset()
    sim.settle()
    qposes = [s.qpos for k, s in zip(range(40), sim.steps(contacts=False)) if k % 4 == 0]
    raws = sim.detector.collide_many(qposes)
    m, d = built.detect, sim.detector.detect_data
    for qpos, raw in zip(qposes, raws):
        d.qpos[:] = qpos
        mujoco.mj_forward(m, d)
        n = d.ncon
        con = d.contact
        assert np.array_equal(raw.geom, con.geom[:n]) and np.array_equal(raw.flex, con.flex[:n])
        assert np.array_equal(raw.dist, con.dist[:n]) and np.array_equal(raw.pos, con.pos[:n])
        vertex = (con.elem[:n] < 0) & (con.vert[:n] >= 0)
        assert np.array_equal(raw.elem, np.where(vertex, -2 - con.vert[:n], con.elem[:n]))
    assert any(len(r.dist) for r in raws)
    reader = ContactReader(built)
    one = [reader.read_many([r], built.origin)[0] for r in raws]
    for a, b in zip(one, reader.read_many(raws, built.origin)):
        assert all(np.array_equal(getattr(a, f), getattr(b, f))
                   for f in ("kind", "a", "b", "elem_a", "elem_b", "dist", "pos", "codes"))
