"""An independent reference for static scenes (issue 25, item 6, static part).

Hypothesis draws whole static scenes and runs them through the product as a
user would (a TOML scene file, `cablecheck.scene.load_scene`, `cablecheck.run.runner.run_scene`
writing a JSON report; `dynamics = false`, `duration = 0`, method `exact`, no
validation, so no MuJoCo model is built). Each scene has every primitive
(box, sphere, cylinder, capsule, ellipsoid) and convex meshes (a box,
icosphere or cylinder written as STL) at drawn poses, placed next to 2-3
cables (straight or through via points, with an occasional clip) so that
many pairs come below the clearance, some overlapping, some beside an end.
Cable ends and clips ride `world` or `[[bodies]]` bodies at drawn poses,
and so do parts; some ends name the part they are fastened to (`part`).
The same scene is written in m or in mm (every length times 1000, meshes
through `scale`) and placed at the origin or 1 km from it.

The reference is computed here from the numbers written into the scene file,
never with the product's distance code: the cables' centrelines are the
report's `rest_points` (the routed shape: nothing moves), and per element
(the segment between consecutive body centres) and part the least signed
surface distance less the radius is

- sphere, capsule: closed form (point-segment, segment-segment);
- box, cylinder, ellipsoid, convex mesh: the signed distance of a convex
  body is convex along a segment, so a golden-section search over the
  segment's parameter, run to machine precision (every value it returns is
  the true distance of a point of the segment, so it never undershoots),
  of a closed-form point signed distance (box, cylinder), Eberly's
  bisection to machine precision (ellipsoid), or exact point-triangle
  distances outside and the face planes inside (convex mesh);

and cable-cable is the segment-segment distance less r1 + r2. Elements that
provably stay beyond the clearance (their distance to a bounding sphere) are
not searched.

What is asserted (the issue's "Done when"): an element lies in an
attachment window of a (cable, part) when its rest arc-length midpoint does
(windows from `cablecheck.run.stepcheck.attachment_exclusions`, their extent checked
here against `check.attach_zone` radii either side of the held vertices,
widened to whole elements). Then for every cable-part pair

- the least distance over the elements outside its windows is reported in
  `pairs` at that distance (1e-9 m, in scene units) when below the
  clearance, and not reported when above it;
- the least distance over each window's elements is listed in `excused`
  at that distance when below the clearance, and nothing else is listed;
- a part is excused by an end or clip only when the scene names it
  there (`part`), or, when the scene names none, when it rides the end's
  body and a held vertex lies within the cable radius + clearance of it
  (measured here); conversely every such part is excused;

and every cable-cable pair below the clearance is reported at its distance,
none above it.

Three product bugs were found this way; each has a test of its own at the
end of this file (a strict xfail while it stands, and the drawn scenes step
around it so the property test stays green and still checks everything
else):

- a part frame within 1e-6 of its body's is measured where MuJoCo's
  compiler snaps it (drawn frames are kept 1e-5 away or put exactly on it);
- an element through a mesh was measured at the deepest of nine samples
  (fixed: cablecheck.checker.segments searches between them; drawn meshes are convex,
  and their depths are now held to the reference like any other);
- an ellipsoid whose two shortest semi-axes are equal read a wrong depth
  next to its centre (fixed: cablecheck.checker.primitives solves for the root
  shifted by the smallest squared semi-axis; drawn ellipsoids have two or
  three equal semi-axes now and then).

A normal run draws 80 scenes (and checks the reference itself on 40 drawn
segments), about 20 s on one core; under CI the draws are derandomised
(tests/conftest.py). A longer local run takes the `long` hypothesis profile
(1000 examples each, about 3 min), e.g.

    .venv/bin/python -m pytest tests/test_reference_static.py -p no:xdist --hypothesis-profile=long
    HYPOTHESIS_PROFILE=long .venv/bin/python -m pytest tests/test_reference_static.py -p no:xdist

(the profile's `max_examples` then replaces this file's CI count).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
import trimesh
from hypothesis import HealthCheck, event, given, settings, strategies as st
from scipy.spatial.transform import Rotation

from cablecheck.build.static import build_static
from cablecheck.run.runner import RunOptions, run_scene
from cablecheck.run.stepcheck import attachment_exclusions
from cablecheck.scene.load import load_scene


def examples(ci: int) -> int:
    """`ci` examples, or the loaded profile's count when it asks for more than
    hypothesis' default of 100 (the `long` profile)."""
    return settings.default.max_examples if settings.default.max_examples > 100 else ci

TOL = 1e-9
"""Distance tolerance, metres."""

UNIT = {"m": 1.0, "mm": 1e-3}
SHAPES = ("box", "sphere", "cylinder", "capsule", "ellipsoid", "mesh")
MESHES = ("box", "icosphere", "cylinder")
FAR = (1000.0, -1500.0, 700.0)
INVPHI = (math.sqrt(5.0) - 1.0) / 2.0
SNAP = 1e-5
"""Drawn part frames within this (quaternion elements, metres) of their body's
frame are put on it: MuJoCo's compiler, and the product after it, takes
frames within 1e-6 as the body's own (a known product bug, tested apart)."""


# --------------------------------------------------------------------------------------------
# the reference geometry (metres, everything from the scene file's numbers)

