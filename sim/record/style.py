"""Colours and entity paths of the review recording, shared by its modules.

Paths mirror the scene: a part's assembly levels become tree levels, a
pair is `<type>/<a>/<b>`. Colours: the cable states' (clear, soft, hard),
the parts', and the spot's, which no cable state, part or contact uses.

Not here: what is logged where (the other modules of `sim.record`).
"""

from __future__ import annotations

from functools import cache

CLEAR = (70, 160, 255)
SOFT = (255, 190, 40)
HARD = (230, 40, 40)
STATE_COLOURS = {"clear": CLEAR, "soft": SOFT, "hard": HARD}
STATES = ("clear", "soft", "hard")
SPOT = (255, 0, 230)
"""The spot's colour: used by no cable state, part or contact."""
PART_COLOUR = (160, 160, 170)
PART_DIMMED = (160, 160, 170, 70)
KEEPOUT_COLOUR = (255, 140, 0, 90)
CONTACT_COLOUR = (40, 220, 120)


@cache
def escape(level: str) -> str:
    """One level of an entity path: rerun separates levels with "/" and
    treats a few characters specially."""
    return "".join(c if (c.isalnum() or c in "-_.") else "_" for c in level) or "_"


def part_path(name: str) -> str:
    """Entity path of a part: its assembly levels become tree levels."""
    return "world/parts/" + "/".join(escape(p) for p in name.split("/"))


def visual_paths(body: str, name: str) -> tuple[str, str]:
    """Entity paths of a visual geom of the mjcf model: its body's and its own
    (`name` is `<body>/<geom>`)."""
    body_path = "world/visual/" + escape(body)
    rest = name[len(body) + 1:] if name.startswith(body + "/") else name
    return body_path, body_path + "/" + "/".join(escape(p) for p in rest.split("/"))


@cache
def pair_path(kind: str, a: str, b: str) -> str:
    """Entity path of a checked pair."""
    return f"{kind}/{escape(a)}/{escape(b)}"


def pair_text(a: str, b: str) -> str:
    """A pair as people read it: `a / b` (a self pair: `a`)."""
    return a if a == b else f"{a} / {b}"


def short_names(names) -> dict[str, str]:
    """Each name shortened to its last assembly levels, as few as tell it
    apart from every other name given: `machine/frame/upright_1` beside
    `machine/frame/upright_2` reads `upright_1`; a last level shared with
    another name keeps its parents until the two differ (`left/rail`,
    `right/rail`)."""
    full = sorted(set(names))
    levels = {n: n.split("/") for n in full}
    short = {}
    for n in full:
        parts = levels[n]
        for k in range(1, len(parts) + 1):
            tail = parts[-k:]
            if not any(m != n and levels[m][-k:] == tail for m in full):
                break
        short[n] = "/".join(tail)
    return short


def short_pairs(events: list, names=()) -> list[str]:
    """Each event's pair in short names (:func:`short_names` among `names`
    and the events' own), as :func:`pair_text` writes it."""
    short = short_names([*names, *(e.a for e in events), *(e.b for e in events)])
    return [pair_text(short[e.a], short[e.b]) for e in events]
