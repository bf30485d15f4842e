"""The time series of the review recording: pair distances and per-cable measures.

`checks/<type>/<a>/<b>/distance` (scene units): every pair below the
clearance, and, at full checks, every pair the checker evaluated up to its
horizon (the approach before a clash); a pair's line breaks (NaN) where it
is not known. `checks/limits/{clearance,zero}`: reference lines.
`cables/strain/<name>` (percent), `cables/bend_radius/<name>` (scene
units, with `<name>_limit` lines), `cables/twist/<name>` (degrees), each
in the cable's own colour as in the 3D view,
`validation/agreement`, `joints/<name>`. Values are buffered by frame and
sent in one column per series when the recording is closed, each series
only where it changes (:func:`changes`: a pair that sits still costs two
rows, not one per frame).

Not here: what the values are (the run measures them).
"""

from __future__ import annotations

import numpy as np
import rerun as rr

from cablecheck.build.built import Built
from cablecheck.record.columns import Once, column, floats, rgba, strings, times as sim_time
from cablecheck.record.style import HARD, escape


class Series:
    """A scalar series buffered by frame; a NaN breaks its line."""

    def __init__(self):
        self.frames: list[int] = []
        self.values: list[float] = []

    def add(self, frame: int, value: float) -> None:
        if self.frames and self.frames[-1] == frame:
            self.values[-1] = min(self.values[-1], value)
            return
        self.frames.append(frame)
        self.values.append(value)

    def gap(self, frame: int) -> None:
        """Not known from this frame on: the line stops here."""
        if self.frames and self.frames[-1] < frame and not np.isnan(self.values[-1]):
            self.frames.append(frame)
            self.values.append(np.nan)


RESOLUTION = 1e-3
"""A series keeps a value only where its line bends by more than this
fraction of its own range (:func:`changes`): the line drawn through the
kept values runs within that of every value, a thousandth of the plot's
height or finer."""


def changes(times: np.ndarray, values: np.ndarray, resolution: float = RESOLUTION) -> np.ndarray:
    """(n,) mask of the values of a series worth keeping: the line through
    the kept ones (rerun draws straight lines between points) passes within
    `resolution` times the series' range of every value. NaNs (where the
    line breaks) and their neighbours, the ends, and the lowest and highest
    value are always kept (:func:`changes_many` for one series)."""
    return changes_many([times], [values], resolution)[0]


def changes_many(times: list[np.ndarray], values: list[np.ndarray],
                 resolution: float = RESOLUTION) -> list[np.ndarray]:
    """:func:`changes` of many series in one vectorised pass.

    Pairwise merging, coarse to fine in log2(n) passes over the series laid
    end to end (a NaN between two series, so no window spans both): at pass
    k each point at an odd multiple of 2^(k-1) goes if every value between
    its neighbours on the coarser grid lies within half the tolerance of
    their chord (the line through what is kept then strays at most twice
    that)."""
    sizes = np.array([len(v) for v in values], int)
    if not len(sizes):
        return []
    gap = np.array([np.nan])
    t = np.concatenate([x for tv in times for x in (np.asarray(tv, float), gap)])
    v = np.concatenate([x for vv in values for x in (np.asarray(vv, float), gap)])
    n = len(v)
    series = np.repeat(np.arange(len(sizes)), sizes + 1)
    starts = np.r_[0, np.cumsum(sizes + 1)[:-1]]
    lo_v = np.fmin.reduceat(v, starts)                       # NaN-ignoring (all-NaN series: NaN)
    hi_v = np.fmax.reduceat(v, starts)
    tol = (0.5 * resolution * (hi_v - lo_v))[series]
    must = ~np.isfinite(v)
    for extreme in (lo_v, hi_v):                              # each series' first lowest and highest
        at = np.flatnonzero(v == extreme[series])
        must[at[np.unique(series[at], return_index=True)[1]]] = True
    keep = np.ones(n, bool)
    half = 1
    while half < n - 1:
        i = np.arange(half, n - 1, 2 * half)                   # candidates of this pass
        lo, hi = i - half, np.minimum(i + half, n - 1)
        w = np.minimum(lo[:, None] + np.arange(2 * half + 1)[None], hi[:, None])   # each window
        with np.errstate(invalid="ignore", divide="ignore"):
            f = (t[w] - t[lo][:, None]) / (t[hi] - t[lo])[:, None]
            dev = np.abs(v[w] - (v[lo][:, None] + f * (v[hi] - v[lo])[:, None]))
        ok = (dev <= tol[i][:, None]).all(axis=1) & ~must[i]    # a NaN in the window keeps it
        keep[i[ok]] = False
        half *= 2
    return [k[:-1] for k in np.split(keep, np.cumsum(sizes + 1))[:-1]]