def rot(euler) -> np.ndarray:
    """Rotation of MuJoCo's default euler sequence (intrinsic x, y, z), degrees."""
    return Rotation.from_euler("XYZ", np.asarray(euler, float), degrees=True).as_matrix()


def point_segment(p, a, b) -> float:
    d = b - a
    dd = float(d @ d)
    t = 0.0 if dd == 0.0 else min(1.0, max(0.0, float((p - a) @ d) / dd))
    return float(np.linalg.norm(a + t * d - p))


def segment_segment(p0, p1, q0, q1) -> float:
    """Least distance between two segments: the four end-to-segment
    distances, and the two lines' closest points when both fall inside."""
    best = min(point_segment(p0, q0, q1), point_segment(p1, q0, q1),
               point_segment(q0, p0, p1), point_segment(q1, p0, p1))
    u, v, w = p1 - p0, q1 - q0, p0 - q0
    a, b, c, d, e = u @ u, u @ v, v @ v, u @ w, v @ w
    den = a * c - b * b
    if den > 1e-14 * a * c:
        s = (b * e - c * d) / den
        t = (a * e - b * d) / den
        if 0.0 < s < 1.0 and 0.0 < t < 1.0:
            for _ in range(3):    # alternate projections: each step only shortens the distance
                t = min(1.0, max(0.0, float((p0 + s * u - q0) @ v) / c))
                s = min(1.0, max(0.0, float((q0 + t * v - p0) @ u) / a))
            best = min(best, float(np.linalg.norm(p0 + s * u - q0 - t * v)))
    return best


def least_along(f) -> float:
    """The least value over t in [0, 1] of a convex f: golden section to
    machine precision, and both ends. Every value is f at some t, so the
    answer never undershoots the true least value."""
    a, b = 0.0, 1.0
    c, d = b - INVPHI * (b - a), a + INVPHI * (b - a)
    fc, fd = f(c), f(d)
    best = min(f(0.0), f(1.0), fc, fd)
    for _ in range(200):
        if fc <= fd:
            b, d, fd = d, c, fc
            c = b - INVPHI * (b - a)
            fc = f(c)
        else:
            a, c, fc = c, d, fd
            d = a + INVPHI * (b - a)
            fd = f(d)
        best = min(best, fc, fd)
        if b - a < 1e-16:
            break
    return best


def box_sdf(p, h) -> float:
    q = [abs(p[0]) - h[0], abs(p[1]) - h[1], abs(p[2]) - h[2]]
    m = max(q)
    if m <= 0.0:
        return m
    return math.sqrt(sum(x * x for x in q if x > 0.0))


def cylinder_sdf(p, radius, half) -> float:
    dr = math.hypot(p[0], p[1]) - radius
    dz = abs(p[2]) - half
    if dr <= 0.0 and dz <= 0.0:
        return max(dr, dz)
    return math.hypot(max(dr, 0.0), max(dz, 0.0))


def _bisect(f, lo: float, hi: float) -> float:
    """The root of a decreasing f in [lo, hi] (f(lo) >= 0 >= f(hi)), to the last bit."""
    for _ in range(2000):
        mid = 0.5 * (lo + hi)
        if mid <= lo or mid >= hi:
            break
        if f(mid) > 0.0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def ellipsoid_sdf(p, axes) -> float:
    """Signed distance to the ellipsoid of semi-axes `axes` (Eberly's
    construction): the closest point is x_i = e_i^2 y_i / (s + c_i) with
    c_i = e_i^2 - m^2 (m the shortest semi-axis) and s > 0 the root of
    F(s) = sum (e_i y_i / (s + c_i))^2 - 1, found by bisection in s itself
    (no cancellation near the pole at s = 0, deep inside). A point inside
    on the plane of the shortest axes past the medial region (F(0) <= 0)
    has its closest point off that plane (s = 0)."""
    e = [float(x) for x in axes]
    y = [abs(float(x)) for x in p]
    g = sum((yi / ei) ** 2 for yi, ei in zip(y, e)) - 1.0
    m = min(e)
    c = [(ei - m) * (ei + m) for ei in e]
    pole = [i for i in range(3) if c[i] == 0.0]
    if max(y) < 1e-100 * m:     # at the centre (to far below any rounding; subnormals would spoil the bisection)
        return -m

    def F(s):
        return sum((e[i] * y[i] / (s + c[i])) ** 2 for i in range(3) if y[i] > 0.0) - 1.0

    def closest(s):
        return [e[i] * e[i] * y[i] / (s + c[i]) if y[i] > 0.0 else 0.0 for i in range(3)]

    if g >= 0.0:
        return math.dist(closest(_bisect(F, m * m, m * m + math.sqrt(sum((ei * yi) ** 2 for ei, yi in zip(e, y))))), y)
    if any(y[i] > 0.0 for i in pole):
        return -math.dist(closest(_bisect(F, max(m * y[i] for i in pole), m * m)), y)
    if F(0.0) > 0.0:
        return -math.dist(closest(_bisect(F, 0.0, m * m)), y)
    x = closest(0.0)
    rest = 1.0 - sum((x[i] / e[i]) ** 2 for i in range(3) if i not in pole)
    return -math.sqrt(sum((x[i] - y[i]) ** 2 for i in range(3) if i not in pole) + m * m * max(rest, 0.0))


