"""A simulation that diverged: found in a batch of states, named, and its likely cause.

A run must not check, report or call complete what a simulation that blew
up made of its cables. Three signs show it (`Sign`):

- MuJoCo's own instability warnings (`mjWARN_BADQPOS`, `mjWARN_BADQVEL`,
  `mjWARN_BADQACC`: a NaN, infinite or huge position, velocity or
  acceleration). The simulation turns MuJoCo's automatic reset off
  (`cablecheck.run.loop`), so the bad values stay where they are instead of the
  cable silently jumping back to its routed shape, stops stepping at the
  first one and hands it on with its state (`Instability`);
- non-finite cable positions or generalized positions in a state;
- runaway positions: a cable point farther than `REACH_FACTOR` times the
  scene's reach from the scene's centre (the reach: the routed cables'
  extent, every cable's length, a free fall over the whole run, and how
  far the parts and the cables' held points have gone as the script moves
  them), moving faster between two checked steps than `RUNAWAY_SPEED` (and
  ten times the fastest held point of the script), or an element
  stretched past `STRETCH_LIMIT` times its rest length.

`DivergenceWatch.scan` looks at a batch of states at once (one stack of
the batch's cable points, array operations over all of them: no Python
loop per point or per state beyond gathering them) and returns the first
diverged state with a `PhysicsError`: the scene time, the cable (and
vertex) or body where it showed, and the likely cause (`Cause`, `likely_cause`):

- units: a size out of all proportion with the scene's cables (a motion
  travelling a hundred times the longest cable, a radius a hundred
  thousandth of its cable, a part a thousand times the cable's length),
  typically millimetre numbers in a metre scene or the reverse;
- a body teleported: the script moves a cable's held point faster than the
  simulation step can follow, even at the most substeps (`cablecheck.build.substeps`);
- stiffness against the timestep: a cable's bending needs a smaller step
  than the run takes, even at the most substeps;
- held against a part: at the last sound state (the routed start when the
  first state checked is already diverged: the settling blew up), within `PINCH_ELEMENTS`
  elements of where it diverged, the cable is both held (an end or clip on
  one body) and pressed into a part of another body, as MuJoCo collides it
  (a mesh as its convex hull): the hold and the contact fight until the
  cable gives (`held_pinch`, MuJoCo's own collision pass at that state);
- unknown, when none of these is found.

This module does not step the simulation, stop the run or write the
report (see `cablecheck.run.loop`, `cablecheck.run.runner`, `cablecheck.report.document`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from enum import Enum

import mujoco
import numpy as np

from cablecheck.build.built import Built, end_roll_body, vertex_body
from cablecheck.build.pinch import contacts_at, held_pinch
from cablecheck.scene.errors import written
from cablecheck.scene.records import Scene

BAD_WARNINGS = (mujoco.mjtWarning.mjWARN_BADQPOS, mujoco.mjtWarning.mjWARN_BADQVEL,
                mujoco.mjtWarning.mjWARN_BADQACC)
"""MuJoCo's warnings that mean the simulation is unstable (its values are
NaN, infinite or beyond mjMAXVAL)."""

REACH_FACTOR = 10.0
"""A cable point farther than this many times the scene's reach from its
centre has run away."""

RUNAWAY_SPEED = 1000.0
"""m/s: a cable point faster than this (and than ten times the script's
fastest held point) between two checked steps has run away: a cable whip's
tip stays below it, a simulation blowing up passes it within steps."""

STRETCH_LIMIT = 3.0
"""An element longer than this many times its rest length has run away (no
cable stretches to three times its length; a taut cable reports strain of
a few percent)."""

UNITS_RATIO = 100.0
"""A motion travelling more than this many times the longest cable, or a
radius below its cable's length over this squared, is out of proportion."""

PART_RATIO = 1000.0
"""A part spanning more than this many times the longest cable (or less
than its inverse) is out of proportion (floors are large, not this large)."""


class Sign(str, Enum):
    """What showed that the simulation diverged."""

    UNSTABLE = "mujoco-unstable"    # MuJoCo's instability warning
    NON_FINITE = "non-finite"       # NaN or infinite positions
    FAR = "runaway-far"             # a point beyond the scene's reach (value: its distance, m)
    FAST = "runaway-speed"          # a point faster than any cable (value: its speed, m/s)
    STRETCHED = "runaway-stretch"   # an element stretched out of all measure (value: length / rest length)


