"""Pictures of clash spots, rendered without a display by MuJoCo's offscreen renderer.

For each event of a run, :func:`render_spots` poses the simulation model at
the event's worst state (its qpos, kept by `cablecheck.report.evidence`),
points a free camera at the spot (the worst point on cable `a`) from a
distance fitted to the pair's parts and the scene, draws the pair in strong colours (the part or
parts opaque orange, the cable or cables magenta) and everything else
translucent grey, marks the spot with a small sphere, renders it with
MuJoCo's own renderer (`mjv_updateScene`, `mjr_render`, `mjr_readPixels`, as
`mujoco.Renderer` does) and encodes it as PNG.

The OpenGL context is made here, not by `mujoco.Renderer`, because MuJoCo
picks its platform once, from `MUJOCO_GL`, when `mujoco` is first imported,
long before a run knows it will render. EGL (Mesa's libEGL, no display) is
tried first; OSMesa when `MUJOCO_GL=osmesa` is set. Both need PyOpenGL. When no
context can be made, no picture is made and :class:`Pictures` says why in its
warnings (which the report and the HTML show): never silently.

This module does not decide where or when a clash is (the run's events do),
and does not lay out the HTML (`cablecheck.report.html`).
"""

from __future__ import annotations

import io
import os
from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from cablecheck.report.evidence import Pictures

WIDTH, HEIGHT = 560, 400
"""Picture size in pixels (within MuJoCo's default offscreen buffer, 640 x 480)."""

PAIR_PART = (1.0, 0.45, 0.05, 0.55)
"""The pair's parts: orange, translucent enough to show the cable and the spot inside them."""
PAIR_CABLE = (1.0, 0.0, 0.9, 1.0)
OTHER_ALPHA = 0.3
OTHER_GREY = (0.85, 0.85, 0.9)
SPOT_RGBA = (1.0, 0.0, 0.9, 0.45)
BACKDROP_RGBA = (0.93, 0.94, 0.96, 1.0)
"""A light opaque screen far behind the spot, so translucent parts blend over light, not black."""


@dataclass(frozen=True)
class Spot:
    """One picture to make.

    Attributes:
      qpos: the simulation's qpos at the worst state, or None (no picture).
      where: (3,) the spot, model coordinates, metres.
      geoms: geom ids of the pair's parts.
      flexes: flex ids of the pair's cables.
      size: a length the spot is seen at (the pair's cable radius, metres).
    """

    qpos: np.ndarray | None
    where: np.ndarray
    geoms: tuple[int, ...]
    flexes: tuple[int, ...]
    size: float


def _context(width: int, height: int):
    """(platform, an OpenGL context made current) or (None, None) with the errors met."""
    wanted = os.environ.get("MUJOCO_GL", "").strip().lower()
    order = ("osmesa",) if wanted == "osmesa" else ("egl",)
    errors = []
    for name in order:
        try:
            if name == "egl":
                from mujoco.egl import GLContext  # loads PyOpenGL on EGL: only a run that renders needs it
            else:
                from mujoco.osmesa import GLContext  # loads PyOpenGL on OSMesa: only when asked for
            ctx = GLContext(width, height)
            ctx.make_current()
            return name, ctx, errors
        except Exception as exc:   # no libEGL, no device, no PyOpenGL: said in the warnings
            errors.append(f"{name}: {type(exc).__name__}: {exc}")
    return None, None, errors


def _png(pixels: np.ndarray) -> bytes:
    """An (h, w, 3) uint8 image as PNG bytes."""
    from matplotlib.image import imsave  # matplotlib loads (slowly) only for a run that renders

    buf = io.BytesIO()
    imsave(buf, pixels, format="png")
    return buf.getvalue()