@dataclass
class ConvexMesh:
    """A closed convex triangle mesh in its own frame: face planes (outward
    unit normals) and triangles."""

    tri: np.ndarray   # (F, 3, 3)
    n: np.ndarray     # (F, 3)
    off: np.ndarray   # (F,)

    @classmethod
    def of(cls, vertices: np.ndarray, faces: np.ndarray) -> ConvexMesh:
        tri = vertices[faces]
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        area = np.linalg.norm(n, axis=1)
        keep = area > 1e-14 * np.max(area)
        tri, n = tri[keep], n[keep] / area[keep, None]
        centre = vertices.mean(axis=0)
        flip = np.einsum("ij,ij->i", n, tri.mean(axis=1) - centre) < 0
        n[flip] *= -1
        off = np.einsum("ij,ij->i", n, tri[:, 0])
        assert np.all(vertices @ n.T <= off + 1e-12 * np.abs(vertices).max()), "the mesh is not convex"
        return cls(tri, n, off)

    def sdf(self, p: np.ndarray) -> float:
        plane = self.n @ p - self.off
        m = float(plane.max())
        if m <= 0.0:
            return m      # inside a convex polytope: the nearest face plane
        return float(point_triangles(p, self.tri).min())


def point_triangles(p: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """(F,) distances from p to each triangle: to its plane where the
    projection falls inside it, else to its nearest edge."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    n = np.cross(b - a, c - a)
    nn = np.einsum("ij,ij->i", n, n)
    inside = np.ones(len(tri), bool)
    for u, v in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("ij,ij->i", np.cross(v - u, p - u), n) >= 0.0
    plane = np.abs(np.einsum("ij,ij->i", p - a, n)) / np.sqrt(nn)
    edges = []
    for u, v in ((a, b), (b, c), (c, a)):
        d = v - u
        t = np.clip(np.einsum("ij,ij->i", p - u, d) / np.einsum("ij,ij->i", d, d), 0.0, 1.0)
        edges.append(np.linalg.norm(u + t[:, None] * d - p, axis=1))
    return np.where(inside, plane, np.minimum.reduce(edges))


@dataclass
class RefPart:
    """A part placed at t = 0 in the reference's world (the scene's, less the offset), metres."""

    name: str
    shape: str
    size: np.ndarray
    rot: np.ndarray
    centre: np.ndarray
    body: str
    keepout: bool
    mesh: ConvexMesh | None = None
    bound: float = 0.0      # radius of a sphere about `centre` holding the part

    def local(self, x: np.ndarray) -> np.ndarray:
        return self.rot.T @ (x - self.centre)

    def point_sdf(self, x: np.ndarray) -> float:
        if self.shape == "sphere":
            return float(np.linalg.norm(x - self.centre)) - self.size[0]
        if self.shape == "capsule":
            axis = self.rot[:, 2] * self.size[1]
            return point_segment(x, self.centre - axis, self.centre + axis) - self.size[0]
        return self._local_sdf(self.local(x))

    def _local_sdf(self, q) -> float:
        if self.shape == "box":
            return box_sdf(q, self.size)
        if self.shape == "cylinder":
            return cylinder_sdf(q, self.size[0], self.size[1])
        if self.shape == "ellipsoid":
            return ellipsoid_sdf(q, self.size)
        return self.mesh.sdf(q)

    def segment_sdf(self, a: np.ndarray, b: np.ndarray) -> float:
        """Least signed distance from the segment ab (world) to the part's surface."""
        if self.shape == "sphere":
            return point_segment(self.centre, a, b) - self.size[0]
        if self.shape == "capsule":
            axis = self.rot[:, 2] * self.size[1]
            return segment_segment(a, b, self.centre - axis, self.centre + axis) - self.size[0]
        la, lb = self.local(a), self.local(b)
        d = lb - la
        return least_along(lambda t: self._local_sdf(la + t * d))


# --------------------------------------------------------------------------------------------
# drawn scenes (metres, near the origin; written with units and offset)

@dataclass
class Anchor:
    body: str
    world: np.ndarray          # the held point, world (less the offset)
    hold: str = "clamp"
    named: tuple[str, ...] = ()


@dataclass
class CableSpec:
    name: str
    radius: float
    start: Anchor
    end: Anchor
    via: list[np.ndarray]
    clips: list[Anchor]
    segments: int | None


@dataclass
class PartSpec:
    name: str
    shape: str
    body: str
    pos: np.ndarray            # in its body's frame
    euler: np.ndarray          # in its body's frame, degrees
    size: list[float] = field(default_factory=list)     # MuJoCo's sizes (primitives)
    mesh: str = ""             # mesh kind
    mesh_size: list[float] = field(default_factory=list)
    keepout: bool = False


@dataclass
class SceneSpec:
    clearance: float
    bodies: dict[str, tuple[np.ndarray, np.ndarray]]    # name: (pos, euler), world less offset
    cables: list[CableSpec]
    parts: list[PartSpec]

    def body_pose(self, body: str) -> tuple[np.ndarray, np.ndarray]:
        if body == "world":
            return np.eye(3), np.zeros(3)
        pos, euler = self.bodies[body]
        return rot(euler), np.asarray(pos, float)


def floats(lo, hi):
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False)


def vec(lo, hi):
    return st.tuples(floats(lo, hi), floats(lo, hi), floats(lo, hi)).map(lambda v: np.array(v, float))


def unit_vectors():
    return vec(-1.0, 1.0).map(lambda v: v / np.linalg.norm(v) if np.linalg.norm(v) > 1e-3 else np.array([1.0, 0, 0]))


