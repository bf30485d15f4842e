"""A design study: one scene, some of its values varied, read from a study file (TOML).

`load_study` reads and checks the study file; `variants` expands its
``[[vary]]`` entries into the scenes to run, as a full grid (the default:
every combination, the first key varying slowest) or ``mode = "zip"`` (the
i-th value of every key together); `check_variants` parses every variant's
scene with `cablecheck.scene.parse_scene` and checks its cables as their plan would (`cablecheck.build.stages.check_cables`)
before anything runs, so a bad key or value is reported once, up front,
naming the study file, the ``[[vary]]`` key, the value and the scene's own
complaint.

Study file::

    [study]
    name = "power-length"          # output folder name
    scene = "drawer.toml"          # relative to the study file
    mode = "grid"                  # optional: "grid" (default) or "zip"
    [[vary]]
    key = "cables.power.length"    # dotted path into the scene's TOML
    values = [620, 640, 660]       # or: from = 600, to = 700, count = 11

A key is a dotted path into the scene's TOML tables. An array of tables is
entered by the name of one of its entries (its ``name``, or for ``[[motion]]``
its ``body``, ``joint`` or ``file``; a name may itself contain dots) or by
a 0-based index: ``cables.power.clips.0.pos``, ``parts.cabinet/rail_left.pos``,
``motion.drawer.time_scale``, ``motion.0.time_scale``. The last step may name
a key the scene leaves out (its default is then replaced); missing tables on
the way are created. Whether the scene accepts the key and the value is the
scene parser's judgement, asked for every variant.

This module runs nothing and imports no Dask (see `cablecheck.study.execute`); it writes
no outputs (see `cablecheck.study.plot`).
"""

from __future__ import annotations

import copy
import difflib
import itertools
import math
import os
import re
import tomllib
from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from typing import Any

from cablecheck.scene.errors import SceneError
from cablecheck.scene.format import LARGEST
from cablecheck.scene.load import load_scene, parse_scene
from cablecheck.scene.records import Scene
from cablecheck.study.goal import Goal, GoalError, Requirement, check_names, parse_goal, parse_requirements

_STUDY_KEYS = ("study", "vary", "require", "goal", "search")
_HEAD_KEYS = ("name", "scene", "mode")
_SEARCH_KEYS = ("method", "budget")
_VARY_KEYS = ("key", "values", "from", "to", "count")
NAME_FIELDS = ("name", "body", "joint", "file")
"""Fields that name an entry of an array of tables, tried in this order."""

MAX_VARIANTS = 100_000
"""A study expanding to more variants than this is refused as a likely mistake."""


class StudyError(SceneError):
    """A study file that cannot be used: the study file, the key path in it
    (``vary[1].values``) and the problem. A `SceneError`, so the command line
    reports it as bad input (exit status 2)."""


class Mode(Enum):
    """How several ``[[vary]]`` entries combine."""

    GRID = "grid"   # every combination, the first key varying slowest
    ZIP = "zip"     # the i-th value of every key together


class Method(Enum):
    """How a study picks its variants (``[search] method``)."""

    GRID = "grid"           # the [[vary]] values, as `Mode` combines them
    OPTIMISE = "optimise"   # rounds of runs in the keys' ranges, zooming in (`cablecheck.study.search`)


@dataclass(frozen=True)
class SearchPlan:
    """``[search]``: the method and, for optimise, the most runs."""

    method: Method = Method.GRID
    budget: int | None = None


@dataclass(frozen=True)
class Vary:
    """One varied key.

    Attributes:
      key: the dotted path as written.
      path: the path resolved against the scene, in the scene parser's key
        notation (``cables[0].length``), used to attribute the parser's
        complaints to this key.
      steps: the path's steps into the scene's TOML dict: str keys of
        tables, int indices of arrays.
      values: the values, as TOML gives them (numbers, strings, arrays);
        for a search, its range's two ends.
      bounds: a single number's range (from, to) when the entry gives one,
        else None: what a search varies it in.
    """

    key: str
    path: str
    steps: tuple[str | int, ...]
    values: tuple[Any, ...]
    bounds: tuple[float, float] | None = None


