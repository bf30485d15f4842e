"""Load a cablecheck scene (TOML) into validated, SI-unit records.

`load_scene` reads the file, `parse_scene` checks a dict as `tomllib` returns
it. Every problem is a `SceneError` naming the file, the key path (for example
``cables[1].radius``, 0-based indices) and the problem; nothing else escapes.

Conventions of the records:

- Lengths are in metres (MuJoCo simulates in SI); `Scene.scale` is metres per
  scene unit so that reports can convert back. Angles stay in degrees
  (`euler`, MuJoCo's default intrinsic x-y-z sequence). Young's modulus (Pa),
  density (kg/m^3) and times (s) are unchanged.
- `check.spacing` and `check.attach_zone` are multiples of the cable radius;
  `check.clearance` is in metres.
- Joint keyframe values stay as written (degrees for hinges, scene units for
  slides) in `MotionDef.keys`; every motion's `Trajectory` holds its samples
  in MuJoCo units (radians, metres), on scene time (`time_scale` applied).
- Positions of parts, clips and cable ends are in the frame of the body they
  ride on; `via`, `points` and `CableDef.route` are world coordinates at t = 0.
  "At t = 0" is the pose the motion script gives: a keyframed body at its
  first key's pose (before the first key a body holds it), any other
  `[[bodies]]` body at its `[[bodies]]` pose, and the mjcf model at `qpos0`
  with each driven joint at its first sample's value. `Scene.start_frames`
  holds these frames, so the builder need not work them out again.

The mjcf model is compiled once here (to know its bodies, joints and the
pose of its bodies at qpos0); meshes are loaded with trimesh to check they
exist, load, and (for keepout parts) are closed. The builder loads both again.
A mesh part whose file is glTF / GLB expands into one part per mesh node of
the file, named ``<name>/<node path>`` (`cablecheck.scene.meshfile`).

A `[[motion]]` gives keys, the mjcf model's keyframes (``key = "home"``) or a
CSV file of samples (`read_samples`); every sample of a joint with a range
(`jnt_limited`) must lie in it. Both interpolations (`cablecheck.run.curves`) stay
between neighbouring samples, so the samples bound the whole motion.

`[[allow]]` names (`AllowDef`) must cover a scene part or cable (by name or
assembly path prefix) or, with an mjcf model, begin with one of its bodies:
its geoms' part names are the builder's, so those are checked against the
built parts once the model exists (`check_allow_names`). So must a cable
end's or clip's `part` (the parts it is fastened to: a part name or assembly
path, `check_fastened_names`).

Where things are: `load` (`load_scene`, `parse_scene`: the tables in order),
`reader` (single values), one module per table (`settings`, `parts`,
`cables`, `motion` with `samples` and `trajectory`, `allow`), `mjcf` and
`frames` (the base model, the frames at t = 0), `records` (what a scene
is), `format` (keys, values, defaults, bounds) and `errors` (`SceneError`).
This package reads and checks; it builds no model (`cablecheck.build.stages`) and runs
nothing (`cablecheck.run.runner`).
"""