@st.composite
def scenes(draw) -> SceneSpec:
    clearance = draw(floats(0.004, 0.03))
    nb = draw(st.integers(0, 2))
    bodies = {f"b{i}": (draw(vec(-0.1, 0.1)), draw(vec(-180.0, 180.0))) for i in range(nb)}
    body_names = ["world", *bodies]
    cables = []
    for c in range(draw(st.integers(2, 3))):
        radius = draw(floats(0.002, 0.008))
        start = draw(vec(-0.12, 0.12))
        end = start + draw(unit_vectors()) * draw(floats(0.12, 0.3))
        if cables and draw(st.booleans()):     # crossing or passing an earlier cable within about the clearance
            other = draw(st.sampled_from(cables))
            u = draw(floats(0.1, 0.9))
            at = other.start.world + u * (other.end.world - other.start.world)
            side = draw(unit_vectors()) * draw(floats(0.0, 1.5)) * (radius + other.radius + clearance)
            across = draw(unit_vectors()) * draw(floats(0.06, 0.15))
            start, end = at + side - across, at + side + across
        via = []
        for k in range(draw(st.integers(0, 2))):
            u = (k + 1) / 3.0
            via.append(start + u * (end - start) + draw(vec(-0.05, 0.05)))
        route = [start, *via, end]
        if min(np.linalg.norm(np.diff(route, axis=0), axis=1)) < 8 * radius:
            via = []
            route = [start, end]
        clips = []
        if draw(st.integers(0, 3)) == 0:
            k = draw(st.integers(0, len(route) - 2))
            u = draw(floats(0.35, 0.65))
            clips.append(Anchor(draw(st.sampled_from(body_names)), route[k] + u * (route[k + 1] - route[k])
                                + draw(vec(-0.01, 0.01)), draw(st.sampled_from(["clamp", "pin"]))))
        need = max(2, len(route) - 1 + len(clips))
        segments = draw(st.one_of(st.none(), st.integers(need, max(need, 20))))
        cables.append(CableSpec(
            f"c{c}", radius,
            Anchor(draw(st.sampled_from(body_names)), start, draw(st.sampled_from(["clamp", "clamp", "pin", "free"]))),
            Anchor(draw(st.sampled_from(body_names)), end, draw(st.sampled_from(["clamp", "clamp", "pin"]))),
            via, clips, segments))
    spec = SceneSpec(clearance, bodies, cables, [])
    route_mean = np.mean([p for c in cables for p in (c.start.world, *c.via, c.end.world)], axis=0)
    for k in range(draw(st.integers(3, 7))):
        shape = draw(st.sampled_from(SHAPES))
        cable = draw(st.sampled_from(cables))
        anchors = [cable.start, cable.end, *cable.clips]
        if draw(st.booleans()):                       # beside (or on) an end or a clip
            anchor = draw(st.sampled_from(anchors))
            at = anchor.world
            body = anchor.body if draw(st.integers(0, 2)) else draw(st.sampled_from(body_names))
        else:                                         # beside some place along the route
            route = [cable.start.world, *cable.via, cable.end.world]
            j = draw(st.integers(0, len(route) - 2))
            at = route[j] + draw(floats(0.0, 1.0)) * (route[j + 1] - route[j])
            body = draw(st.sampled_from(body_names))
        size, mesh, mesh_size = [], "", []
        if shape == "box":
            size = [draw(floats(0.003, 0.04)) for _ in range(3)]
        elif shape == "sphere":
            size = [draw(floats(0.003, 0.04))]
        elif shape in ("cylinder", "capsule"):
            size = [draw(floats(0.003, 0.03)), draw(floats(0.003, 0.04))]
        elif shape == "ellipsoid":
            size = [draw(floats(0.003, 0.04)) for _ in range(3)]
            # two or three semi-axes equal, now and then (a ball or a spheroid)
            k1, k2, k3 = draw(st.permutations(range(3)))
            equal = draw(st.sampled_from(["none", "none", "two", "three"]))
            if equal != "none":
                size[k2] = size[k1]
            if equal == "three":
                size[k3] = size[k1]
        else:
            mesh = draw(st.sampled_from(MESHES))
            mesh_size = [draw(floats(0.004, 0.04)) for _ in range(3 if mesh == "box" else 2)]
        extent = max(size or mesh_size)
        centre = at + draw(unit_vectors()) * draw(floats(0.0, 1.6)) * (extent + cable.radius + clearance)
        r_b, p_b = spec.body_pose(body)
        euler = draw(vec(-180.0, 180.0))
        pos = r_b.T @ (centre - p_b)
        # no frame within SNAP of its body's but off it (see test_a_frame_next_to_its_body_is_where_the_scene_puts_it)
        q = Rotation.from_euler("XYZ", euler, degrees=True).as_quat()
        if min(np.abs(q - (0, 0, 0, 1)).max(), np.abs(q + (0, 0, 0, 1)).max()) < SNAP:
            euler = np.zeros(3)
        if not euler.any():
            if body != "world" and np.abs(pos).max() < SNAP:
                pos = np.zeros(3)
            elif body == "world" and np.abs(pos - route_mean).max() < SNAP:
                pos = route_mean
        spec.parts.append(PartSpec(f"{draw(st.sampled_from(['jig', 'frame']))}/p{k}", shape, body, pos, euler,
                                   size, mesh, mesh_size, draw(st.integers(0, 9)) == 0))
    names = [p.name for p in spec.parts]
    for cable in cables:
        for anchor in (cable.start, cable.end, *cable.clips):
            if anchor.hold != "free" and draw(st.integers(0, 4)) == 0:
                paths = sorted({n.split("/")[0] for n in names})
                anchor.named = tuple(draw(st.lists(st.sampled_from([*names, *paths]), min_size=1,
                                                   max_size=2, unique=True)))
    return spec


