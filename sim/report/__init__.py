"""The report stage: a run's outcome as its JSON report (and, with `--html`, an HTML one), compared with an earlier run and a reviewer's notes.

`document` (`RunOutcome`, `report_of`, an atomic write), `baseline` (clash
status against an earlier report), `review` (a reviewer's notes file),
`outputs` (output paths checked before any work starts), `evidence` (what
a run keeps for the HTML report: each clash's worst state and distance
history), `render` (pictures of the spots, MuJoCo's offscreen renderer),
`html` (the self-contained HTML report).

This package computes no distances and runs no simulation; it lays out
(and, for the HTML report, renders) what a run found.
"""
