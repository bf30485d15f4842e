"""A search over continuous study keys in rounds of parallel runs: where the answer is, look closer.

`Search` proposes a round of points, is told their scores (larger is
better), and proposes the next: the first round covers the box of the keys'
ranges (evenly spaced for one key, its ends included; a Latin hypercube
with the box's centre for more), each later round the box around the best
point so far, half as wide as the round before on every key, clipped to the
ranges, a few new points in it (never one already run: where all would
repeat one, the box halves again). A round holds
``batch`` points (the workers the study has), so a round costs about one
run's time on the cluster; the search stops when ``budget`` runs are spent.

Written here because the derivative-free optimisers of scipy
(``minimize_scalar``, ``direct``, Nelder-Mead) ask for one point at a time,
which would leave all but one worker idle, and the batch Bayesian
optimisers on PyPI are no longer kept. A run is seconds to minutes, so the
cost of proposing is nothing beside it.

Deliberately not here: running the points, scoring them (see
`cablecheck.study.goal.Judgement.score`) or reading the study file.
"""

from __future__ import annotations

import numpy as np

FIRST_SHARE = 0.4
"""The first round takes this share of the budget (at least a batch and
three points a key): enough to see where the answer lies before zooming."""


class Search:
    """Rounds of points in the box ``lo``..``hi`` (D,), ``budget`` runs in all,
    ``batch`` a round (at least)."""

    def __init__(self, lo, hi, budget: int, batch: int, seed: int = 0):
        self.lo = np.asarray(lo, float)
        self.hi = np.asarray(hi, float)
        self.budget = int(budget)
        self.batch = max(1, int(batch))
        self._rng = np.random.default_rng(seed)
        self._seed = seed
        self.points: list[np.ndarray] = []
        self.scores: list[tuple] = []
        self._width = self.hi - self.lo

    @property
    def left(self) -> int:
        return self.budget - len(self.points)

    def first(self) -> list[np.ndarray]:
        """The first round's points."""
        d = len(self.lo)
        n = min(self.left, max(self.batch, 3 * d, int(round(FIRST_SHARE * self.budget))))
        if d == 1:
            pts = np.linspace(self.lo, self.hi, n) if n > 1 else (0.5 * (self.lo + self.hi))[None]
        else:
            from scipy.stats import qmc  # half a second to import: only a search pays it

            unit = qmc.LatinHypercube(d, seed=self._seed).random(max(n - 1, 1))[: n - 1]
            pts = np.vstack([0.5 * (self.lo + self.hi), qmc.scale(unit, self.lo, self.hi)]) if n > 1 \
                else (0.5 * (self.lo + self.hi))[None]
        return self._new(list(pts))

    def tell(self, points: list[np.ndarray], scores: list[tuple]) -> None:
        """The scores of points run (a failed run: a score below every other)."""
        self.points += [np.asarray(p, float) for p in points]
        self.scores += list(scores)

    def best(self) -> tuple[np.ndarray, tuple] | None:
        if not self.points:
            return None
        k = max(range(len(self.points)), key=lambda i: self.scores[i])
        return self.points[k], self.scores[k]

    def next(self) -> list[np.ndarray]:
        """The next round's points (empty when the budget is spent)."""
        if self.left <= 0 or not self.points:
            return []
        centre, _ = self.best()
        n = min(self.left, self.batch if self.batch > 1 else 2)
        for _ in range(64):      # each try halves the box; a few suffice unless the box is a point
            self._width = self._width / 2.0
            lo = np.maximum(self.lo, centre - self._width / 2.0)
            hi = np.minimum(self.hi, centre + self._width / 2.0)
            if len(self.lo) == 1:
                # evenly through the narrowed box, its ends left out (two at
                # least: one would be the box's centre, the best itself)
                pts = list(np.linspace(lo, hi, max(n, 2) + 2)[1:-1])
            else:
                from scipy.stats import qmc  # see first()

                unit = qmc.LatinHypercube(len(self.lo), seed=self._rng.integers(2**31)).random(n)
                pts = [lo + (hi - lo) * u for u in unit]
            found = self._new(pts)
            if found:
                return found[:n]
        return []

    def _new(self, pts: list[np.ndarray]) -> list[np.ndarray]:
        """The points not run yet (nearer than 1e-9 of the box to one run counts as run)."""
        seen = list(self.points)
        out = []
        scale = np.maximum(self.hi - self.lo, 1e-300)
        for p in pts:
            p = np.clip(np.asarray(p, float), self.lo, self.hi)
            if all(np.max(np.abs(p - q) / scale) > 1e-9 for q in seen):
                out.append(p)
                seen.append(p)
        return out