@dataclass(frozen=True)
class Study:
    """A checked study file.

    Attributes:
      path: the study file as given.
      name: output folder name.
      scene_path: the scene file (resolved against the study file's folder).
      scene_data: the scene file as `tomllib` reads it (not modified).
      mode: how the varied keys combine.
      vary: the varied keys, in file order.
      requirements, goal: what must hold and what to make best
        (`cablecheck.study.goal`).
      search: how the variants are picked.
    """

    path: Path
    name: str
    scene_path: Path
    scene_data: dict
    mode: Mode
    vary: tuple[Vary, ...]
    requirements: tuple[Requirement, ...] = ()
    goal: Goal | None = None
    search: SearchPlan = SearchPlan()


@dataclass(frozen=True)
class Variant:
    """One scene of a study.

    Attributes:
      id: zero-padded number in expansion order ("000", "001", ...), also
        its output folder name.
      values: one value per `Study.vary` entry, in that order.
      data: the scene dict with the values set (a deep copy).
    """

    id: str
    values: tuple[Any, ...]
    data: dict


def load_study(path: str | Path) -> Study:
    """Read and check a study file and read its scene file's TOML.

    Raises StudyError for a problem of the study file (a key that leads
    nowhere in the scene included) and SceneError for an unreadable scene."""
    path = Path(path)
    data = _read_toml(path, StudyError)
    _table(data, path, "(top level)", _STUDY_KEYS, ("study", "vary"))
    head = _table(data["study"], path, "study", _HEAD_KEYS, ("name", "scene"))
    name = head["name"]
    if not isinstance(name, str) or not name.strip():
        raise StudyError(path, "study.name", f"expected a non-empty string, got {name!r}")
    if "/" in name or "\\" in name or name in (".", ".."):
        raise StudyError(path, "study.name", f"is used as a folder name; it may not contain "
                                             f"'/' or '\\' or be '.' or '..', got {name!r}")
    scene = head["scene"]
    if not isinstance(scene, str) or not scene.strip():
        raise StudyError(path, "study.scene", f"expected a file name, got {scene!r}")
    scene_path = Path(os.path.normpath(path.parent / scene))   # "studies/../drawer.toml" -> "drawer.toml"
    if not scene_path.is_file():
        raise StudyError(path, "study.scene", f"file not found: {scene_path}")
    mode_text = head.get("mode", "grid")
    try:
        mode = Mode(mode_text if isinstance(mode_text, str) else None)
    except ValueError:
        raise StudyError(path, "study.mode", f"must be 'grid' or 'zip', got {mode_text!r}") from None
    scene_data = _read_toml(scene_path, SceneError)
    entries = data["vary"]
    if not isinstance(entries, list) or not entries or not all(isinstance(e, dict) for e in entries):
        raise StudyError(path, "vary", "expected one or more [[vary]] tables")
    search = _search(data.get("search"), path)
    vary = tuple(_vary(e, path, f"vary[{i}]", scene_data, scene_path, search.method)
                 for i, e in enumerate(entries))
    try:
        requirements = parse_requirements(data.get("require"))
        goal = parse_goal(data.get("goal"))
    except GoalError as e:
        raise StudyError(path, e.args[0], e.args[1]) from None
    seen: dict[tuple, int] = {}
    for i, v in enumerate(vary):
        if v.steps in seen:
            raise StudyError(path, f"vary[{i}].key", f"{v.key!r} is the same scene key as "
                                                     f"vary[{seen[v.steps]}].key")
        seen[v.steps] = i
    if mode is Mode.ZIP:
        for i, v in enumerate(vary[1:], 1):
            if len(v.values) != len(vary[0].values):
                raise StudyError(path, f"vary[{i}]", f"mode 'zip' needs as many values for every "
                                 f"key: {len(v.values)} here, {len(vary[0].values)} in vary[0]")
    count = (len(vary[0].values) if mode is Mode.ZIP
             else math.prod(len(v.values) for v in vary))
    if count > MAX_VARIANTS and search.method is Method.GRID:
        raise StudyError(path, "vary", f"{count} variants, more than {MAX_VARIANTS}")
    return Study(path=path, name=name, scene_path=scene_path, scene_data=scene_data,
                 mode=mode, vary=vary, requirements=requirements, goal=goal, search=search)


def variant_at(study: Study, id: str, values: tuple[Any, ...]) -> Variant:
    """The scene with one value per varied key set (a search's point)."""
    data = copy.deepcopy(study.scene_data)
    for v, value in zip(study.vary, values):
        _set(data, v.steps, copy.deepcopy(value))
    return Variant(id=id, values=tuple(values), data=data)


