"""The report stage: a run's outcome as its JSON report, compared with an earlier run and a reviewer's notes.

`document` (`RunOutcome`, `report_of`, an atomic write), `baseline` (clash
status against an earlier report), `review` (a reviewer's notes file),
`outputs` (output paths checked before any work starts).

This package computes no distances and runs nothing; it lays out what a run
found.
"""
