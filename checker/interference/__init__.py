"""Interference of one scene state: self, cable-cable, cable-structure, keep-out, bend, taut.

The discrete-point distance method (Ju et al., 2016) as a package of one job
per module, in the order a check runs them:

- :mod:`~cablecheck.checker.interference.discrete`: each cable densified so no element
  is longer than ``spacing * r``; arc lengths and material coordinates.
- :mod:`~cablecheck.checker.interference.broad`: chunks of consecutive points (or
  elements) with bounding spheres and a k-d tree over them.
- :mod:`~cablecheck.checker.interference.cablepairs`: self and cable-cable pairs.
- :mod:`~cablecheck.checker.interference.structure`: cables against parts
  (cable-structure and keep-out).
- :mod:`~cablecheck.checker.interference.single`: bend radius and taut, per cable.
- :mod:`~cablecheck.checker.interference.hits`: candidates reduced to one record per
  pair, and the gaps the skip rule (:mod:`cablecheck.checker.advance`) needs.
- :mod:`~cablecheck.checker.interference.pipeline`: :class:`Checker` and
  :func:`check_state`, which run the above.

Method ``points`` is the paper's; method ``exact`` takes the same polylines
as chains of capsules (exact segment distances), so contact between two
discrete points is never missed. Each pass that the run evaluates for many
states at once (``*_many``) shares its arithmetic with the single-state pass
through one kernel, so both give the same bits.

Deliberately not done here: part-part interference (:mod:`cablecheck.checker.parts`),
events over time and comparison with MuJoCo.
"""

from cablecheck.checker.interference.discrete import DenseStates
from cablecheck.checker.interference.hits import CableCandidates, Gaps, PartCandidates
from cablecheck.checker.interference.pipeline import Checked, Checker, check_state
from cablecheck.checker.interference.single import single_records_many

__all__ = ["CableCandidates", "Checked", "Checker", "DenseStates", "Gaps", "PartCandidates", "check_state",
           "single_records_many"]