# --------------------------------------------------------------------------------------------
# writing the scene file

def _num(x: float) -> str:
    return repr(float(x))


def _vec(v) -> str:
    return "[" + ", ".join(_num(x) for x in v) + "]"


def write_mesh(spec: PartSpec, path: Path) -> None:
    """A convex mesh in metres: the hull of the kind's vertices rounded to
    single precision (as STL stores them), so it stays exactly convex."""
    if spec.mesh == "box":
        m = trimesh.creation.box(extents=2 * np.asarray(spec.mesh_size))
    elif spec.mesh == "icosphere":
        m = trimesh.creation.icosphere(subdivisions=1, radius=spec.mesh_size[0])
    else:
        m = trimesh.creation.cylinder(radius=spec.mesh_size[0], height=2 * spec.mesh_size[1], sections=10)
    v = np.asarray(m.vertices, np.float32).astype(float)
    trimesh.convex.convex_hull(v).export(path)


def write_scene(spec: SceneSpec, folder: Path, units: str, offset) -> Path:
    k = 1.0 / UNIT[units]
    off = np.asarray(offset, float)

    def world(p):
        return _vec((off + p) * k)

    def local(p):
        return _vec(np.asarray(p) * k)

    def anchor(a: Anchor, key: str = "") -> str:
        r_b, p_b = spec.body_pose(a.body)
        pos = world(a.world) if a.body == "world" else local(r_b.T @ (a.world - p_b))
        items = [f'body = "{a.body}"', f"pos = {pos}", f'hold = "{a.hold}"']
        if a.named:
            items.append("part = [" + ", ".join(f'"{n}"' for n in a.named) + "]")
        return "{ " + ", ".join(items) + " }"

    out = [f'[scene]\nname = "reference"\nunits = "{units}"\nduration = 0.0\n',
           "[effects]\ndynamics = false\n",
           f'[check]\nmethod = "exact"\nclearance = {_num(spec.clearance * k)}\nvalidate = false\n']
    for name, (pos, euler) in spec.bodies.items():
        out.append(f'[[bodies]]\nname = "{name}"\npos = {world(pos)}\neuler = {_vec(euler)}\n')
    for i, p in enumerate(spec.parts):
        text = (f'[[parts]]\nname = "{p.name}"\nbody = "{p.body}"\nshape = "{p.shape}"\n'
                f"pos = {world(p.pos) if p.body == 'world' else local(p.pos)}\neuler = {_vec(p.euler)}\n")
        if p.shape == "mesh":
            file = folder / f"mesh{i}.stl"
            write_mesh(p, file)
            text += f'file = "{file.name}"\n' + (f"scale = {_num(k)}\n" if k != 1.0 else "")
        else:
            text += f"size = {local(p.size)}\n"
        if p.keepout:
            text += "keepout = true\n"
        out.append(text)
    for c in spec.cables:
        text = (f'[[cables]]\nname = "{c.name}"\nradius = {_num(c.radius * k)}\n'
                f"start = {anchor(c.start)}\nend = {anchor(c.end)}\n")
        if c.via:
            text += "via = [" + ", ".join(world(v) for v in c.via) + "]\n"
        if c.clips:
            text += "clips = [" + ", ".join(anchor(a) for a in c.clips) + "]\n"
        if c.segments is not None:
            text += f"segments = {c.segments}\n"
        out.append(text)
    path = folder / f"scene-{units}.toml"
    path.write_text("\n".join(out))
    return path


def reference_parts(spec: SceneSpec, folder: Path) -> dict[str, RefPart]:
    """Every part placed at t = 0 from the numbers written (meshes read back from their files)."""
    out = {}
    for i, p in enumerate(spec.parts):
        r_b, p_b = spec.body_pose(p.body)
        r = r_b @ rot(p.euler)
        centre = p_b + r_b @ p.pos
        mesh = None
        if p.shape == "mesh":
            m = trimesh.load(folder / f"mesh{i}.stl", force="mesh", process=False)
            v = np.asarray(m.vertices, float)
            mesh = ConvexMesh.of(v, np.asarray(m.faces))
            bound = float(np.linalg.norm(v, axis=1).max())
        else:
            bound = float(np.linalg.norm(p.size)) if p.shape in ("box", "ellipsoid") else sum(p.size)
        out[p.name] = RefPart(p.name, p.shape, np.asarray(p.size, float), r, centre, p.body, p.keepout, mesh,
                              bound)
    return out


def covers(pattern: str, name: str) -> bool:
    return name == pattern or name.startswith(pattern + "/")


# --------------------------------------------------------------------------------------------
# the reference distances