class Cause(str, Enum):
    """The likely cause of a divergence (`likely_cause`)."""

    UNITS = "units"
    TELEPORT = "teleport"
    STIFFNESS = "stiffness-timestep"
    PINCHED = "held-against-part"
    UNKNOWN = "unknown"


@dataclass(frozen=True)
class Instability:
    """MuJoCo's first instability warning of a simulation.

    Attributes:
      warning: its `mjtWarning` name, e.g. "mjWARN_BADQACC".
      index: MuJoCo's number for where: the qpos address (BADQPOS) or the
        degree of freedom (BADQVEL, BADQACC).
      t: scene time it was found at, seconds (negative while settling).
    """

    warning: str
    index: int
    t: float


@dataclass(frozen=True)
class PhysicsError:
    """Where and why a run's simulation diverged (times in seconds, lengths in metres).

    Attributes:
      t: scene time of the first diverged state (negative: while settling).
      step: the scene step of that state (0: the rest state after settling).
      settling: it diverged while settling, before t = 0.
      sign: what showed it.
      cable: the cable it showed in, or None.
      vertex: that cable's vertex (0 at its start), or None.
      body: the body it showed in (a scripted or mjcf body, or the cable's
        vertex body as MuJoCo names it), or None.
      warning: MuJoCo's instability warning, or None.
      value: the runaway measure (`Sign`: a distance from the scene's
        centre, metres; a speed, m/s; an element's length over its rest
        length), or None.
      cause: the likely cause.
      detail: the cause in words, with the key and the numbers behind it.
    """

    t: float
    step: int
    settling: bool
    sign: Sign
    cable: str | None
    vertex: int | None
    body: str | None
    warning: str | None
    value: float | None
    cause: Cause
    detail: str

    def message(self) -> str:
        """One line: when, where, what and the likely cause."""
        where = (f"cable {self.cable!r}" + (f" (vertex {self.vertex})" if self.vertex is not None else "")
                 if self.cable is not None else f"body {self.body!r}" if self.body is not None else "the model")
        if self.sign is Sign.UNSTABLE:
            what = f"MuJoCo found the simulation unstable ({self.warning})"
        elif self.sign is Sign.NON_FINITE:
            what = "positions became NaN or infinite"
        else:
            what = {Sign.FAR: "a point ran away to {:.4g} m from the scene",
                    Sign.FAST: "a point ran away at {:.4g} m/s",
                    Sign.STRETCHED: "an element stretched to {:.4g} times its length"}[self.sign].format(self.value)
        when = f"while settling (t = {self.t:.4g} s)" if self.settling else f"at t = {self.t:.4g} s"
        return f"the simulation diverged {when} in {where}: {what}; likely cause: {self.cause.value}: {self.detail}"


def _fmt(x: float) -> str:
    return f"{x:.4g}"



def _other_unit(scene: Scene, metres: float) -> str:
    """What the number as written would mean in the other unit."""
    written = metres / scene.scale
    if scene.units == "m":
        return f"as millimetres {_fmt(written)} mm = {_fmt(written / 1000)} m"
    return f"as metres {_fmt(written)} m = {_fmt(written * 1000)} mm"


def unit_outliers(scene: Scene, built: Built) -> list[tuple[float, str]]:
    """(how far out of proportion, the finding in words) for each size of the
    scene out of proportion with its cables, the worst first."""
    lengths = [c.length for c in built.cables]
    if not lengths:
        return []
    longest = max(lengths)
    out = []
    for i, m in enumerate(scene.motions):
        traj = m.trajectory
        pos = np.asarray(traj.body_pos, float) if traj is not None else np.zeros(0)
        if pos.size:
            travel = float(np.linalg.norm(pos.max(axis=0) - pos.min(axis=0), axis=-1).max())
            if travel > UNITS_RATIO * longest:
                out.append((travel / longest,
                            f"motion[{i}] moves {m.body or m.joint!r} {written(scene, travel)}, "
                            f"{_fmt(travel / longest)} times the longest cable ({written(scene, longest)}): "
                            f"mm and m values mixed? ({_other_unit(scene, travel)})"))
    for i, (c, cm) in enumerate(zip(scene.cables, built.cables)):
        if cm.length > UNITS_RATIO ** 2 * c.radius:
            out.append((cm.length / (UNITS_RATIO * c.radius),
                        f"cables[{i}].radius = {written(scene, c.radius)} is 1/{_fmt(cm.length / c.radius)} of "
                        f"its length ({written(scene, cm.length)}): mm and m values mixed? "
                        f"({_other_unit(scene, c.radius)})"))
    for i, p in enumerate(scene.parts):
        if p.shape in ("plane", "mesh") or not p.size:
            continue
        span = 2.0 * max(p.size)
        if span > PART_RATIO * longest or span * PART_RATIO < longest:
            ratio = max(span / longest, longest / span)
            out.append((ratio * UNITS_RATIO / PART_RATIO,
                        f"parts[{i}] ({p.name!r}) spans {written(scene, span)} against the longest cable's "
                        f"{written(scene, longest)}: mm and m values mixed? ({_other_unit(scene, span)})"))
    return sorted(out, key=lambda x: -x[0])