def variants(study: Study) -> tuple[Variant, ...]:
    """The study's scenes, in expansion order (grid: the first key slowest)."""
    columns = [v.values for v in study.vary]
    combos = (list(zip(*columns)) if study.mode is Mode.ZIP
              else list(itertools.product(*columns)))
    width = max(3, len(str(len(combos) - 1)))
    return tuple(variant_at(study, f"{k:0{width}d}", values) for k, values in enumerate(combos))


def check_variants(study: Study, variants: tuple[Variant, ...]) -> tuple[Scene, ...]:
    """Check every variant's scene (`check_variant`); raise StudyError naming
    the study file, the varied key, the value and the scene's problem for
    the first bad one.

    The unvaried scene is loaded first: a problem of its own is reported as
    the scene's (a SceneError), not blamed on a varied value."""
    load_scene(study.scene_path)
    return tuple(check_variant(study, v) for v in variants)


def check_variant(study: Study, variant: Variant) -> Scene:
    """Parse a variant's scene and check its cables as a run's plan would
    before it simulates (`cablecheck.build.stages.check_cables`: a length
    shorter than the route through its clips, or leaving its clamps along
    their tangents, is refused there, not run at another length; the
    shapes, which raise nothing, are left to the run); StudyError naming the
    study file, the varied key, the value and the scene's problem."""
    try:
        scene = parse_scene(variant.data, study.scene_path)
        if scene.cables:
            from cablecheck.build.stages import check_cables  # MuJoCo loads only for a study of cables

            check_cables(scene)
    except SceneError as e:
        raise StudyError(study.path, _culprit(study, variant, e.key),
                         f"scene {study.scene_path}: {e.key}: {e.problem}") from None
    return scene


def varied_cables(study: Study) -> tuple[str, ...]:
    """The cables whose own keys the study varies (``cables[i]...``), in the
    scene's order; every cable when some varied key is not a cable's (a
    motion's, a part's: it may move any of them)."""
    cables = study.scene_data.get("cables", [])
    names = [c.get("name") for c in cables if isinstance(c, dict)]
    found = set()
    for v in study.vary:
        m = re.match(r"cables\[(\d+)\]", v.path)
        if m is None:
            return tuple(names)
        found.add(int(m.group(1)))
    return tuple(n for i, n in enumerate(names) if i in found)


def check_study_names(study: Study, scene: Scene) -> None:
    """StudyError for a requirement or goal naming no cable or part of the
    scene (with an mjcf model, a name beginning with one of its bodies
    passes: its geoms' parts are named at the build)."""
    from cablecheck.scene.mjcf import compile_mjcf  # only a study naming parts of an mjcf model compiles it

    cables = {c.name for c in scene.cables}
    parts = {p.name for p in scene.parts}
    found = check_names(study.requirements, study.goal, cables, parts)
    if found is not None and scene.mjcf is not None:
        bodies = set(compile_mjcf(scene.path, Path(scene.mjcf)).bodies)
        found = check_names(study.requirements, study.goal, cables, parts, bodies)
    if found is not None:
        raise StudyError(study.path, *found)


def _culprit(study: Study, variant: Variant, scene_key: str) -> str:
    """The varied key(s) and value(s) a scene error at `scene_key` comes from."""
    pairs = list(zip(study.vary, variant.values))
    hits = [(v, x) for v, x in pairs if scene_key == v.path or scene_key.startswith(v.path + ".")
            or scene_key.startswith(v.path + "[")]
    named = hits or pairs
    return ", ".join(f"vary[{study.vary.index(v)}] {v.key} = {format_value(x)}" for v, x in named)


