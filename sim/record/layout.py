"""The review recording's blueprint: views, viewpoints and plot ranges.

The 3D scene framed on the whole scene and, for the worst clashes, a saved
viewpoint on each spot (opening on the worst); the pair state lanes below;
the plots (distances with a range round the clearance, bend radius, strain,
twist, agreement, joints, the wear profiles) beside the clash list, the
event log and the summary. Written when the recording is closed, when the
run's extent is known.

Not here: the data the views show (the other modules of `cablecheck.record`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
from rerun.blueprint.components import ComponentColumnSelector

from cablecheck.build.built import Built
from cablecheck.record.style import SPOT, STATE_COLOURS, STATES, escape, pair_text, short_pairs

CLASH_COLUMNS = ("severity", "pair", "worst_distance", "status", "type", "phase", "start", "end", "joints", "a", "b")
"""The clash list's columns, in order, after its rank (`clash`) and worst
time (`sim_time`); each is an entity, `clashes/<column>` ("status" only
against a baseline run). rerun's dataframe view orders a view's columns by
entity (`entity_order`), and one entity's components alphabetically
whatever the selection's order: hence an entity per column."""
CLASH_TIMELINE = "clash"
"""The clash list's index: its rows' rank, worst first (a sequence); each
row's `sim_time` cell jumps to its worst time."""
PAIR_HEADER = "cable / other"


def clash_headers(units: str, pair_width: int) -> dict[str, str]:
    """Each clash list column's component name, the header under its entity
    path: the unit where there is one. The dataframe view sizes a column to
    its headers and cuts longer values short, so the pair's header is padded
    to the longest pair (`pair_width` characters, and the quotes the view
    puts round text)."""
    return {"severity": "severity", "pair": PAIR_HEADER.ljust(pair_width + 2), "worst_distance": units,
            "status": "status", "type": "type", "phase": "phase", "start": "s", "end": "s", "joints": "joints",
            "a": "full path", "b": "full path"}
VIEWPOINTS = 6
"""Clashes (worst first) that get a saved viewpoint of their own."""


@dataclass(frozen=True)
class Together:
    """Several archetypes' components as one (rerun's `AsComponents`): a
    view's defaults logged in one entry, one chunk of the blueprint, not one
    per archetype."""

    parts: tuple

    def as_component_batches(self) -> list:
        return [batch for part in self.parts for batch in part.as_component_batches()]


def spot_style() -> Together:
    """The 3D views' defaults that style the spots (`cablecheck.record.marks`): a
    wire sphere, its label on a small point and its gap, in the spot's
    colour. Every other ellipsoid, point and line strip (parts, cables'
    names, contacts, the wear map) carries its own fill, colour and radius,
    which a default never overrides."""
    return Together((rr.Ellipsoids3D.from_fields(colors=[SPOT], line_radii=[-2.5], fill_mode="MajorWireframe"),
                     rr.Points3D.from_fields(colors=[SPOT], radii=[-2.0], show_labels=True),
                     rr.LineStrips3D.from_fields(colors=[SPOT])))


def lane_style() -> rr.StateConfiguration:
    """The state timeline's default: the pair states' names and colours."""
    return rr.StateConfiguration(values=list(STATES), colors=[STATE_COLOURS[x] for x in STATES])


@dataclass(frozen=True)
class Extent:
    """What the layout needs to know of a finished run.

    Attributes:
      bounds: (lo, hi) of the scene at t = 0, metres.
      lowest_distance: the lowest pair distance plotted (scene units), or None.
      series_roots: the first levels of every series path (`checks`, `joints`, ...).
      twist: whether any cable's twist is plotted.
      twisted: the cables whose twist along them is charted (`twist/<name>/max_moment`).
      worn: the cables whose wear is charted (`wear/<name>/<measure>`).
    """

    bounds: tuple[np.ndarray, np.ndarray]
    lowest_distance: float | None
    series_roots: frozenset[str]
    twist: bool
    twisted: tuple[str, ...] = ()
    worn: tuple[str, ...] = ()


def _eye(bounds, target: np.ndarray, distance: float, unit: float) -> rrb.EyeControls3D:
    lo, hi = bounds
    away = target - 0.5 * (lo + hi)
    away[2] = 0.0
    n = float(np.linalg.norm(away))
    side = away / n if n > 1e-9 * max(distance, 1e-12) else np.array([0.6, -0.8, 0.0])
    direction = side + np.array([0.0, 0.0, 0.6]) + np.array([0.3, -0.5, 0.0])
    direction /= np.linalg.norm(direction)
    return rrb.EyeControls3D(kind=rrb.Eye3DKind.Orbital, position=(target + distance * direction) / unit,
                             look_target=target / unit, eye_up=[0.0, 0.0, 1.0])


