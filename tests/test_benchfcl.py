"""The collision-library side of the benchmark (cablecheck.bench.fcl): without
python-fcl it says how to install it. The comparison itself runs in
test_bench on the tiny sizes."""

from __future__ import annotations

import pytest


def test_without_python_fcl_the_comparison_says_how_to_install_it(monkeypatch):
    import sys

    from cablecheck.bench.fcl import FclMissing, fcl_queries
    from cablecheck.bench.scenes import make_scene
    from cablecheck.checker.scene_state import CheckConfig

    monkeypatch.setitem(sys.modules, "fcl", None)   # what an absent package looks like to import
    cables, parts = make_scene(n_cables=2, n_points=5, n_prims=3, n_meshes=0)
    with pytest.raises(FclMissing, match=r"pip install 'cablecheck\[bench\]'"):
        fcl_queries(cables, parts, CheckConfig("points"), 1)