def element_distances(part: RefPart, pts: np.ndarray, radius: float, horizon: float) -> tuple[np.ndarray, np.ndarray]:
    """Per element, the exact least signed distance less the radius, or (for
    elements provably beyond `horizon`) a lower bound above it; and what the
    product may answer at most: the same (an element through a convex mesh
    is measured at its deepest point too: see
    test_a_segment_through_a_mesh_is_measured_at_its_deepest_point)."""
    a, b = pts[:-1], pts[1:]
    out = np.empty(len(a))
    upper = np.empty(len(a))
    for i in range(len(a)):
        bound = point_segment(part.centre, a[i], b[i]) - part.bound - radius
        out[i] = upper[i] = bound if bound > horizon else part.segment_sdf(a[i], b[i]) - radius
    return out, upper


def cable_cable(pa: np.ndarray, ra: float, pb: np.ndarray, rb: float, horizon: float) -> float:
    mids_a, mids_b = 0.5 * (pa[:-1] + pa[1:]), 0.5 * (pb[:-1] + pb[1:])
    half_a = 0.5 * np.linalg.norm(np.diff(pa, axis=0), axis=1)
    half_b = 0.5 * np.linalg.norm(np.diff(pb, axis=0), axis=1)
    gap = (np.linalg.norm(mids_a[:, None] - mids_b[None], axis=2) - half_a[:, None] - half_b[None] - ra - rb)
    for i, j in zip(*np.nonzero(gap <= horizon)):     # elsewhere a lower bound beyond the horizon
        gap[i, j] = segment_segment(pa[i], pa[i + 1], pb[j], pb[j + 1]) - ra - rb
    return float(gap.min())


def held_of(spec: CableSpec, window: str) -> Anchor:
    if window == "start":
        return spec.start
    if window == "end":
        return spec.end
    return spec.clips[int(window.split()[1]) - 1]


# --------------------------------------------------------------------------------------------
# the test

def run_and_check(spec: SceneSpec, folder: Path, units: str, offset) -> dict[str, int]:
    unit = UNIT[units]
    off = np.asarray(offset, float)
    path = write_scene(spec, folder, units, offset)
    run_scene(load_scene(path), RunOptions(report=folder / "report.json", record=None))
    report = json.loads((folder / "report.json").read_text())
    built = build_static(load_scene(path))
    windows = attachment_exclusions(built)
    zone = built.scene.check.attach_zone
    clearance = spec.clearance
    horizon = clearance + 1e-6
    parts = reference_parts(spec, folder)

    cables = {c["name"]: c for c in report["cables"]}
    pts = {}
    for c, model in zip(spec.cables, built.cables):
        assert model.name == c.name
        p = np.asarray(cables[c.name]["rest_points"], float) * unit - off
        pts[c.name] = p
        # the routed shape starts and ends where the scene says, through every via point and clip
        assert np.linalg.norm(p[0] - c.start.world) <= TOL and np.linalg.norm(p[-1] - c.end.world) <= TOL
        for q in [*c.via, *(a.world for a in c.clips)]:
            assert np.linalg.norm(p - q, axis=1).min() <= TOL
        assert np.allclose(model.routed - off, p, rtol=0, atol=TOL)

    reported = {(q["a"], q["b"]): q for q in report["pairs"] if q["a"] in cables and q["a"] != q["b"]}
    excused = {(q["a"], q["b"], q["window"]): q for q in report["excused"]}
    assert len(excused) == len(report["excused"])
    assert report["summary"]["excused"] == len(excused)

    # which parts each end and clip excuses, checked against the scene and measured here
    by_window: dict[tuple[str, str], list] = {}
    for e in windows:
        by_window.setdefault((e.cable, e.window), []).append(e)
    for c, model in zip(spec.cables, built.cables):
        p = pts[c.name]
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
        held: dict[str, list[int]] = {}
        for att in model.attachments:
            held.setdefault(att.window, []).append(att.vertex)
        anchors = {"start": c.start, "end": c.end} | {f"clip {n}": a for n, a in enumerate(c.clips, 1)}
        assert set(held) == {w for w, a in anchors.items() if a.hold != "free"}
        for w, vertices in held.items():
            a = anchors[w]
            assert min(np.linalg.norm(p[v] - a.world) for v in vertices) <= TOL
            got = by_window.get((c.name, w), [])
            if a.named:
                want = {n for n in parts if any(covers(x, n) for x in a.named)}
            else:
                reach = c.radius + clearance
                gap = {n: min(parts[n].point_sdf(p[v]) for v in vertices) for n in parts if parts[n].body == a.body}
                assert all(gap[e.part] <= reach + TOL for e in got), (w, [(e.part, gap.get(e.part)) for e in got])
                want = {n for n, g in gap.items() if g <= reach - TOL} | ({e.part for e in got} & set(gap))
            assert {e.part for e in got} == want, (c.name, w)
            lo_s, hi_s = s[vertices].min() - zone * c.radius, s[vertices].max() + zone * c.radius
            for e in got:      # the window: zone radii either side of the held vertices, widened to whole elements
                assert e.s_min <= max(lo_s, 0.0) + TOL and (e.s_min <= TOL or s[s > e.s_min + TOL].min() > lo_s - TOL)
                assert e.s_max >= min(hi_s, s[-1]) - TOL and (e.s_max >= s[-1] - TOL
                                                               or s[s < e.s_max - TOL].max() < hi_s + TOL)

    expect_pairs, expect_excused = {}, {}
    for c in spec.cables:
        p = pts[c.name]
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
        mid = 0.5 * (s[:-1] + s[1:])
        for name, part in parts.items():
            d, upper = element_distances(part, p, c.radius, horizon)
            free = np.ones(len(d), bool)
            for e in windows:
                if e.cable == c.name and e.part == name:
                    inside = (mid >= e.s_min) & (mid <= e.s_max)
                    free &= ~inside
                    if inside.any():
                        expect_excused[c.name, name, e.window] = float(d[inside].min()), float(upper[inside].min())
            if free.any():
                expect_pairs[c.name, name] = float(d[free].min()), float(upper[free].min())
    for i, c in enumerate(spec.cables):
        for c2 in spec.cables[i + 1:]:
            d = cable_cable(pts[c.name], c.radius, pts[c2.name], c2.radius, horizon)
            expect_pairs[c.name, c2.name] = d, d

    def compare(expected: dict, got: dict, what: str, key_type=None):
        for key, (ref, upper) in expected.items():
            q = got.get(key)
            if ref < clearance - TOL:
                assert q is not None, f"{what} {key} at {ref!r} m (clearance {clearance!r}) is missing"
                value = q["min_distance"] * unit
                if upper == ref:
                    assert abs(value - ref) <= TOL, (what, key, value, ref)
                else:     # an element through a mesh: between the true depth and its shallower end
                    assert ref - TOL <= value <= upper + TOL, (what, key, value, ref, upper)
                if key_type is not None:
                    assert q["type"] == key_type(key)
            elif ref > clearance + TOL:
                assert q is None, f"{what} {key} listed at {q['min_distance'] * unit!r} m, reference {ref!r} m"
        assert set(got) <= set(expected), set(got) - set(expected)

    def pair_type(key):
        if key[1] in parts:
            return "keepout" if parts[key[1]].keepout else "cable-structure"
        return "cable-cable"

    compare(expect_pairs, reported, "pair", pair_type)
    compare(expect_excused, excused, "excused")
    below = [k for k, (ref, _) in expect_pairs.items() if ref < clearance]
    return {"pairs below the clearance": len(below),
            "through a mesh": sum(ref != upper for ref, upper in [*expect_pairs.values(), *expect_excused.values()]),
            "overlapping": sum(expect_pairs[k][0] < 0 for k in below),
            "cable-cable below": sum(k[1] not in parts for k in below),
            "excused": len(excused),
            "windows": len(windows)}