class SeriesSet:
    """Every series of a run by entity path, with its legend label and,
    where given, its colour (a cable's measures: the cable's own)."""

    def __init__(self):
        self.series: dict[str, Series] = {}
        self.labels: dict[str, str] = {}
        self.colours: dict[str, tuple[int, int, int]] = {}

    def add(self, path: str, frame: int, value: float, label: str | None = None) -> None:
        """A value at `frame`; `label` names the series in legends (the first one given)."""
        if label is not None and path not in self.labels:
            self.labels[path] = label
        series = self.series.get(path)
        if series is None:
            series = self.series[path] = Series()
        series.add(frame, float(value))

    def lowest(self, prefix: str) -> float | None:
        """The lowest finite value of the series under `prefix`, or None."""
        lows = [np.nanmin(s.values) for p, s in self.series.items()
                if p.startswith(prefix) and s.values and np.isfinite(s.values).any()]
        return float(min(lows)) if lows else None

    def send(self, rec: rr.RecordingStream, times: np.ndarray) -> None:
        """Every series, one column each, its label in the first row (the
        plots query the whole timeline, so the legend finds it; one chunk per
        series, not two)."""
        every = list(self.series.items())
        kept = changes_many([times[s.frames] for _, s in every], [s.values for _, s in every])
        scalars, names = rr.Scalars.descriptor_scalars(), rr.SeriesLines.descriptor_names()
        for (path, series), keep in zip(every, kept):
            columns = [column(scalars, floats(np.asarray(series.values, float)[keep]))]
            if path in self.labels:
                columns.append(Once(names, strings([self.labels[path]]), int(keep.sum())))
            if path in self.colours:
                columns.append(Once(rr.SeriesLines.descriptor_colors(), rgba([self.colours[path]]), int(keep.sum())))
            rec.send_columns(path, indexes=[sim_time(times[series.frames][keep])], columns=columns)


def send_limit_lines(rec: rr.RecordingStream, built: Built, times: np.ndarray, clearance: float, unit: float,
                     units: str) -> None:
    """Clearance and zero lines on the distance plot, bend-radius limits on the bend plot."""
    ends = [sim_time(np.array([times[0], times[-1]]))]
    lines = [("checks/limits/clearance", clearance / unit, f"clearance ({units})", (120, 120, 120)),
             ("checks/limits/zero", 0.0, "touching", (60, 60, 60))]
    for cable in built.cables:
        if cable.min_bend_radius is not None:
            lines.append((f"cables/bend_radius/{escape(cable.name)}_limit", cable.min_bend_radius / unit,
                          f"{cable.name} bend limit ({units})", HARD))
    for path, value, name, colour in lines:
        # the line's style rides in its first row: one chunk per line
        rec.send_columns(path, indexes=ends, columns=[
            column(rr.Scalars.descriptor_scalars(), floats([value, value])),
            Once(rr.SeriesLines.descriptor_names(), strings([name]), 2),
            Once(rr.SeriesLines.descriptor_colors(), rgba([colour]), 2),
            Once(rr.SeriesLines.descriptor_widths(), floats([1.0], np.float32), 2)])
