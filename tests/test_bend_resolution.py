"""A bend tighter than the rod's elements can resolve is read larger than it
is, and the run says so (cablecheck.run.runner, BEND_RESOLUTION): a hairpin
between two clamps, coarse against fine."""

import json

import pytest
from cablecheck.build.cablephysics import BEND_RESOLUTION
from cablecheck.run.runner import RunOptions, run_scene
from cablecheck.scene.load import load_scene

pytestmark = pytest.mark.filterwarnings("error")

HAIRPIN = """
[scene]
name = "hairpin"
units = "m"
duration = 0.1
settle = 0.3

[check]
clearance = 0.001

[[cables]]
name = "c"
radius = 0.002
start = {{ pos = [0.0, 0.0, 0.5], tangent = [1, 0, 0] }}
end = {{ pos = [0.0, 0.03, 0.5], tangent = [-1, 0, 0] }}
length = 0.12
segments = {segments}
young = 5e6
density = 1200
min_bend_radius = 0.02
"""


def _run(tmp_path, segments):
    path = tmp_path / f"hairpin{segments}.toml"
    path.write_text(HAIRPIN.format(segments=segments))
    report = tmp_path / f"r{segments}.json"
    run_scene(load_scene(path), RunOptions(report=report, record=None))
    r = json.loads(report.read_text())
    return r["cables"][0]["min_bend_radius"], [w for w in r["physics_warnings"] if "cannot resolve" in w]


def test_a_bend_the_elements_cannot_resolve_is_read_larger_and_warned(tmp_path):
    coarse, warned = _run(tmp_path, 6)        # elements of 20 mm about a bend of about 16 mm
    fine, quiet = _run(tmp_path, 60)          # 2 mm elements: the bend spans eight of them
    # the fine rod's bend is the converged one: twice as many segments read it within 1 %
    finer, _ = _run(tmp_path, 120)
    assert fine == pytest.approx(finer, rel=0.01)
    assert fine == pytest.approx(0.01575, rel=0.01)
    assert coarse > 1.1 * fine
    assert len(warned) == 1 and "'c'" in warned[0] and "segments = " in warned[0]
    need = int(warned[0].split("segments = ")[1].split()[0])
    assert need >= BEND_RESOLUTION * 0.12 / coarse
    assert quiet == []


def test_the_warning_gives_lengths_in_the_scenes_units(tmp_path):
    """The same hairpin written in millimetres: the same warning, its
    lengths in mm (a millimetre scene was told of 0.0334 m bends in 0.0249 m
    elements)."""
    mm = (HAIRPIN.replace('units = "m"', 'units = "mm"').replace("0.002", "2").replace("0.03,", "30,")
          .replace("0.001", "1").replace("0.12", "120").replace("0.02\n", "20\n").replace("0.5]", "500]"))
    path = tmp_path / "hairpin_mm.toml"
    path.write_text(mm.format(segments=6))
    report = tmp_path / "mm.json"
    run_scene(load_scene(path), RunOptions(report=report, record=None))
    r = json.loads(report.read_text())
    (warned,) = [w for w in r["physics_warnings"] if "cannot resolve" in w]
    coarse_m, metres = _run(tmp_path, 6)
    radius = float(warned.split("least bend radius, ")[1].split(" mm")[0])
    assert radius == pytest.approx(1000 * coarse_m, rel=1e-3)
    assert "mm each)" in warned and "(its limit is 20 mm)" in warned and " m " not in warned
