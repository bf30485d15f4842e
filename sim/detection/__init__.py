"""The detection model: MuJoCo's own collision passes, run at the simulation's states to cross-check the checker.

`detector` runs the passes, `contacts` maps contacts back to the scene's
names, `mesh` and `surfacereach` let concave mesh parts be seen as their true
surface, `hullgap` finds cables the simulation holds on a concave part's
convex hull.

This package does not simulate (`cablecheck.run`) and does not compare its
contacts with the checker's events (`cablecheck.checker.validation`).
"""
