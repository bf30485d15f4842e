"""The scene format's fixed words and numbers: which keys each table accepts,
the values a key may take, the defaults and the bounds every scene is held to.

`docs/scene-format.md` documents these; `tests/test_scene.py` compares its
tables with the key tuples here. This module reads nothing and checks
nothing (the table readers do, `cablecheck.scene.load`); the records that carry
the values are in `cablecheck.scene.records`.
"""

from __future__ import annotations

import math
from enum import Enum

UNITS = {"m": 1.0, "mm": 0.001}
"""Scene units and their size in metres."""

SHAPE_SIZES = {"box": 3, "sphere": 1, "cylinder": 2, "capsule": 2, "ellipsoid": 3,
               "plane": 0, "mesh": 0}
"""Number of `size` entries per part shape (MuJoCo's convention; 0: no size)."""

INTERACTIONS = ("cable-structure", "cable-cable", "self", "part-part")
"""Names allowed in `effects.contact`."""

METHODS = ("points", "exact")

INTERPOLATIONS = ("cubic", "linear")
"""How a motion's samples are joined (`cablecheck.run.curves`), the default first."""
"""Values allowed in `check.method`."""

DEFAULT_CLEARANCE = 0.005
"""`check.clearance` when absent: 5 mm, in metres, whatever the scene units."""

DEFAULT_YOUNG = 5.0e7
"""Cable bending modulus when absent, Pa.

A PVC-jacketed wire or small harness bends like a rod of effective modulus
10-100 MPa: plasticised PVC is 10-50 MPa, and stranded copper adds little in
bending because its strands slide. Measured harness bending stiffness EI of
about 0.02 N m^2 at 10 mm diameter (I = pi r^4 / 4 = 4.9e-10 m^4) gives
E = 4e7 Pa; we round to 5e7."""

DEFAULT_DENSITY = 1500.0
"""Cable density when absent, kg/m^3: PVC (~1400) with some copper and air."""

DEFAULT_FRICTION = 1.0
"""Sliding friction of a contact where neither the cable nor the part (nor
the other cable) sets `friction`: MuJoCo's default geom friction. Where
one side sets it, that side's; where both do, the larger (MuJoCo's rule
for geoms of equal priority; see `cablecheck.build.mjspec`)."""

DEFAULT_DAMPING = 0.02
"""`damping` when absent: fraction of critical damping of a cable's own first
bending mode as held (see `cablecheck.build.stages.rayleigh_damping` and docs/physics.md). 2 % is
the loss of a polymer-jacketed cable swinging in air; a hanging cable keeps
swinging for many periods."""


class Hold(str, Enum):
    """How an end or clip holds the cable (SPEC, additions)."""

    CLAMP = "clamp"   # position and tangent (the cable's direction)
    PIN = "pin"       # position only, free to turn
    FREE = "free"     # not held: the position only shapes the initial route


LARGEST = 1e15
"""No number in a scene may exceed this magnitude (keeps squares and sums finite)."""

ROUTE_TOLERANCE = 1e-9
"""Relative tolerance by which `length` may fall short of its route."""

POINTS_LENGTH_TOLERANCE = 1e-6
"""Relative tolerance by which `length` may exceed a `points` route with
dynamics off (the route's length printed to 6 digits is accepted)."""

SELF_CONTACT_ELEMENT = 2.25
"""Shortest element, in cable radii, when self-contact pushes back: MuJoCo's
flex self-collision skips only elements sharing a vertex, so elements two
apart along a straight cable are one element length apart and touch (within
the simulation's contact margin of 0.25 r, `cablecheck.build.stages.SIM_MARGIN_FRACTION`)
unless it exceeds 2 r + 0.25 r. Without self-contact MuJoCo sets no such
limit on the element length."""

DEGENERATE = 1e-6
"""A route segment shorter than this many cable radii has zero length."""

ANGLES = {"deg": math.pi / 180.0, "rad": 1.0}
"""Values of `[[motion]] angles` and radians per unit."""

BODY_AXES = ("x", "y", "z", "rx", "ry", "rz")
"""Column suffixes of a body in a motion file: position (scene units), euler angles (degrees)."""

ZERO3 = (0.0, 0.0, 0.0)
"""A position or orientation of zeros, the default of `pos` and `euler`."""

# The keys each table accepts, in the order docs/scene-format.md lists them.

TOP_KEYS = ("scene", "effects", "check", "bodies", "parts", "cables", "motion", "limits", "allow")
LIMIT_KEYS = ("steps", "elements", "points")
SCENE_KEYS = ("name", "units", "duration", "timestep", "settle", "mjcf")
EFFECTS_KEYS = ("dynamics", "gravity", "contact")
CHECK_KEYS = ("method", "spacing", "clearance", "every", "validate", "attach_zone", "attach_links")
ALLOW_KEYS = ("a", "b", "reason")
BODY_KEYS = ("name", "pos", "euler")
PART_KEYS = ("name", "body", "shape", "size", "pos", "euler", "file", "scale", "keepout",
             "friction")
CABLE_KEYS = ("name", "radius", "start", "end", "via", "length", "points", "clips",
               "segments", "young", "density", "min_bend_radius", "twist_stiffness",
               "damping", "friction")
ANCHOR_KEYS = ("body", "pos", "hold", "tangent", "part")
MOTION_KEYS = ("body", "joint", "file", "keys", "angles", "interpolation", "time_scale")
BODY_KEY_KEYS = ("t", "pos", "euler")
JOINT_KEY_KEYS = ("t", "value", "key")
ANGLES = {"deg": math.pi / 180.0, "rad": 1.0}