def likely_cause(built: Built, cable: str | None) -> tuple[Cause, str]:
    """The likely cause of a divergence that showed in `cable` (or in no
    cable), and the finding behind it (module docstring)."""
    scene = built.scene
    units = unit_outliers(scene, built)
    if units:
        return Cause.UNITS, units[0][1]
    sub = built.substeps
    if sub is not None and built.cables:
        names = [cable] if cable in sub.needed else list(sub.needed)
        # a part too fast for the step is named before running (tunnel_warnings)
        short = [n for n in names if sub.needed[n] < sub.step * (1 - 1e-9) and sub.reasons[n][0] != "contact"]
        if short:
            worst = min(short, key=lambda n: sub.needed[n])
            kind, speed, element = sub.reasons[worst]
            steps = f"(the scene's timestep {scene.timestep:.3g} s in {sub.count} substeps)"
            if kind == "speed":
                cm = next(c for c in built.cables if c.name == worst)
                bodies = sorted({a.body for a in cm.attachments if a.body != "world"})
                on = f" on {', '.join(repr(b) for b in bodies)}" if bodies else ""
                return Cause.TELEPORT, (
                    f"the script moves a held point of cable {worst!r}{on} at up to {written(scene, speed)}/s, "
                    f"{written(scene, speed * sub.step)} per simulation step of {sub.step:.3g} s "
                    f"{steps}, {_fmt(speed * sub.step / element)} of an element: the cable cannot follow "
                    f"(a body teleported); slow the motion or make scene.timestep <= "
                    f"{sub.needed[worst] * sub.count:.3g} s")
            defn = next(c for c in scene.cables if c.name == worst)
            return Cause.STIFFNESS, (
                f"cable {worst!r} (young {defn.young:.3g} Pa, elements of {written(scene, element)}) "
                f"needs a simulation step of {sub.needed[worst]:.3g} s and the run steps {sub.step:.3g} s "
                f"{steps}: lower scene.timestep to <= {sub.needed[worst] * sub.count:.3g} s, or the "
                f"stiffness, or use fewer segments")
    return Cause.UNKNOWN, ("no unit mix-up, script too fast for the step or stiffness beyond the step was "
                           "found; look at the contacts and the parts near that time in the recording")


