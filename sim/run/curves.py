"""Interpolating scripted samples in time: piecewise polynomials over many channels.

A motion gives samples (n times, C channels: joint values, body coordinates)
and an interpolation:

- ``"cubic"``: piecewise cubic Hermite with the shape-preserving slopes of
  Fritsch and Carlson (PCHIP, scipy's `PchipInterpolator`), continuous in
  value and velocity. Unlike a C2 cubic spline it never overshoots: on each
  interval the curve stays between its two samples, so a hold between two
  equal keys stays a hold and a joint sampled inside its range never leaves
  it between samples. The first and last slopes are zero (still within the
  Fritsch-Carlson region), because the motion holds the first sample before
  it and the last one after it: the velocity is continuous there too.
- ``"linear"``: straight lines between samples, velocity constant on each
  interval (it jumps at the samples).

`merge` re-expresses the curves of several motions, each on its own times,
as one `Curve` over the union of their times (a piecewise cubic on some
breakpoints is a piecewise cubic on any finer set, exactly), so a step
evaluates every channel of every motion in two vectorised calls. This module
knows nothing of MuJoCo, joints or bodies: it interpolates columns of numbers.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from cablecheck.scene.format import INTERPOLATIONS

if TYPE_CHECKING:
    from scipy.interpolate import PPoly

"""Values of `[[motion]] interpolation`; the first is the default."""


def interpolant(times: np.ndarray, values: np.ndarray, kind: str) -> PPoly:
    """The piecewise polynomial through samples `values` (n, C) at strictly
    increasing `times` (n,), of `kind` (see the module docstring), defined on
    [times[0], times[-1]] (a single sample: a constant on [t, t + 1])."""
    from scipy.interpolate import (  # a run loads it, `check` does not
        CubicHermiteSpline,
        PchipInterpolator,
        PPoly,
    )

    times = np.asarray(times, float)
    values = np.asarray(values, float).reshape(len(times), -1)
    if len(times) == 1:
        coef = np.zeros((4, 1, values.shape[1]))
        coef[3, 0] = values[0]
        return PPoly(coef, np.array([times[0], times[0] + 1.0]))
    if kind == "linear":
        coef = np.zeros((4, len(times) - 1, values.shape[1]))
        coef[2] = np.diff(values, axis=0) / np.diff(times)[:, None]
        coef[3] = values[:-1]
        return PPoly(coef, times)
    if kind != "cubic":
        raise ValueError(f"interpolation must be one of {INTERPOLATIONS}, got {kind!r}")
    # Secant slopes near the smallest float overflow scipy's weighted harmonic
    # mean to inf, whose reciprocal is the right slope (0): no warning for that.
    with np.errstate(over="ignore", divide="ignore"):
        slopes = PchipInterpolator(times, values, axis=0).derivative()(times)
    slopes[[0, -1]] = 0.0
    return CubicHermiteSpline(times, values, slopes, axis=0)


def _held(poly: PPoly, start: float, end: float) -> PPoly:
    """`poly` extended to [start, end] by holding its end values (zero slope)."""
    from scipy.interpolate import PPoly  # loaded already by the interpolant it extends

    x, c = poly.x, poly.c
    if start < x[0]:
        head = np.zeros((4, 1) + c.shape[2:])
        head[3, 0] = poly(x[0])
        x, c = np.concatenate([[start], x]), np.concatenate([head, c], axis=1)
    if end > x[-1]:
        tail = np.zeros((4, 1) + c.shape[2:])
        tail[3, 0] = poly(x[-1])
        x, c = np.concatenate([x, [end]]), np.concatenate([c, tail], axis=1)
    return PPoly(c, x)


@dataclass(frozen=True, eq=False)
class Curve:
    """Channels of several motions on one set of breakpoints.

    Attributes:
      value: PPoly over the union of the motions' times, (C,) channels.
      rate: its derivative.
      start, end: the first and last breakpoint; outside them every channel
        holds its end value with zero rate.
      lo, hi: (C,) each channel's least and greatest sample. Both kinds of
        interpolation stay between their samples, but a polynomial summed in
        floating point does not quite: keys 0, 60, 0 read -2.5e-14 degrees
        at the last, and a joint keyed at its range's end would leave it by
        as much. Every value is held within them.
    """

    value: PPoly
    rate: PPoly
    start: float
    end: float
    lo: np.ndarray
    hi: np.ndarray

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(C,) values and (C,) rates at time t."""
        if t <= self.start or t >= self.end:
            clamped = min(max(t, self.start), self.end)
            value = np.clip(self.value(clamped), self.lo, self.hi)
            return value, np.zeros_like(value)
        return np.clip(self.value(t), self.lo, self.hi), self.rate(t)

    def at_many(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """`at` at each of `times` (m,): (m, C) values and (m, C) rates, the
        same numbers as `at` one time after the other (scipy evaluates each
        time on its own), for two polynomial calls in all."""
        t = np.asarray(times, float)
        value = self.sample(t)
        rate = np.zeros_like(value)
        inside = (t > self.start) & (t < self.end)
        if inside.any():
            rate[inside] = self.rate(t[inside])
        return value, rate

    def sample(self, times: np.ndarray) -> np.ndarray:
        """(m, C) values at the times (m,), held outside [start, end]."""
        return np.clip(self.value(np.clip(np.asarray(times, float), self.start, self.end)), self.lo, self.hi)


def merge(polys: list[PPoly], samples: list[np.ndarray] | None = None) -> Curve:
    """One Curve whose channels are those of `polys` in order, each held
    before its first and after its last breakpoint. At least one poly.
    `samples`: each poly's samples (n, C), whose least and greatest bound its
    channels (`Curve.lo`, `Curve.hi`); None: its values at its breakpoints."""
    from scipy.interpolate import PPoly  # loaded already by the interpolants it merges

    start = min(p.x[0] for p in polys)
    end = max(p.x[-1] for p in polys)
    held = [_held(p, start, end) for p in polys]
    knots = np.unique(np.concatenate([p.x for p in held]))
    left = knots[:-1]
    # Coefficients of each new interval from the derivatives at its left end;
    # scipy evaluates a breakpoint with the interval to its right.
    factorial = np.array([6.0, 2.0, 1.0, 1.0])
    columns = [np.stack([p(left, nu=3 - k) / factorial[k] for k in range(4)]).reshape(
        4, len(left), -1) for p in held]
    value = PPoly(np.concatenate(columns, axis=2), knots)
    # each channel's samples as given (a poly's value at its last breakpoint is a sum of rounded
    # terms), else its own poly's values at its own breakpoints
    at_knots = ([np.asarray(v, float).reshape(len(v), -1) for v in samples] if samples is not None
                else [p(p.x).reshape(len(p.x), -1) for p in held])
    lo = np.concatenate([v.min(axis=0) for v in at_knots])
    hi = np.concatenate([v.max(axis=0) for v in at_knots])
    return Curve(value, value.derivative(), float(start), float(end), lo, hi)
