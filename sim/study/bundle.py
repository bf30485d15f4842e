"""The files a scene needs, packed as bytes to travel with a task, and unpacked again.

A study's variants run on workers that may share no disk with the machine
that started the study. `make_bundle` lists what the scene dicts name and
reads it: every string value of a scene dict that names an existing file
next to the scene (meshes, the mjcf model, trajectory CSVs, whatever key
names them), and what those files name in turn: an MJCF model's ``file``
attributes (``<include>``, ``<model>``, meshes, textures, height fields,
skins, under the ``<compiler>`` meshdir / texturedir / assetdir) and a glTF
file's external buffers and images. `materialise` writes the files into a
folder with the same relative layout, so every relative name still
resolves, and returns where the scene file would be.

Absolute file names in a scene dict are rewritten to relative ones in the
bundle; absolute names inside an MJCF file are not (such a model runs on a
worker only if the worker has the same file).

This module does not parse scenes (see `cablecheck.scene`) or run anything.
"""

from __future__ import annotations

import json
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Any

MJCF_SUFFIXES = (".xml", ".mjcf")
"""Files read as MJCF models for the files they name."""

_MJCF_DIR = {"mesh": "meshdir", "skin": "meshdir", "hfield": "meshdir", "texture": "texturedir"}
"""MJCF elements whose files are looked up under a <compiler> folder."""


@dataclass(frozen=True)
class Bundle:
    """A scene's files as bytes.

    Attributes:
      scene: the scene file's path relative to the bundle root (POSIX).
      files: (relative POSIX path, content) of every file the scenes name.
    """

    scene: str
    files: tuple[tuple[str, bytes], ...]

    @property
    def size(self) -> int:
        """Total bytes of the files."""
        return sum(len(b) for _, b in self.files)


def make_bundle(scene_path: Path, scenes: list[dict]) -> tuple[Bundle, list[dict]]:
    """Pack the files that any of `scenes` (scene dicts read from
    `scene_path`) name; return the bundle and the dicts with absolute file
    names made relative to the scene's folder (others unchanged)."""
    scene_path = Path(scene_path).absolute()
    folder = scene_path.parent
    named: set[Path] = set()
    for data in scenes:
        named |= set(_named_files(data, folder))
    files: set[Path] = set()
    for path in named:
        files |= _with_references(path)
    root = Path(os.path.commonpath([folder, *(f.parent for f in files)]))
    out = tuple(sorted((PurePosixPath(f.relative_to(root)).as_posix(), f.read_bytes()) for f in files))
    rewritten = [_relative_names(d, folder) for d in scenes]
    return Bundle(scene=PurePosixPath(scene_path.relative_to(root)).as_posix(), files=out), rewritten


def materialise(bundle: Bundle, folder: Path) -> Path:
    """Write the bundle's files under `folder`; return the scene file's path there."""
    folder = Path(folder)
    for rel, content in bundle.files:
        target = folder / rel
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(content)
    scene = folder / bundle.scene
    scene.parent.mkdir(parents=True, exist_ok=True)
    return scene


def _strings(value: Any):
    if isinstance(value, str):
        yield value
    elif isinstance(value, dict):
        for v in value.values():
            yield from _strings(v)
    elif isinstance(value, list):
        for v in value:
            yield from _strings(v)


def _named_files(data: dict, folder: Path):
    """Existing files named by the string values of a scene dict."""
    for text in _strings(data):
        if not text.strip() or len(text) > 4096:
            continue
        try:
            path = (folder / text).resolve()
            if path.is_file():
                yield path
        except (OSError, ValueError):   # not a possible file name (e.g. a NUL character)
            continue


def _relative_names(value: Any, folder: Path) -> Any:
    """A copy of a scene dict with absolute names of existing files made relative to `folder`."""
    if isinstance(value, dict):
        return {k: _relative_names(v, folder) for k, v in value.items()}
    if isinstance(value, list):
        return [_relative_names(v, folder) for v in value]
    if isinstance(value, str) and os.path.isabs(value) and "\0" not in value and Path(value).is_file():
        return Path(os.path.relpath(Path(value).resolve(), folder.resolve())).as_posix()
    return value


def _with_references(path: Path, seen: set[Path] | None = None) -> set[Path]:
    """`path` and every existing file it names, recursively."""
    seen = set() if seen is None else seen
    if path in seen:
        return seen
    seen.add(path)
    suffix = path.suffix.lower()
    if suffix in MJCF_SUFFIXES:
        refs = _mjcf_references(path)
    elif suffix == ".gltf":
        refs = _gltf_references(path)
    else:
        refs = []
    for ref in refs:
        if ref.is_file():
            _with_references(ref.resolve(), seen)
    return seen


def _mjcf_references(path: Path) -> list[Path]:
    """Files an MJCF model names. MuJoCo resolves them against the main
    model's folder: includes as they are, assets under the compiler's
    meshdir / texturedir (or assetdir). A file that is not XML names nothing."""
    try:
        root = ET.parse(path).getroot()
    except (ET.ParseError, OSError):
        return []
    base = path.parent
    trees = [root]
    refs: list[Path] = []
    k = 0
    while k < len(trees):   # included files are part of the model: their compiler counts too
        for inc in trees[k].iter("include"):
            f = inc.get("file")
            if f:
                p = base / f
                refs.append(p)
                try:
                    trees.append(ET.parse(p).getroot())
                except (ET.ParseError, OSError):
                    pass
        k += 1
    dirs: dict[str, str] = {}
    for tree in trees:
        for comp in tree.iter("compiler"):
            for key in ("meshdir", "texturedir", "assetdir"):
                if comp.get(key) is not None:
                    dirs[key] = comp.get(key)
    for tree in trees:
        for el in tree.iter():
            if el.tag == "include":
                continue
            sub = dirs.get(_MJCF_DIR.get(el.tag, ""), dirs.get("assetdir", "")) \
                if el.tag in _MJCF_DIR else ""
            for attr, value in el.attrib.items():
                if attr.startswith("file") and value:
                    refs.append(base / sub / value)
    return refs


def _gltf_references(path: Path) -> list[Path]:
    """External buffers and images of a glTF file (data: URIs carry their own bytes)."""
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return []
    uris = [item.get("uri") for key in ("buffers", "images") for item in doc.get(key, [])
            if isinstance(item, dict)]
    return [path.parent / u for u in uris if isinstance(u, str) and not u.startswith("data:")]
