"""Conservative advancement: steps on which no pair can have come within the clearance.

After a full check at step k0 the checker knows, up to a horizon H, how far
every pair stays from the clearance (the :class:`~cablecheck.checker.interference.hits.Gaps`
record :meth:`cablecheck.checker.interference.Checker.check_with_gaps` returns, with its
part and cable candidates, and :func:`part_pair_bounds`). On a later step k, with

- ``d_i``: the displacement of cable body centre i since k0, ``dq_i = |d_i|``,
- ``spread``: the diagonal of the bounding box of all ``d_i`` (at least
  ``|d_a - d_b|`` for any two centres; ``min(spread, 2 max dq)`` is used),
- ``u_i^k``: centre i in part k's own frame, ``R_k^T (x_i - t_k)``, and
  ``rel[i, k] = |u_i^k(k) - u_i^k(k0)|`` its displacement relative to part k,
- ``dp[k]``: a bound on how far any point of part k moved since k0, its
  translation plus ``||R - R0||_F`` times the part's bounding radius about
  its frame's origin (a plane that rotated: unbounded), or with the part's
  box the farthest move of a corner of it, ``max |(R - R0) c + t - t0|``
  (a point's move is convex in the point),
- ``g[i, k]``: centre i's gap to part k (inf when (i, k) is *active*: the
  caller evaluates every discrete point of the elements next to i against
  part k directly at every step, as the run does for places inside or
  near the clearance at k0): the smallest, over the elements
  next to centre i, of the value minus the clearance of part k's candidates
  on the element, or where there is none the larger of H and the element's
  floor ``F[e, k]``: at k0, the distance in part k's frame between the
  element's bounding box and the part's box, minus the cable radius and the
  clearance (a lower bound on every value of the element against part k),

no pair can have come within the clearance while

- self and cable-cable, either ``spread < gap_cable`` (the least gap over
  all cable pairs), or, with the checker's cable candidates, all of

  - for every near element pair (e, f) (one cable, ``e <= f < e + 2
    BLOCK``), either the chord bound holds at step k: ``T < pi`` and
    ``max(w, S) cos(T / 2) > 2 r + clearance``, with ``T`` the cable's
    total turning at the centres e + 1 .. f (the sum of the angles between
    consecutive elements) at step k, ``S`` the arc length from centre e + 1
    to centre f at k0 minus ``stretch`` (the arc length at k is no less
    under the last condition), ``w = pi r + clearance`` the self-exclusion window
    (:func:`cablecheck.checker.cable.self_pair_excluded`) and r the cable's radius; or
    the largest ``|d_a - d_b|`` over a in {e, e + 1} and b in {f, f + 1} is
    below the pair's gap: the least value minus the clearance of the
    candidates with both places on the pair (H when there is none, capped
    at H),
  - ``|d_i - d_j| < g[i, j]`` for every pair of centres (i, j) such that a
    candidate pair that is no near pair's has one place on an element next
    to i and the other on an element next to j; ``g[i, j]`` the least such
    candidate's value minus the clearance,
  - for every pair of blocks A, B of ``BLOCK`` consecutive elements of
    one cable (centres ``s .. s + K``, restarting at every cable) other
    than a block with itself or the next on one cable (their element
    pairs are all near pairs), either ``box(A, B) < max(H, L[A, B])``,
    where ``box(A, B)`` is the norm of the componentwise largest ``|d_a -
    d_b|`` over the two blocks' bounding boxes of displacements, and
    ``L[A, B]`` the distance at k0 between the axis-aligned boxes of the
    blocks' centres, minus the largest radii of the two blocks and the
    clearance (capped at ``FAR_HORIZONS * H``); or the same distance at
    step k itself is above 0; or at step k, for every element a of A and
    b of B, the distance between their midpoints less half their lengths,
    or the gap between their projections on the unit vector ``n`` from
    the closest point of a to that of b (as
    :func:`cablecheck.checker.closest.segment_segment` finds them), exceeds the two
    blocks' largest radii and the clearance,
  - ``min(spread, 2 max dq) < FAR_HORIZONS * H`` when some block pairs are
    farther apart than that and left unlisted,
- ``dq_i < g[i, k]`` for every part k that did not move, and for every
  part k that moved and every element (i, i + 1), either ``rel[j, k] <
  g[j, k]`` for both its centres j, or ``dq_j + dp[k] < g[j, k]`` for both
  (one bound for the whole element; cable-structure, keep-out),
- ``min(dp[i] + dp[j], rel[i, j]) < bound[i, j] - clearance`` for every
  part pair that can move relative to the other (part-part, keep-out
  between parts), ``rel`` the move of one part in the other's own frame
  (modulo turns about that part's axis where it is a solid of revolution,
  less both tessellation errors as a margin:
  :class:`~cablecheck.checker.advance.partpairs.PartPairGaps`),
  or the same box separation at step k itself above the clearance,
  except the pairs the caller leaves out of the bound and checks itself at
  every step (*active* part pairs, within the clearance at k0),
- every cable element splits into the same number of discrete points as at
  k0, and the element lengths of every *run* changed by at most ``stretch``
  in total: the run of element e is e .. L(e) on its cable, with L(e) the
  last element f such that the elements e + 1 .. f - 1 were shorter in
  all than ``w + stretch`` at k0 (``w`` the self-exclusion window, below),
  and at least e + 2 BLOCK (without cable radii: whole cables).

A pair whose own condition fails at step k need not end the skipping: the
caller may evaluate it itself from then on, as it does the active pairs
(:meth:`Advancement.clear_run_local`, *promoted* pairs); the conditions
that name no pair (pieces and stretch, part pairs, the far limit of the
block pairs, a centre past the sparse gaps' cap) still end it.

Proof sketch. With the same number of pieces per element, every discrete
point (and every element midpoint, and every point of a piece) is the same
convex combination of the same two body centres as at k0, in the world and
in any part's frame alike (the maps are affine); so its displacement is the
same combination of the two centres' displacements: at most the larger of
their ``dq`` (or ``rel``), and the difference of two such displacements lies
within the bounding box's diagonal. Cable pairs, per place: two places on
elements (i, i + 1) and (j, j + 1) moved relative to each other by a convex combination of ``d_i - d_j``,
``d_i - d_(j+1)``, ``d_(i+1) - d_j`` and ``d_(i+1) - d_(j+1)`` (the
product of the two combinations' weights), so by at most the largest of
their norms (a common translation cancels); each such centre pair carries
the gap of every candidate charged to it (each side charged as the part
candidates are, below). A checked pair of places that was no candidate was
at least H past the clearance at k0 (or deeper than ``stretch`` inside its
exclusion window, where it stays), and at least ``L[A, B]`` past it for
blocks holding its elements (each place is in the convex hull of its
block's centres, inside their bounding box); its relative displacement
lies in the difference of the two blocks' boxes of displacements, whose
largest point is ``box(A, B)`` away from the origin, and below
``min(spread, 2 max dq)`` for any two places. A point of a rigid
part moved by at most
``dp``. Every value checked is a distance between two cable points, or a
point's distance to a rigid solid, minus fixed radii: a 1-Lipschitz function
of the places, so it dropped by at most ``|d_a - d_b|`` (cable pairs), and
by at most the point's displacement in the part's own frame, or the point's
plus the part's displacement in the world (cable and part; a point outside a
solid with distance above the clearance stays outside, where the signed
distance is the distance). A point ``(1 - t) x_i + t x_(i+1)`` of an element
moved in part k's frame by at most ``(1 - t) rel[i, k] + t rel[i + 1, k] <
(1 - t) g[i, k] + t g[i + 1, k]``, at most the element's own gap (each
centre's gap is the least over its elements), and likewise in the world:
hence one bound for both centres (a centre riding with a turning part, next
to one held still in the world, passes by the one and the other by the
other, and the points between them by neither). Two conditions look at step k alone (the chord's ``S`` aside). Boxes:
every place of a block lies in the convex hull of its centres, inside
their bounding box. Axes: every place of a block lies on one of its
elements, within half the element's length of its midpoint; and for two
segments and any unit vector ``n`` the distance of
any two of their points is at least ``n`` times their difference, at least
the least projection of the one's ends less the largest of the other's (a
linear function is extreme on a segment at its ends); ``n`` need not be
the exact closest points' direction. Chord: let two places on elements e and f
be checked at step k, so their arc lengths differ by at least ``w`` (and by
at least ``S``). Along the polyline between them the unit tangent turns by
at most ``T`` in total, so every tangent lies within the angle ``T / 2`` of
the tangent halfway along that turning, m; the chord is the integral of
the tangent over the arc, so its length is at least its component along
m, at least the arc length times ``cos(T / 2)``, and the pair's distance
minus ``2 r`` exceeds the clearance. (The turning angles are rounded up by
1e-6 rad; ``arccos`` near 0 loses about 1e-8.) At k0 every candidate value below ``clearance +
H`` was evaluated, and each part candidate is charged to every centre of the
element holding its arc length (with a rounding margin: more centres only
lower the gaps); a point with no candidate for part k was at least H past
the clearance from it, and at least ``F[e, k]`` past it, since the element
lies in its box and the part in its own (a point outside the part's box is
outside the part, at a distance no less than the boxes' separation). Exclusions are windows in arc length (self: ``|s_a -
s_b| < pi r + clearance``, both places on one cable), and the arc length
between two places changed by at most the total change of the elements
from the one's to the other's, a part of a run when they were inside the
window at k0 (the elements between them shorter than ``w``) or are a near
pair's (the chord's ``S``); attachments are fixed windows of the cable's
material, where a discrete point, the same combination of the same two
centres, keeps its material coordinate (and so its window) while skipping;
the gaps at k0 include candidates up to ``stretch`` inside every window
all the same, so none that left a window since was unaccounted for. Part pairs: the least distance
of their triangles is at least the separation of their oriented boxes on any
box axis (or, for a plane, the box's lowest point above it), which
:func:`part_pair_bounds` takes at k0; the distance of two rigid solids
depends on their relative pose alone, and not on a turn about the axis of
a solid of revolution; boxes more than the clearance apart at step k on
a box axis are rejected there by the part-part check's own oriented-box
test (the same boxes grown by half the clearance each). Rounding is absorbed by a margin of
1e-9 of the scene's extent.

So on such a step the pairwise checks can be skipped: their answer is "no
pair below the clearance" apart from the active pairs, exactly what a full
check would return. Single-cable checks (bend, taut) and the active pairs are still
evaluated every step, by the caller. Method ``exact`` (closest points whose
exclusion can change discontinuously) and the face-plane distance never
skip.

The package holds only the bound, one module per condition:
:mod:`~cablecheck.checker.advance.cablepairs` (self and cable-cable),
:mod:`~cablecheck.checker.advance.structure` (cables against parts),
:mod:`~cablecheck.checker.advance.partpairs` (part pairs), and
:mod:`~cablecheck.checker.advance.skip` (:class:`Advancement`: the start, the run of
states, pieces and stretch). It takes arrays and knows no simulator; it does
not check anything itself.
"""

from cablecheck.checker.advance.partpairs import PartSolids, part_pair_bounds
from cablecheck.checker.advance.skip import Active, Advancement

__all__ = ["Active", "Advancement", "PartSolids", "part_pair_bounds"]