def _scene_eye(bounds, unit: float) -> rrb.EyeControls3D:
    lo, hi = bounds
    centre = 0.5 * (lo + hi)
    diag = float(np.linalg.norm(hi - lo)) or 1.0
    direction = np.array([0.55, -0.75, 0.45])
    direction /= np.linalg.norm(direction)
    return rrb.EyeControls3D(kind=rrb.Eye3DKind.Orbital, position=(centre + 0.85 * diag * direction) / unit,
                             look_target=centre / unit, eye_up=[0.0, 0.0, 1.0])


def blueprint(built: Built, events: list, wear: list, extent: Extent, clearance: float, scale, unit: float,
              units: str, status: bool = False, names=()) -> rrb.Blueprint:
    """The layout of a finished run (`clearance` in metres; `scale`: the wear
    map's :class:`cablecheck.record.wearview.WearScale`; `status`: the
    clash list has a status column, against a baseline run; `names`: the
    scene's names that the clash list's short names are told apart among)."""
    bounds = extent.bounds
    spots = [spot_style()]          # made once, the default of every 3D view
    tabs = [rrb.Spatial3DView(name="Scene", origin="world", eye_controls=_scene_eye(bounds, unit),
                              defaults=spots)]
    radius = {c.name: c.radius for c in built.cables}
    worst = sorted(events, key=lambda e: (e.severity != "hard", e.min_distance))[:VIEWPOINTS]
    for n, ev in enumerate(worst, 1):
        reach = max(12.0 * (radius.get(ev.a, 0.01) + clearance), 0.25 * float(np.linalg.norm(bounds[1] - bounds[0])))
        tabs.append(rrb.Spatial3DView(
            name=f"#{n} {ev.severity} {pair_text(ev.a, ev.b)} @ {ev.t_worst:.3f} s", origin="world",
            eye_controls=_eye(bounds, np.asarray(ev.where, float), reach, unit), defaults=spots))
    if wear:
        tabs.append(rrb.Spatial3DView(name=f"Wear map: {scale.legend()}", origin="wear_map"))
    clear = clearance / unit
    low = min(extent.lowest_distance if extent.lowest_distance is not None else 0.0, 0.0)
    limits = [c.min_bend_radius for c in built.cables if c.min_bend_radius is not None]
    titles = {"joints": "Joint values (deg, or scene units for slides)"}
    plots = [
        rrb.TimeSeriesView(name=f"Pair distances ({units})", origin="checks",
                           axis_y=rrb.ScalarAxis(range=(min(low * 1.1, -0.1 * clear), 4.0 * clear), zoom_lock=False),
                           plot_legend=rrb.PlotLegend(corner="LeftTop", visible=True)),
        rrb.TimeSeriesView(name=f"Min bend radius ({units})", origin="cables/bend_radius",
                           axis_y=rrb.ScalarAxis(range=(0.0, 5.0 * max(limits) / unit)) if limits else None),
        rrb.TimeSeriesView(name="Strain (%)", origin="cables/strain"),
        *([rrb.TimeSeriesView(name="Twist (deg)", origin="cables/twist")] if extent.twist else []),
        rrb.TimeSeriesView(name="Agreement with MuJoCo (fraction of pairs)", origin="validation",
                           axis_y=rrb.ScalarAxis(range=(0.0, 1.05))),
        # a plot for every other series root (e.g. joint values logged by the run)
        *[rrb.TimeSeriesView(name=titles.get(root, root), origin=root)
          for root in sorted(extent.series_roots - {"checks", "cables", "validation"})],
        *[rrb.BarChartView(name=f"Wear {w.name}: {m} per bin ({unit_})", origin=f"wear/{escape(w.name)}/{m}")
          for w in wear if w.name in extent.worn
          for m, unit_ in (("contact_time", "s"), ("sliding", units), ("bend_cycles", "cycles"))],
        *[rrb.BarChartView(name=f"Twist {name}: largest moment along it (N m; {units} from its start)",
                           origin=f"twist/{escape(name)}/max_moment") for name in extent.twisted],
    ]
    columns = [c for c in CLASH_COLUMNS if status or c != "status"]
    headers = clash_headers(units, max(map(len, short_pairs(events, names)), default=0))
    lists = rrb.Tabs(
        rrb.DataframeView(name="Clash list, worst first (click a row's sim_time to jump)", origin="clashes",
                          query=rrb.archetypes.DataframeQuery(
                              timeline=CLASH_TIMELINE, select=[CLASH_TIMELINE, "sim_time", *[ComponentColumnSelector(
                                  entity_path=f"/clashes/{c}", component=headers[c]) for c in columns]],
                              entity_order=[f"/clashes/{c}" for c in columns])),
        rrb.TextLogView(name="Events", origin="events"),
        rrb.TextDocumentView(name="Summary", origin="summary"),
    )
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(rrb.Tabs(*tabs, active_tab=1 if worst else 0),   # opens on the worst clash
                         rrb.StateTimelineView(name="Pair states (clear / soft / hard)", origin="lanes",
                                               defaults=[lane_style()]),
                         row_shares=[5, 1]),
            rrb.Vertical(rrb.Tabs(*plots), lists, row_shares=[3, 2]),
            column_shares=[3, 2],
        ),
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="collapsed", timeline="sim_time"),
    )
