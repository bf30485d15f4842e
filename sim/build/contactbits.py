"""Which geoms collide with which: the scene's contype / conaffinity bits.

A pair collides when (type1 & aff2) | (type2 & aff1). An mjcf model is
taken as it comes. Its geoms that MuJoCo never collides (`contype` and
`conaffinity` both 0 as written: visual meshes) are left out of both
models (`cablecheck.scene.mjcf.lean_spec`) or, where MuJoCo keeps them, stay
so; the recording draws them (`cablecheck.build.drawn`), the checker never.
Its other geoms are parts whose own bits say which of them meet each
other; the scene's interactions use three bits the model leaves unused
(`ContactBits`), added to the model geoms' conaffinity only, so they never
make two model geoms meet:
- detection model: every part (model geom or scene part) has contype 0 and
  conaffinity the cable bit, so MuJoCo reports the cables' contacts with
  every part and nothing else: validation compares cable pairs only, and a
  robot's links pressed together at their joints (their hulls) were a
  third of its collision pass on the zoo's Panda and UR5e. The checker's
  part-part pairs leave out the model-geom pairs the model itself never
  collides (their own bits never meet, or their bodies form a
  `<contact><exclude>` pair: `Built.model_skip`, from the bits as written);
- simulation model, cable-structure: the model geoms' conaffinity is the
  cable bit, so cables push on every link;
- simulation model, part-part: the model geoms keep their own bits (a
  robot's self-collision as its author set it) plus the part bit, so they
  also meet the scene's parts. Without part-part their contype is 0: the
  base model is driven kinematically, and contacts among its own geoms (a
  housing resting on its column) could only fight the script.

This module computes bits from the scene's `effects.contact`; it does not
write them into a model (see `cablecheck.build.mjspec`).
"""

from __future__ import annotations

from dataclasses import dataclass

from cablecheck.scene.records import Scene


@dataclass(frozen=True)
class ContactBits:
    """The scene's contype/conaffinity bits (a pair collides when
    (type1 & aff2) | (type2 & aff1)): three bits no geom of the base model
    uses, so the model's own bits keep their meaning beside them.

    Attributes:
      cable: cable contype; conaffinity of parts when cable-structure is on.
      cable_cable: cable conaffinity and contype when cable-cable is on.
      part: scene parts' contype; conaffinity of all parts when part-part is on.
    """

    cable: int
    cable_cable: int
    part: int

    @classmethod
    def free_of(cls, used: int) -> "ContactBits":
        """The three lowest bits not set in `used` (the model's bits, or'ed)."""
        free = [1 << k for k in range(32) if not used & (1 << k)]
        if len(free) < 3:
            raise ValueError("the mjcf model uses 30 or more of MuJoCo's 32 contact bits; "
                             "three free ones are needed for the cables and the scene's parts")
        return cls(*free[:3])


def part_bits(scene: Scene, bits: ContactBits, detect: bool, keepout: bool) -> tuple[int, int]:
    """contype, conaffinity of a scene part."""
    contact = scene.effects.contact
    if detect:
        return 0, bits.cable
    if keepout:
        return 0, 0
    contype = bits.part if "part-part" in contact else 0
    conaff = (bits.cable if "cable-structure" in contact else 0) | contype
    return contype, conaff


def model_bits(scene: Scene, bits: ContactBits, detect: bool, own: tuple[int, int]) -> tuple[int, int]:
    """contype, conaffinity of a colliding geom of the mjcf model (see the
    module docstring): the scene's bits go into conaffinity only, so the
    model's geoms meet each other only as their own bits say; in the
    simulation model those own bits act only when part-part is asked."""
    contact = scene.effects.contact
    if detect:
        return 0, bits.cable
    cable = bits.cable if "cable-structure" in contact else 0
    if "part-part" not in contact:
        return 0, cable
    return own[0], own[1] | cable | bits.part


def cable_bits(scene: Scene, bits: ContactBits, detect: bool) -> tuple[int, int]:
    if detect or "cable-cable" in scene.effects.contact:
        return bits.cable | bits.cable_cable, bits.cable_cable
    return bits.cable, 0