@settings(max_examples=examples(30), deadline=None,      # HYPOTHESIS_PROFILE=long: the large draw
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(spec=scenes(), units=st.sampled_from(["m", "mm"]), far=st.booleans())
def test_static_scenes_match_the_reference(tmp_path_factory, spec, units, far):
    folder = tmp_path_factory.mktemp("reference")
    counts = run_and_check(spec, folder, units, FAR if far else (0.0, 0.0, 0.0))
    for what, n in counts.items():
        event(f"{what}: {min(n, 5)}{'+' if n >= 5 else ''}")




@settings(max_examples=examples(40), deadline=None)
@given(a=vec(-0.1, 0.1), b=vec(-0.1, 0.1), euler=vec(-180.0, 180.0), centre=vec(-0.02, 0.02),
       size=st.tuples(floats(0.005, 0.05), floats(0.005, 0.05), floats(0.005, 0.05)))
def test_the_reference_agrees_with_itself(a, b, euler, centre, size):
    """The reference's line search (golden section over a point distance)
    against its closed forms: a sphere and a capsule searched along their
    point distances, an ellipsoid of equal semi-axes against the sphere, a
    box against the same box as a convex mesh; and every shape against a
    dense sampling of the segment (never above it: every searched value is
    attained; below it by at most the sampling step)."""
    r = rot(euler)
    sphere = RefPart("s", "sphere", np.array(size[:1]), r, centre, "world", False)
    capsule = RefPart("c", "capsule", np.array(size[:2]), r, centre, "world", False)
    ball = RefPart("e", "ellipsoid", np.array([size[0]] * 3), r, centre, "world", False)
    box = RefPart("b", "box", np.array(size), r, centre, "world", False)
    m = trimesh.creation.box(extents=2 * np.array(size))
    mesh = RefPart("m", "mesh", np.array(size), r, centre, "world", False,
                   ConvexMesh.of(np.asarray(m.vertices), np.asarray(m.faces)))
    for part in (sphere, capsule):
        assert abs(least_along(lambda t: part.point_sdf(a + t * (b - a))) - part.segment_sdf(a, b)) <= 1e-13
    assert abs(ball.segment_sdf(a, b) - sphere.segment_sdf(a, b)) <= 1e-13
    assert abs(box.segment_sdf(a, b) - mesh.segment_sdf(a, b)) <= 1e-13
    t = np.linspace(0.0, 1.0, 201)
    for part in (sphere, capsule, box, RefPart("y", "cylinder", np.array(size[:2]), r, centre, "world", False),
                 RefPart("z", "ellipsoid", np.array(size), r, centre, "world", False)):
        dense = min(part.point_sdf(a + x * (b - a)) for x in t)
        assert part.segment_sdf(a, b) <= dense + 1e-13
        assert dense - part.segment_sdf(a, b) <= float(np.linalg.norm(b - a)) / 200

SNAP_SCENE = """
[scene]
name = "snap"
units = "m"
duration = 0.0

[effects]
dynamics = false

[check]
method = "exact"
clearance = 0.005
validate = false

[[bodies]]
name = "arm"
pos = [0.3, 0.2, 0.1]

[[parts]]
name = "part"
body = "arm"
shape = "{shape}"
size = {size}
pos = {pos}
euler = {euler}

[[cables]]
name = "lead"
radius = 0.002
start = {{ pos = [0.314, 0.1, {z}] }}
end = {{ pos = [0.314, 0.3, {z}] }}
"""


@pytest.mark.parametrize("shape,size,pos,euler,z", [
    ("sphere", [0.01], [9e-7, 0.0, 0.0], [0.0, 0.0, 0.0], 0.1),           # 9e-7 m nearer than measured
    ("box", [0.011, 0.05, 0.05], [0.0, 0.0, 0.0], [0.0, 1e-4, 0.0], 0.14),  # turned 1.7e-6 rad: 7e-8 m nearer
], ids=["position", "rotation"])
@pytest.mark.xfail(strict=True, reason="product bug: a part's frame within 1e-6 of its body's (quaternion "
                   "elements; and its position, in metres, when the rotation is) is measured where MuJoCo's "
                   "compiler snaps it (cablecheck.run.kinematic.same_frame, FRAME_EPS), not where the scene puts it")
def test_a_frame_next_to_its_body_is_where_the_scene_puts_it(tmp_path, shape, size, pos, euler, z):
    """A part on a body, its frame a hair off the body's; a straight cable
    (radius 0.002) along y, 0.014 from the body's origin along x: the
    sphere (radius 0.01) moved 9e-7 m toward it, the box (half-size 0.011
    along x) turned 1e-4 degrees about y, so that its x face comes 0.04
    sin(1e-4 deg) nearer where the cable passes it (0.04 above its centre).
    Expected: the reference's distance to the part as written, which
    differs from the snapped part's by more than 5e-8 m."""
    path = tmp_path / "snap.toml"
    path.write_text(SNAP_SCENE.format(shape=shape, size=size, pos=pos, euler=euler, z=z))
    report = run_scene(load_scene(path), RunOptions(report=tmp_path / "r.json", record=None))
    (pair,) = report["pairs"]
    body = np.array([0.3, 0.2, 0.1])
    a, b = np.array([0.314, 0.1, z]), np.array([0.314, 0.3, z])
    written = RefPart("part", shape, np.array(size, float), rot(euler), body + np.array(pos), "arm", False)
    snapped = RefPart("part", shape, np.array(size, float), np.eye(3), body, "arm", False)
    expected = written.segment_sdf(a, b) - 0.002
    assert abs(expected - (snapped.segment_sdf(a, b) - 0.002)) > 5e-8
    assert abs(pair["min_distance"] - expected) <= TOL, (pair["min_distance"], expected)


MESH_SCENE = """
[scene]
name = "through"
units = "m"
duration = 0.0

[effects]
dynamics = false

[check]
method = "exact"
clearance = 0.005
validate = false

[[parts]]
name = "block"
shape = "mesh"
file = "block.stl"
pos = [0.0, 0.01, 0.0]

[[cables]]
name = "lead"
radius = 0.002
start = { pos = [0.0, -0.1, 0.0] }
end = { pos = [0.0, 0.1, 0.0] }
segments = 2
"""


def test_a_segment_through_a_mesh_is_measured_at_its_deepest_point(tmp_path):
    """A box mesh (half-size 0.03125) centred at y = 0.01, a straight cable
    along y through its centre in two elements (and two short clamp edges):
    the centreline's deepest point, y = 0.01, lies 0.03125 inside (the x and
    z faces), so the pair is at -0.03125 - r. The element from y = 0 on (to
    the end's clamp edge) holds that point between its nine samples."""
    trimesh.creation.box(extents=[0.0625, 0.0625, 0.0625]).export(tmp_path / "block.stl")
    path = tmp_path / "through.toml"
    path.write_text(MESH_SCENE)
    report = run_scene(load_scene(path), RunOptions(report=tmp_path / "r.json", record=None))
    (pair,) = report["pairs"]
    assert abs(pair["min_distance"] - (-0.03125 - 0.002)) <= TOL, pair["min_distance"]


BALL_SCENE = """
[scene]
name = "ball"
units = "m"
duration = 0.0

[effects]
dynamics = false

[check]
method = "exact"
clearance = 0.005
validate = false

[[parts]]
name = "ball"
shape = "ellipsoid"
size = [0.03125, 0.03125, 0.03125]
euler = [0.0, 10.0, 0.0]

[[cables]]
name = "lead"
radius = 0.002
start = { pos = [-0.1, 0.0, 0.0] }
end = { pos = [0.1, 0.0, 0.0] }
"""


def test_a_cable_through_a_balls_centre_is_no_deeper_than_its_radius(tmp_path):
    """An ellipsoid with three equal semi-axes (a ball of radius 0.03125,
    turned 10 degrees about y) and a straight cable through its centre: the
    deepest point is the centre, 0.03125 inside, so the pair is at
    -0.03125 - r (it read -0.0339: the point distance within 1e-12 of the
    centre was lost in the rounding of Eberly's root near the pole)."""
    path = tmp_path / "ball.toml"
    path.write_text(BALL_SCENE)
    report = run_scene(load_scene(path), RunOptions(report=tmp_path / "r.json", record=None))
    (pair,) = report["pairs"]
    assert abs(pair["min_distance"] - (-0.03125 - 0.002)) <= TOL, pair["min_distance"]