def render_spots(model: mujoco.MjModel, spots: Sequence[Spot], width: int = WIDTH,
                 height: int = HEIGHT) -> Pictures:
    """A PNG picture of each spot (module docstring), or the reasons why not."""
    if not spots:
        return Pictures((), None, ())
    missing = [k for k, s in enumerate(spots) if s.qpos is None]
    warnings = [f"no picture of clash {k + 1}: no state of it was kept" for k in missing]
    if len(missing) == len(spots):
        return Pictures((None,) * len(spots), None, tuple(warnings))
    width = min(width, model.vis.global_.offwidth)
    height = min(height, model.vis.global_.offheight)
    platform, ctx, errors = _context(width, height)
    if ctx is None:
        why = "; ".join(errors)
        return Pictures((None,) * len(spots), None, (
            f"no clash pictures: no offscreen OpenGL context could be made ({why}); install Mesa's libEGL "
            f"and PyOpenGL, or set MUJOCO_GL=osmesa with libOSMesa installed",))
    geom_rgba, flex_rgba = model.geom_rgba.copy(), model.flex_rgba.copy()
    out: list[bytes | None] = []
    try:
        con = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150.value)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, con)
        scn = mujoco.MjvScene(model, maxgeom=10000)
        opt, pert, cam = mujoco.MjvOption(), mujoco.MjvPerturb(), mujoco.MjvCamera()
        data = mujoco.MjData(model)
        rect = mujoco.MjrRect(0, 0, width, height)
        pixels = np.zeros((height, width, 3), np.uint8)
        extent = float(model.stat.extent)
        for spot in spots:
            if spot.qpos is None:
                out.append(None)
                continue
            data.qpos[:] = spot.qpos
            mujoco.mj_forward(model, data)
            _colour(model, geom_rgba, flex_rgba, spot)
            cam.type = mujoco.mjtCamera.mjCAMERA_FREE
            cam.lookat[:] = spot.where
            cam.distance = _distance(model, spot, extent)
            cam.azimuth, cam.elevation = 135.0, -25.0
            mujoco.mjv_updateScene(model, data, opt, pert, cam, mujoco.mjtCatBit.mjCAT_ALL.value, scn)
            _dim_others(scn, set(spot.geoms))
            _mark(scn, spot.where, 2.0 * spot.size)
            _backdrop(scn, cam)
            mujoco.mjr_render(rect, scn, con)
            mujoco.mjr_readPixels(pixels, None, rect, con)
            out.append(_png(np.flipud(pixels).copy()))
        con.free()
    finally:
        model.geom_rgba[:] = geom_rgba
        model.flex_rgba[:] = flex_rgba
        ctx.free()
    return Pictures(tuple(out), platform, tuple(warnings))


def _distance(model: mujoco.MjModel, spot: Spot, extent: float) -> float:
    """How far the camera stands from the spot: the pair's parts whole in view (two and a half
    times their bounding radius), at most a third of the scene, and never closer than 40 cable radii."""
    bounds = [float(model.geom_rbound[g]) for g in spot.geoms if model.geom_rbound[g] > 0]
    near = min(0.3 * extent, 2.5 * max(bounds)) if bounds else 0.3 * extent
    return max(near, 40.0 * spot.size)


def _colour(model: mujoco.MjModel, geom_rgba: np.ndarray, flex_rgba: np.ndarray, spot: Spot) -> None:
    """The pair in strong colours, the other cables translucent (the model's own colours otherwise)."""
    model.geom_rgba[:] = geom_rgba
    model.flex_rgba[:] = flex_rgba
    if len(flex_rgba):
        model.flex_rgba[:, 3] = np.minimum(flex_rgba[:, 3], 0.5)
    for g in spot.geoms:
        model.geom_rgba[g] = PAIR_PART
    for f in spot.flexes:
        model.flex_rgba[f] = PAIR_CABLE


def _dim_others(scn: mujoco.MjvScene, pair: set[int]) -> None:
    """Every drawn geom not of the pair (parts, the flex's own bodies) translucent grey."""
    geom = mujoco.mjtObj.mjOBJ_GEOM
    for g in scn.geoms[:scn.ngeom]:
        if g.objtype == geom and g.objid not in pair:
            g.rgba[:3] = OTHER_GREY
            g.rgba[3] = min(g.rgba[3], OTHER_ALPHA)


def _mark(scn: mujoco.MjvScene, where: np.ndarray, radius: float) -> None:
    """A translucent sphere at the spot."""
    if scn.ngeom >= scn.maxgeom:
        return
    mujoco.mjv_initGeom(scn.geoms[scn.ngeom], mujoco.mjtGeom.mjGEOM_SPHERE.value,
                        np.array([radius, 0.0, 0.0]), np.asarray(where, float), np.eye(3).ravel(),
                        np.array(SPOT_RGBA, np.float32))
    scn.ngeom += 1


def _backdrop(scn: mujoco.MjvScene, cam: mujoco.MjvCamera) -> None:
    """An opaque light plate across the view, four camera distances behind the spot (glowing, so the
    headlight's angle does not shade it)."""
    if scn.ngeom >= scn.maxgeom:
        return
    az, el = np.radians(cam.azimuth), np.radians(cam.elevation)
    forward = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    mat = np.column_stack([right, up, forward]).ravel()
    far = 4.0 * cam.distance
    g = scn.geoms[scn.ngeom]
    mujoco.mjv_initGeom(g, mujoco.mjtGeom.mjGEOM_BOX.value, np.array([3 * far, 3 * far, 0.001 * far]),
                        np.asarray(cam.lookat, float) + far * forward, mat, np.array(BACKDROP_RGBA, np.float32))
    g.emission = 1.0
    scn.ngeom += 1
