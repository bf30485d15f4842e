"""The rerun recording of a run: a clash review on a `sim_time` timeline.

Entity tree (mirrors the scene, in the scene's units, z up), and the
module of this package that writes each part:
- `world/parts/<assembly path>`, `world/visual/<body>/<geom>`: the parts
  and the mjcf model's visual geoms, translucent while a clash is shown,
  floors always (:mod:`.scene`); many parts of one kind under one assembly
  level (or in all, where no level holds enough) as the instances of one
  entity, `world/parts/<level>/_boxes` and so on (:mod:`.batches`);
- `world/cables/<name>`: each cable as a chain of shaded capsules (one per
  element) at its true radius in its own colour, named, only the elements
  near a clash's worst place in its state colour (:mod:`.cables`);
- `world/interference/<type>/<a>/<b>`: the spot and its gap, and
  `lanes/<type>/<a>/<b>`: the pair's state (:mod:`.marks`);
  `world/mujoco_contacts`: MuJoCo's contact points;
- `checks/...`, `cables/{strain,bend_radius,twist}/<name>`,
  `validation/agreement`, `joints/<name>`: time series (:mod:`.series`);
- `clashes`, `events`, `summary`: the clash list, the event log and the
  summary (:mod:`.clashes`);
- `wear_map/<cable>`, `wear/<cable>/<measure>`: the wear map (:mod:`.wearview`);
- the blueprint: views, a saved viewpoint per clash, plot ranges (:mod:`.layout`).

:class:`Recorder` (:mod:`.recorder`) buffers each frame and sends
everything in columns when closed, built as arrow arrays from numpy
(:mod:`.columns`): recording costs a fraction of a step.

This package does not decide what is interference or wear; it shows what it
is given.
"""
