"""The build stage: a validated scene made into MuJoCo models and what the run needs to know of them.

A scene (`cablecheck.scene`) is placed at t = 0 (`startframes`), each cable
planned (`route`, `obstacles`, `cableplan`) and checked against the parts it
would start inside (`routecheck`), written and compiled with MuJoCo's MjSpec
(`mjspec`, `contactbits`, `cablephysics`), read back as a frozen `Built`
(`modelread`, `built`), given a timestep (`substeps`) and a checker's view
(`checkview`); `stages` runs these in order. `static` builds a scene with no
MuJoCo model at all, for a static check.

This package steps nothing (`cablecheck.run`) and decides no interference
(`cablecheck.checker`).
"""
