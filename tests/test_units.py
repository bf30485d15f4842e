"""cablecheck.scene.units: sizes that make no sense in the declared units are refused or warned
about, naming the key and the likely unit; sizes that do make sense never are."""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers import examples
from hypothesis import given, settings, strategies as st

from cablecheck.cli.main import main
from cablecheck.scene.errors import SceneError
from cablecheck.scene.load import load_scene

SCENES = sorted((Path(__file__).resolve().parents[1] / "scenes").glob("*.toml"))

# A drawer harness in metres: radius, part sizes and positions, length.
CELL = dict(radius=0.004, half=(0.3, 0.2, 0.005), part_pos=(0.25, 0.0, -0.005), start=(-0.04, 0.0, 0.3),
            end=(0.285, 0.0, 0.3), length=0.65, travel=0.25)

TEXT = """
[scene]
name = "cell"
units = "{units}"
duration = 1.0

[[bodies]]
name = "drawer"

[[parts]]
name = "cabinet/floor"
shape = "box"
size = [{hx}, {hy}, {hz}]
pos = [{px}, {py}, {pz}]

[[cables]]
name = "power"
radius = {radius}
start = {{ pos = [{sx}, {sy}, {sz}] }}
end = {{ body = "drawer", pos = [{ex}, {ey}, {ez}] }}
length = {length}

[[motion]]
body = "drawer"
keys = [ {{ t = 0.0, pos = [0, 0, 0] }}, {{ t = 1.0, pos = [{travel}, 0, 0] }} ]
"""


def _write(tmp_path: Path, units: str, k: float, **changes) -> Path:
    """The cell with every length multiplied by ``k`` (1000: written in mm)."""
    c = {**CELL, **changes}
    path = tmp_path / f"cell-{units}-{k:g}.toml"
    hx, hy, hz = (v * k for v in c["half"])
    px, py, pz = (v * k for v in c["part_pos"])
    sx, sy, sz = (v * k for v in c["start"])
    ex, ey, ez = (v * k for v in c["end"])
    path.write_text(TEXT.format(units=units, hx=hx, hy=hy, hz=hz, px=px, py=py, pz=pz, sx=sx, sy=sy, sz=sz,
                                ex=ex, ey=ey, ez=ez, radius=c["radius"] * k, length=c["length"] * k,
                                travel=c["travel"] * k))
    return path


@pytest.mark.parametrize("units,k", [("m", 1.0), ("mm", 1000.0)])
def test_a_cell_in_its_own_units_passes_without_a_word(tmp_path, units, k):
    assert load_scene(_write(tmp_path, units, k)).warnings == ()


@pytest.mark.parametrize("units,k,likely", [("m", 1000.0, 'units = "mm"'), ("mm", 1.0, 'units = "m"')])
def test_a_cell_in_the_other_units_is_refused_naming_the_likely_unit(tmp_path, units, k, likely):
    with pytest.raises(SceneError) as err:
        load_scene(_write(tmp_path, units, k))
    assert err.value.key == "cables[0].radius" and likely in err.value.problem


def test_check_says_so_and_exits_2(tmp_path, capsys):
    assert main(["check", str(_write(tmp_path, "m", 1000.0))]) == 2
    err = capsys.readouterr().err
    assert "cables[0].radius" in err and "4 m is no cable radius" in err and 'did you mean units = "mm"' in err


@pytest.mark.parametrize("changes,key,warned", [
    (dict(radius=0.3), "cables[0].radius", "unusual cable radius"),          # a 300 mm radius: a duct, maybe
    (dict(half=(400.0, 0.2, 0.005)), "parts[0].size", "spans 800 m"),
    (dict(travel=300.0), "motion[0].keys", "spans 300 m"),
    (dict(length=5000.0, end=(1000.0, 0.0, 0.3)), "cables[0].length", "unusual cable length"),
])
def test_unusual_sizes_are_warned_about(tmp_path, changes, key, warned):
    (w,) = load_scene(_write(tmp_path, "m", 1.0, **changes)).warnings
    assert w.startswith(key) and warned in w


@pytest.mark.parametrize("changes,key", [
    (dict(radius=2.0), "cables[0].radius"),
    (dict(radius=5e-6), "cables[0].radius"),
    (dict(half=(6000.0, 0.2, 0.005)), "parts[0].size"),
    (dict(travel=20000.0), "motion[0].keys"),
])
def test_absurd_sizes_are_refused(tmp_path, changes, key):
    with pytest.raises(SceneError) as err:
        load_scene(_write(tmp_path, "m", 1.0, **changes))
    assert err.value.key == key


@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.stem)
def test_the_example_scenes_raise_no_unit_warning(path):
    assert load_scene(path).warnings == ()


@settings(max_examples=examples(40), deadline=None)
@given(radius=st.floats(1e-4, 0.05), scale=st.floats(0.2, 5.0), mm=st.booleans())
def test_plausible_cells_in_either_unit_never_warn(tmp_path_factory, radius, scale, mm):
    """Any cell of everyday sizes (radius 0.1-50 mm, the cell 0.2-5 times
    the drawer), written in m or mm: no warning."""
    c = {k: tuple(x * scale for x in v) if isinstance(v, tuple) else v * scale for k, v in CELL.items()}
    c["radius"] = radius
    k = 1000.0 if mm else 1.0
    path = _write(tmp_path_factory.mktemp("u"), "mm" if mm else "m", k, **c)
    assert load_scene(path).warnings == ()
