"""Scenes shared by the model-building tests (test_build, test_cableplan,
test_obstacles, test_modelread, test_contactbits): a cable to a slider past
a post, a cable along a floor, and an MJCF arm as it comes, with or without
its visual geoms; and a run of a scene's steps. Not a test file."""

from __future__ import annotations

from pathlib import Path

from cablecheck.build.stages import build
from cablecheck.run.loop import Simulation
from cablecheck.scene.load import parse_scene


def slider_scene(tmp_path: Path, **over) -> dict:
    data = {
        "scene": {"name": "t", "units": "m", "duration": 0.2, "settle": 0.3},
        "effects": {"contact": ["cable-structure"]},
        "bodies": [{"name": "slider"}],
        # off the cable's midpoint: a droop centred on a box edge-on is a tie between faces
        "parts": [{"name": "frame/post", "shape": "box", "size": [0.02, 0.02, 0.2], "pos": [0.36, 0.0, 0.2]}],
        "cables": [{"name": "c", "radius": 0.004, "start": {"pos": [0, 0, 0.5]},
                    "end": {"body": "slider", "pos": [0.6, 0, 0.5]}, "length": 0.7, "segments": 20}],
        "motion": [{"body": "slider", "keys": [{"t": 0, "pos": [0, 0, 0]}, {"t": 0.2, "pos": [0.02, 0, 0]}]}],
    }
    data.update(over)
    return data


def run_steps(data: dict, tmp_path: Path, contacts=True):
    sim = Simulation(build(parse_scene(data, tmp_path / "s.toml")))
    sim.reset()
    sim.settle()
    return sim, list(sim.steps(contacts=contacts))


def floor_scene(shape: str, pressed: float = 0.0) -> dict:
    """A cable of radius 5 mm laid along a floor (top at z = 0): ends and via
    on it, 20 % longer than its route; the via `pressed` into it."""
    r = 5.0
    floor = ({"name": "floor", "shape": "box", "size": [400, 300, 10], "pos": [0, 0, -10]} if shape == "box"
             else {"name": "floor", "shape": "plane", "pos": [0, 0, 0]})
    return {"scene": {"name": "f", "units": "mm", "duration": 0.3, "settle": 1.0},
            "effects": {"contact": ["cable-structure"]}, "parts": [floor],
            "cables": [{"name": "c", "radius": r, "start": {"pos": [-300, 0, r]}, "end": {"pos": [300, 0, r]},
                        "via": [[0, 0, r - pressed]], "length": 720.0}]}


_ARM = """<mujoco>
  <asset><mesh name="lug" vertex="0 0 0  0.02 0 0  0 0.02 0  0 0 0.02"/></asset>
  <worldbody>
    <body name="stand" pos="0 0 0.2">
      {visual_stand}
      <geom name="column" type="box" size="0.03 0.03 0.1" contype="1" conaffinity="1"/>
      <body name="link" pos="0 0 0.15">
        <joint name="j" type="hinge" axis="0 0 1"/>
        {visual_link}
        <geom type="capsule" fromto="0 0 0 0.25 0 0" size="0.02" contype="2" conaffinity="0"/>
        <geom type="mesh" mesh="lug" pos="0.25 0 0" contype="2" conaffinity="0"/>
        <geom type="sphere" size="0.015" pos="0.1 0 0.05" contype="0" conaffinity="2"/>
      </body>
    </body>
    <body name="post" pos="0.45 0 0.2">
      <joint name="lift" type="slide" axis="0 0 1"/>
      <geom name="rod" type="cylinder" size="0.02 0.15" contype="2" conaffinity="1"/>
    </body>
  </worldbody>
  {contact}
</mujoco>"""


_VISUALS = dict(
    visual_stand='<geom type="box" size="0.05 0.05 0.12" contype="0" conaffinity="0" group="2"/>',
    visual_link='<geom type="mesh" mesh="lug" contype="0" conaffinity="0" group="2"/>'
                '<geom name="shell" type="capsule" fromto="0 0 0 0.25 0 0" size="0.03" '
                'contype="0" conaffinity="0" group="2"/>')


def arm_scene(tmp_path: Path, visuals: bool, contact: str = "", effects=("cable-structure",)) -> dict:
    fill = _VISUALS if visuals else dict.fromkeys(_VISUALS, "")
    (tmp_path / "arm.xml").write_text(_ARM.format(contact=contact, **fill))
    return {
        "scene": {"name": "t", "units": "m", "duration": 0.05, "settle": 0.05, "mjcf": "arm.xml"},
        "effects": {"contact": list(effects)},
        "parts": [{"name": "cell/table", "shape": "box", "size": [0.5, 0.5, 0.01], "pos": [0.2, 0, 0.09]}],
        "cables": [{"name": "hose", "radius": 0.005, "start": {"body": "stand", "pos": [-0.05, 0, 0.0]},
                    "end": {"body": "link", "pos": [0.2, 0, 0.03]}, "length": 0.5, "segments": 16}],
    }


def arm_built(tmp_path: Path, **kw):
    return build(parse_scene(arm_scene(tmp_path, **kw), tmp_path / "s.toml"))
