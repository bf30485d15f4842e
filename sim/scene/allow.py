"""`[[allow]]`: contacts that belong to the design, and whether their names
cover anything.

An allow name must cover a scene part or cable (by name or assembly path
prefix) or a colliding geom of the mjcf model, named as the builder names
it (checked again against the built parts once the model exists,
`check_allow_names`, called by `cablecheck.run.runner`). Applying
the rules to interference records is the checker's job, not this module's.
"""

from __future__ import annotations

import difflib

from cablecheck.scene.errors import SceneError
from cablecheck.scene.format import ALLOW_KEYS
from cablecheck.scene.reader import Reader
from cablecheck.scene.records import AllowDef, Scene


def read_allow(r: Reader, value: dict, where: str, names: list[str]) -> AllowDef:
    """An `[[allow]]` pair. Its names must cover a scene part or cable, or
    a colliding geom of the mjcf model by the name the builder gives it
    (`cablecheck.scene.mjcf.colliding_parts`: ``<body>/<geom>``; a body
    names all of its colliding geoms)."""
    t = r.table(value, where, ALLOW_KEYS, ("a", "b", "reason"))
    model_parts = list(r.mjcf.parts) if r.mjcf is not None else []
    out = []
    for key in ("a", "b"):
        name = r.name(t[key], f"{where}.{key}")
        if not covers(name, names + model_parts):
            body = name.split("/")[0]
            if r.mjcf is not None and (body in r.mjcf.bodies or body == "world") and name == body:
                raise r.error(f"{where}.{key}", f"body {body!r} of the mjcf model has no colliding geom (its geoms "
                                                f"are visual, contype = conaffinity = 0, or none): nothing of it "
                                                f"is a part a cable can touch")
            raise r.error(f"{where}.{key}", unknown_name(name, names + model_parts))
        out.append(name)
    reason = r.name(t["reason"], f"{where}.reason")
    return AllowDef(out[0], out[1], reason)


def covers(pattern: str, names) -> bool:
    """True when `pattern` is one of `names` or an assembly path prefix of one."""
    prefix = pattern + "/"
    return any(n == pattern or n.startswith(prefix) for n in names)


def unknown_name(name: str, names, what: str = "part, assembly path or cable") -> str:
    """The problem text for a name (of an `[[allow]]` rule, or a cable end's
    `part`) that covers nothing, with the closest known name as a hint."""
    known = sorted({"/".join(n.split("/")[:k]) for n in names for k in range(1, n.count("/") + 2)})
    close = difflib.get_close_matches(name, known, n=1, cutoff=0.6)
    hint = f"did you mean {close[0]!r}?" if close else f"{len(known)} names known, e.g. " + \
        ", ".join(repr(k) for k in known[:5])
    return f"no {what} named {name!r} ({hint})"


def check_allow_names(scene: Scene, names) -> None:
    """Raise SceneError when an `[[allow]]` name covers none of `names` (the
    built parts' and the cables' names): a name taken at load time for a
    body of the mjcf model whose geoms the builder named otherwise."""
    names = list(names)
    for i, rule in enumerate(scene.allow):
        for key, name in (("a", rule.a), ("b", rule.b)):
            if not covers(name, names):
                raise SceneError(scene.path, f"allow[{i}].{key}", unknown_name(name, names))