def format_value(value: Any) -> str:
    """A value as written in TOML (numbers in shortest form)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return f"{value:.10g}"
    if isinstance(value, list):
        return "[" + ", ".join(format_value(v) for v in value) + "]"
    if isinstance(value, str):
        return repr(value)
    return str(value)


# -- reading ------------------------------------------------------------------

def _read_toml(path: Path, error: type[SceneError]) -> dict:
    try:
        text = path.read_bytes().decode("utf-8")
    except OSError as e:
        raise error(path, "(file)", f"cannot read: {e.strerror or e}") from None
    except UnicodeDecodeError as e:
        raise error(path, "(file)", f"not UTF-8 text (byte {e.start}: {e.reason})") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        message = str(e)
        where = re.search(r"\s*\(at (line \d+, column \d+)\)$", message)
        if where:
            raise error(path, where.group(1), f"invalid TOML: {message[:where.start()]}") from None
        raise error(path, "(syntax)", f"invalid TOML: {message}") from None


def _table(value: Any, file: Path, where: str, allowed: tuple[str, ...],
           required: tuple[str, ...]) -> dict:
    if not isinstance(value, dict):
        raise StudyError(file, where, f"expected a table, got {type(value).__name__}")
    for key in value:
        if key not in allowed:
            close = difflib.get_close_matches(key, allowed, n=1, cutoff=0.6)
            hint = f"did you mean '{close[0]}'?" if close else "valid keys: " + ", ".join(allowed)
            raise StudyError(file, key if where == "(top level)" else f"{where}.{key}",
                             f"unknown key ({hint})")
    for key in required:
        if key not in value:
            raise StudyError(file, key if where == "(top level)" else f"{where}.{key}",
                             "missing (required)")
    return value


def _search(table: Any, file: Path) -> SearchPlan:
    if table is None:
        return SearchPlan()
    _table(table, file, "search", _SEARCH_KEYS, ())
    text = table.get("method", "grid")
    try:
        method = Method(text if isinstance(text, str) else None)
    except ValueError:
        raise StudyError(file, "search.method", f"must be 'grid' or 'optimise', got {text!r}") from None
    budget = table.get("budget")
    if method is Method.OPTIMISE:
        if not isinstance(budget, int) or isinstance(budget, bool) or budget < 2:
            raise StudyError(file, "search.budget", f"a search needs a budget of at least 2 runs, got {budget!r}")
    elif budget is not None:
        raise StudyError(file, "search.budget", "only a search (method = 'optimise') has a budget")
    return SearchPlan(method, budget)


def _vary(entry: dict, file: Path, where: str, scene: dict, scene_path: Path,
          method: Method = Method.GRID) -> Vary:
    _table(entry, file, where, _VARY_KEYS, ("key",))
    key = entry["key"]
    if not isinstance(key, str) or not key.strip():
        raise StudyError(file, f"{where}.key", f"expected a dotted path, got {key!r}")
    try:
        steps, path = resolve(scene, key)
    except KeyError as e:
        raise StudyError(file, f"{where}.key", f"{key!r}: {e.args[0]} in {scene_path}") from None
    if method is Method.OPTIMISE:
        # a search varies a number within a range: from and to, no count
        for k in ("from", "to"):
            if k not in entry:
                raise StudyError(file, f"{where}.{k}", "missing (a search varies a key from one number to another)")
            if not _is_number(entry[k]):
                raise StudyError(file, f"{where}.{k}", f"expected a finite number, got {entry[k]!r}")
        for k in ("values", "count"):
            if k in entry:
                raise StudyError(file, f"{where}.{k}", "a search picks its own values: give from and to only")
        lo, hi = float(entry["from"]), float(entry["to"])
        if not lo < hi:
            raise StudyError(file, f"{where}.to", f"must be above from ({lo:g}), got {hi:g}")
        return Vary(key=key, path=path, steps=tuple(steps), values=(lo, hi), bounds=(lo, hi))
    ranged = [k for k in ("from", "to", "count") if k in entry]
    if ("values" in entry) == bool(ranged):
        raise StudyError(file, where, "give either 'values' or 'from', 'to' and 'count'")
    if "values" in entry:
        values = entry["values"]
        if not isinstance(values, list) or not values:
            raise StudyError(file, f"{where}.values", f"expected a non-empty array, got {values!r}")
    else:
        for k in ("from", "to", "count"):
            if k not in entry:
                raise StudyError(file, f"{where}.{k}", "missing (a range needs from, to and count)")
        values = _range(entry["from"], entry["to"], entry["count"], file, where)
    return Vary(key=key, path=path, steps=tuple(steps), values=tuple(values))


def _is_number(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) \
        and abs(x) <= LARGEST


def _range(start: Any, stop: Any, count: Any, file: Path, where: str) -> list:
    """`count` evenly spaced values from `start` to `stop` inclusive (numbers,
    or arrays of numbers of one length, spaced element by element)."""
    if not isinstance(count, int) or isinstance(count, bool) or count < 1:
        raise StudyError(file, f"{where}.count", f"expected a positive integer, got {count!r}")
    if count > MAX_VARIANTS:
        raise StudyError(file, f"{where}.count", f"{count} values, more than {MAX_VARIANTS}")
    vector = isinstance(start, list)
    a = start if vector else [start]
    b = stop if isinstance(stop, list) else [stop]
    for k, v in (("from", a), ("to", b)):
        if not all(_is_number(x) for x in v) or not v:
            raise StudyError(file, f"{where}.{k}", f"expected a finite number or an array of them, "
                                                   f"got {start if k == 'from' else stop!r}")
    if isinstance(stop, list) != vector or len(a) != len(b):
        raise StudyError(file, f"{where}.to", "must have the shape of 'from'")
    if count == 1 and a != b:
        raise StudyError(file, f"{where}.count", "1 value cannot span from a value to another")
    out = []
    for k in range(count):
        f = k / (count - 1) if count > 1 else 0.0
        # both ends exact; in between, the nearer end plus a multiple of the step
        v = [float(x) if k == 0 else float(y) if k == count - 1 else x + (y - x) * f
             for x, y in zip(a, b)]
        out.append(v if vector else v[0])
    return out


# -- paths --------------------------------------------------------------------

def resolve(data: dict, key: str) -> tuple[list[str | int], str]:
    """Resolve a dotted study key against a scene dict.

    Returns the steps (str keys, int indices) and the path in the scene
    parser's notation (``cables[0].clips[1].pos``). Raises KeyError with the
    problem in words when a step leads nowhere."""
    parts = key.split(".")
    if any(not p for p in parts):
        raise KeyError("empty step in the dotted path")
    steps: list[str | int] = []
    shown = ""
    node: Any = data
    i = 0
    while i < len(parts):
        part = parts[i]
        last = i == len(parts) - 1
        if isinstance(node, dict):
            if part not in node:
                if last:
                    steps.append(part)
                    shown = f"{shown}.{part}" if shown else part
                    break
            steps.append(part)
            shown = f"{shown}.{part}" if shown else part
            # an absent table on the way is created in every variant (`_set`)
            node = node.get(part, {})
            i += 1
        elif isinstance(node, list):
            index, used = _entry(node, parts, i, shown)
            steps.append(index)
            shown = f"{shown}[{index}]"
            node = node[index]
            i += used
            if i == len(parts) and isinstance(node, dict):
                raise KeyError(f"{shown} is a table; name a key in it")
        else:
            raise KeyError(f"{shown} is a value ({node!r}), not a table or array; "
                           f"cannot go into it with {'.'.join(parts[i:])!r}")
    return steps, shown


def _entry(array: list, parts: list[str], i: int, shown: str) -> tuple[int, int]:
    """The index in `array` that parts[i:] start with, and how many parts it used:
    the longest dotted name of a table entry, else a 0-based index."""
    tables = all(isinstance(v, dict) for v in array)
    if tables:
        for j in range(len(parts), i, -1):
            name = ".".join(parts[i:j])
            hits = [k for k, t in enumerate(array) if any(t.get(f) == name for f in NAME_FIELDS)]
            if len(hits) > 1:
                raise KeyError(f"{name!r} names {len(hits)} entries of {shown} "
                               f"(at {hits}); give an index instead")
            if hits:
                return hits[0], j - i
    part = parts[i]
    if re.fullmatch(r"\d+", part):
        index = int(part)
        if index >= len(array):
            raise KeyError(f"index {index} is past the end of {shown} ({len(array)} entries)")
        return index, 1
    names = [str(t.get(f)) for t in array if isinstance(t, dict) for f in NAME_FIELDS if f in t]
    if tables:
        raise KeyError(f"no entry of {shown} named {part!r}" + _hint(part, names))
    raise KeyError(f"{shown} is an array of values; give a 0-based index, not {part!r}")


def _hint(word: str, known: list[str]) -> str:
    close = difflib.get_close_matches(word, known, n=1, cutoff=0.6)
    if close:
        return f" (did you mean {close[0]!r}?)"
    return f" (known: {', '.join(known)})" if known else ""


def _set(data: dict, steps: tuple[str | int, ...], value: Any) -> None:
    node: Any = data
    for step in steps[:-1]:
        if isinstance(node, dict) and step not in node:
            node[step] = {}
        node = node[step]
    node[steps[-1]] = value