class DivergenceWatch:
    """Finds the first diverged state of a run's batches (module docstring).

    `scan(states)` is called with each batch in order; it remembers the
    last state of the previous batch (for speeds) and the farthest the
    parts have gone (for the reach).

    Attributes:
      seconds: CPU seconds spent scanning so far (the calling thread's).
    """

    def __init__(self, built: Built, settle: float):
        self.built = built
        self.seconds = 0.0
        self.names = [c.name for c in built.cables]
        self.counts = np.array([c.count for c in built.cables], int)
        self.starts = np.concatenate([[0], np.cumsum(self.counts)])
        scene = built.scene
        routed = (np.concatenate([c.routed for c in built.cables]) if built.cables else np.zeros((1, 3)))
        self.centre = 0.5 * (routed.min(axis=0) + routed.max(axis=0))
        duration = settle + scene.duration
        fall = 0.5 * 9.81 * duration ** 2 if scene.effects.gravity else 0.0
        self.lengths = float(sum(c.length for c in built.cables))
        self.reach = float(np.linalg.norm(routed - self.centre, axis=1).max() + self.lengths + fall)
        speeds = [r[1] for r in built.substeps.reasons.values()] if built.substeps is not None else []
        self.speed = max(RUNAWAY_SPEED, 10.0 * max(speeds, default=0.0))
        self._last: tuple[float, np.ndarray] | None = None
        # the last sound state's qpos, for `held_pinch`: until a state is scanned, the routed start
        # (a run that diverges while settling has no checked state before it)
        self._last_qpos: np.ndarray | None = np.asarray(built.qpos0, float)
        # held vertices in the batch's stacked points; each element's rest length (inf across cables)
        self.held = np.array([self.starts[i] + a.vertex for i, c in enumerate(built.cables)
                              for a in c.attachments], int)
        rest = [np.append(np.diff(np.asarray(c.rest_s, float)), np.inf) for c in built.cables]
        self.rest = np.concatenate(rest)[:-1] if rest else np.zeros(0)
        self._vertex_of, self._cable_of = self._vertex_bodies()
        self._sound: np.ndarray | None = None   # qpos of the state before the diverged one, when known

    def _vertex_bodies(self) -> tuple[dict[int, int], dict[int, int]]:
        """Body id -> vertex index and -> cable index, for the cables' vertex bodies."""
        m = self.built.model
        vertex, cable = {}, {}
        ids = getattr(m, "flex_vertbodyid", None)
        if ids is None:
            return vertex, cable
        for i, c in enumerate(self.built.cables):
            for k, b in enumerate(np.asarray(ids[c.vert_adr:c.vert_adr + c.count]).tolist()):
                if m.body(b).name == vertex_body(c.name, k):   # held vertices ride their body
                    vertex[b], cable[b] = k, i
        return vertex, cable

    def scan(self, states: list) -> tuple[int, PhysicsError] | None:
        """The first diverged state of `states` (its index in the batch) and
        what diverged, or None when all are sound."""
        t = time.thread_time()
        try:
            return self._scan(states)
        finally:
            self.seconds += time.thread_time() - t

    def _scan(self, states: list) -> tuple[int, PhysicsError] | None:
        if not states:
            return None
        unstable = [i for i, s in enumerate(states) if getattr(s, "unstable", None) is not None]
        first = unstable[0] if unstable else len(states)
        if first == 0:
            return 0, self._unstable(states[0])
        pts = np.stack([np.concatenate(s.cables) if s.cables else np.zeros((0, 3)) for s in states[:first]])
        finite = np.isfinite(pts).all(axis=2)                                    # (B, N)
        qfinite = np.array([np.isfinite(s.qpos).all() for s in states[:first]], bool)
        bad_nf = ~finite.all(axis=1) | ~qfinite
        # the reach grows with how far the parts have gone
        poses = np.stack([s.part_poses[:, :3, 3] for s in states[:first]])
        part_d = np.linalg.norm(poses - self.centre, axis=2) if poses.size else np.zeros((len(pts), 0))
        part_d = np.where(np.isfinite(part_d), part_d, 0.0)
        held = np.linalg.norm(pts[:, self.held] - self.centre, axis=2) if len(self.held) else part_d[:, :0]
        held = np.where(np.isfinite(held), held, 0.0)
        moved = np.maximum(part_d.max(axis=1, initial=0.0), held.max(axis=1, initial=0.0)) + self.lengths
        reach = np.maximum.accumulate(np.maximum(self.reach, moved))
        self.reach = float(reach[-1])
        dist = np.linalg.norm(np.where(finite[..., None], pts, self.centre) - self.centre, axis=2)
        far = dist > REACH_FACTOR * reach[:, None]
        fast, speed = self._fast(states[:first], pts, finite)
        with np.errstate(invalid="ignore"):
            stretch = np.linalg.norm(np.diff(pts, axis=1), axis=2) / self.rest      # (B, N - 1)
        long = np.isfinite(stretch) & (stretch > STRETCH_LIMIT)
        bad = bad_nf | far.any(axis=1) | fast.any(axis=1) | long.any(axis=1)
        hit = np.flatnonzero(bad)
        k = int(hit[0]) if len(hit) else first
        if k == len(states):
            self._remember(states, pts)
            return None
        state = states[k]
        self._sound = states[k - 1].qpos if k > 0 else self._last_qpos
        if k < first:
            if bad_nf[k]:
                cols = np.flatnonzero(~finite[k])
                error = self._error(state, Sign.NON_FINITE, int(cols[0]) if len(cols) else None, None)
            elif far[k].any():
                col = int(np.argmax(np.where(far[k], dist[k], -1.0)))
                error = self._error(state, Sign.FAR, col, float(dist[k, col]))
            elif long[k].any():
                col = int(np.argmax(np.where(long[k], stretch[k], -1.0)))
                error = self._error(state, Sign.STRETCHED, col, float(stretch[k, col]))
            else:
                col = int(np.argmax(np.where(fast[k], speed[k], -1.0)))
                error = self._error(state, Sign.FAST, col, float(speed[k, col]))
        else:
            error = self._unstable(state)
        return k, error

    def _fast(self, states: list, pts: np.ndarray, finite: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(B, N) points faster than the runaway speed since the state before, and their speeds."""
        if not len(states):
            return np.zeros((0, 0), bool), np.zeros((0, 0))
        t = np.array([s.t for s in states], float)
        prev_t = np.concatenate([[self._last[0] if self._last else np.nan], t[:-1]])
        prev = np.concatenate([self._last[1][None] if self._last is not None and
                               self._last[1].shape == pts.shape[1:] else np.full((1,) + pts.shape[1:], np.nan),
                               pts[:-1]])
        dt = t - prev_t
        with np.errstate(invalid="ignore"):
            speed = np.linalg.norm(pts - prev, axis=2) / np.where(dt > 0, dt, np.nan)[:, None]
        speed = np.where(finite & np.isfinite(speed), speed, 0.0)
        return speed > self.speed, speed

    def _remember(self, states: list, pts: np.ndarray) -> None:
        if len(pts):
            self._last = (states[len(pts) - 1].t, pts[-1].copy())
            self._last_qpos = states[len(pts) - 1].qpos

    def _cable_at(self, col: int | None) -> tuple[str | None, int | None]:
        if col is None or not len(self.names):
            return None, None
        i = int(np.searchsorted(self.starts, col, side="right") - 1)
        return self.names[i], int(col - self.starts[i])

    def _error(self, state, sign: Sign, col: int | None, value: float | None) -> PhysicsError:
        cable, vertex = self._cable_at(col)
        if cable is None and sign is Sign.NON_FINITE:    # positions fine, qpos not: the first bad one's body
            bad = np.flatnonzero(~np.isfinite(state.qpos))
            return self._at_body(state.t, state.step, sign, self._qpos_body(int(bad[0])) if len(bad) else None,
                                 None, value)
        body = None
        if cable is not None:
            i = self.names.index(cable)
            c = self.built.cables[i]
            ids = getattr(self.built.model, "flex_vertbodyid", None)
            if ids is not None:
                m = self.built.model
                b = int(ids[c.vert_adr + vertex])
                if m.body(b).name == end_roll_body(c.name):     # a clamped end rides its holder's child
                    b = int(m.body_parentid[b])
                body = m.body(b).name or "world"
        cause, detail = self._cause(cable, vertex)
        return PhysicsError(state.t, state.step, False, sign, cable, vertex, body, None, value, cause, detail)

    def _cause(self, cable: str | None, vertex: int | None) -> tuple[Cause, str]:
        """`likely_cause`, and where that finds none, a held point pressed into a part (`held_pinch`)."""
        cause, detail = likely_cause(self.built, cable)
        if cause is Cause.UNKNOWN and cable is not None and self._sound is not None:
            pinch = held_pinch(self.built, contacts_at(self.built, self._sound), self.names.index(cable), vertex)
            if pinch is not None:
                return Cause.PINCHED, (f"{pinch}: the hold and the contact fight until the cable gives; keep "
                                       "the held point clear of that part over the program (move the hold or the "
                                       "part, or change the motion)")
        return cause, detail

    def _qpos_body(self, adr: int) -> int:
        m = self.built.model
        j = int(np.searchsorted(m.jnt_qposadr, adr, side="right") - 1)
        return int(m.jnt_bodyid[max(j, 0)])

    def _at_body(self, t: float, step: int, sign: Sign, body: int | None, warning: str | None,
                 value: float | None, settling: bool = False) -> PhysicsError:
        """The error where MuJoCo's body `body` diverged: its cable and vertex, or its name."""
        cable = vertex = name = None
        if body is not None:
            name = self.built.model.body(body).name
            if body in self._cable_of:
                cable, vertex = self.names[self._cable_of[body]], self._vertex_of[body]
            else:
                scene_names = {v: k for k, v in self.built.body_ids.items()}
                name = scene_names.get(body, name)
        cause, detail = self._cause(cable, vertex)
        return PhysicsError(t, step, settling, sign, cable, vertex, name, warning, value, cause, detail)

    def _unstable(self, state) -> PhysicsError:
        """The error of MuJoCo's instability warning carried by `state`."""
        u = state.unstable
        m = self.built.model
        if u.warning == mujoco.mjtWarning.mjWARN_BADQPOS.name:
            body = self._qpos_body(u.index) if 0 <= u.index < m.nq else None
        else:
            body = int(m.dof_bodyid[u.index]) if 0 <= u.index < m.nv else None
        return self._at_body(u.t, state.step, Sign.UNSTABLE, body, u.warning, None, settling=u.t < 0)
