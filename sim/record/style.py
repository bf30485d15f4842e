"""Colours and entity paths of the review recording, shared by its modules.

Paths mirror the scene: a part's assembly levels become tree levels, a
pair is `<type>/<a>/<b>`. Colours: the cable states' (clear, soft, hard),
the parts' and floors', the spot's, which no cable state, part or contact
uses, and each cable's own (:func:`cable_colour`, from a qualitative
palette kept apart from all of those).

Not here: what is logged where (the other modules of `cablecheck.record`).
"""

from __future__ import annotations

from collections import Counter
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
FLOOR = (160, 160, 170, 110)
"""A plane (a floor): always translucent, so what lies under it shows."""
FLOOR_DIMMED = (160, 160, 170, 45)
"""A plane while a clash is shown."""
KEEPOUT_COLOUR = (255, 140, 0, 90)
CONTACT_COLOUR = (40, 220, 120)
CABLE_PALETTE = ((31, 119, 180), (44, 160, 44), (148, 103, 189), (23, 190, 207), (140, 86, 75), (120, 120, 20),
                 (40, 60, 140), (150, 200, 80), (190, 140, 90), (90, 60, 200))
"""Each cable's own colour, in the scene's order (a qualitative palette:
blue, green, purple, cyan, brown, olive, navy, lime, tan, violet), far from
the soft and hard states' amber and red, the spot's magenta, the parts'
grey and the contacts' green."""


def cable_colour(index: int) -> tuple[int, int, int]:
    """The colour of the scene's `index`-th cable: the palette's, darker on
    each further round of it (a harness of more cables than colours)."""
    rgb = CABLE_PALETTE[index % len(CABLE_PALETTE)]
    shade = 0.75 ** (index // len(CABLE_PALETTE) % 3)
    return tuple(round(c * shade) for c in rgb)


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
    levels = {n: tuple(n.split("/")) for n in full}
    depth = max(map(len, levels.values()), default=0)
    # how many names end in each tail of k levels: a tail only its own name ends in tells it apart
    # (every name against every other, a harness's 1,064 names cost a quarter second a call)
    ends = [Counter(parts[-k:] for parts in levels.values() if len(parts) >= k) for k in range(1, depth + 1)]
    short = {}
    for n, parts in levels.items():
        for k in range(1, len(parts) + 1):
            tail = parts[-k:]
            if ends[k - 1][tail] == 1:
                break
        short[n] = "/".join(tail)
    return short


def short_pairs(events: list, names=()) -> list[str]:
    """Each event's pair in short names (:func:`short_names` among `names`
    and the events' own), as :func:`pair_text` writes it."""
    short = short_names([*names, *(e.a for e in events), *(e.b for e in events)])
    return [pair_text(short[e.a], short[e.b]) for e in events]
