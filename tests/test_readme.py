"""The README's scene example is a valid scene, and its quick-start commands name real files."""

from __future__ import annotations

import re
from pathlib import Path

from cablecheck.scene.load import load_scene

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def test_readme_scene_example_loads(tmp_path: Path):
    blocks = re.findall(r"```toml\n(.*?)```", README, flags=re.S)
    assert blocks, "README has a TOML scene example"
    path = tmp_path / "example.toml"
    path.write_text(blocks[0])
    scene = load_scene(path)
    assert scene.units == "mm" and scene.cables[0].name == "power"


def test_quick_start_scene_exists():
    for scene in re.findall(r"cablecheck run (scenes/\S+\.toml)", README):
        assert (ROOT / scene).exists(), scene
