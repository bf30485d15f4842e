"""Contact bits (cablecheck.build.contactbits): only the listed interactions push back,
an MJCF model's own bits are kept and filter the part pairs, and the detection
model collides the cables alone."""

from __future__ import annotations

import numpy as np
from buildscenes import arm_built, run_steps, slider_scene


def test_only_listed_interactions_push_back(tmp_path):
    data = slider_scene(tmp_path)
    # a shelf below the sagging cable rises through it during the motion
    data["bodies"].append({"name": "lift"})
    data["parts"][0] = {"name": "lift/shelf", "body": "lift", "shape": "box",
                        "size": [0.1, 0.2, 0.01], "pos": [0.3, 0, 0.2]}
    data["motion"].append({"body": "lift", "keys": [{"t": 0, "pos": [0, 0, 0]}, {"t": 0.2, "pos": [0, 0, 0.2]}]})
    _, resolved = run_steps(data, tmp_path, contacts=False)
    data["effects"] = {"contact": []}
    _, ghost = run_steps(data, tmp_path, contacts=False)
    top = 0.4 + 0.01  # the shelf's top face at the end
    over = lambda states: states[-1].cables[0][np.abs(states[-1].cables[0][:, 0] - 0.3) < 0.05, 2]  # noqa: E731
    assert over(resolved).min() > top + 0.004 - 2e-3  # lifted: lies on the shelf
    assert over(ghost).min() < top - 0.05  # passed through: never pushed


def test_the_models_own_bits_are_kept_and_filter_part_pairs(tmp_path):
    from cablecheck.run.stepcheck import part_pairs_skipped
    built = arm_built(tmp_path, visuals=True, effects=("cable-structure", "part-part"))
    by = {p.name: p.geom_id for p in built.parts}
    m, det = built.model, built.detect
    # the scene's bits are the three lowest the model leaves free (it uses 1 and 2): 4, 8, 16
    cable, part = 4, 16
    assert m.flex_contype[0] == cable
    for name, own in {"stand/column": (1, 1), "link/capsule0": (2, 0), "link/sphere2": (0, 2)}.items():
        g = by[name]
        assert (m.geom_contype[g], m.geom_conaffinity[g]) == (own[0], own[1] | cable | part)
        assert (det.geom_contype[g], det.geom_conaffinity[g]) == (0, cable)    # detection: cables' contacts only
    assert (m.geom_contype[by["cell/table"]], m.geom_conaffinity[by["cell/table"]]) == (part, part | cable)
    assert (det.geom_contype[by["cell/table"]], det.geom_conaffinity[by["cell/table"]]) == (0, cable)
    # without part-part the model's geoms take no part in collisions but the cable's
    only_cable = arm_built(tmp_path, visuals=True)
    g = [p.geom_id for p in only_cable.parts if p.name == "stand/column"][0]
    assert (only_cable.model.geom_contype[g], only_cable.model.geom_conaffinity[g]) == (0, cable)
    skip = part_pairs_skipped(built)
    idx = {p.name: k for k, p in enumerate(built.parts)}
    # the rod (2/1) meets the column (1/1) and the sphere (0/2), never the capsule or lug (2/0)
    assert not skip[idx["stand/column"], idx["post/rod"]] and not skip[idx["link/sphere2"], idx["post/rod"]]
    assert skip[idx["link/capsule0"], idx["post/rod"]] and skip[idx["post/rod"], idx["link/lug"]]
    # scene parts meet every model geom
    assert not skip[idx["cell/table"], idx["link/capsule0"]] and not skip[idx["cell/table"], idx["stand/column"]]


def test_the_detection_model_reports_only_the_cables_contacts(tmp_path):
    """Parts that meet each other (the arm's rod in its column, with
    part-part contact on in the simulation model): the simulation model
    collides them; the detection model, whose contacts validation compares
    with the cables' records only, reports the cables' contacts and no
    part-part one."""
    import mujoco

    built = arm_built(tmp_path, visuals=True, effects=("cable-structure", "part-part"))
    found = {}
    for name, model in (("simulation", built.model), ("detection", built.detect)):
        d = mujoco.MjData(model)
        mujoco.mj_forward(model, d)
        flex = np.asarray(d.contact.flex[:d.ncon]).reshape(-1, 2)
        found[name] = (int(np.sum((flex < 0).all(axis=1))), int(np.sum((flex >= 0).any(axis=1))))
    assert found["simulation"][0] > 0            # parts pressed together where part-part is asked
    assert found["detection"][0] == 0
