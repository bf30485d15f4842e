"""benchmarks/relayout.py: a revision exported by git archive imports as `cablecheck` from its own folder,
whether from before the move into stage packages (rewritten) or after it (linked); the rewrite's rules on a
small made-up old tree."""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("relayout", ROOT / "benchmarks" / "relayout.py")
relayout = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(relayout)

LAST_BEFORE_THE_MOVE = "91e2737"


def _files(tree: Path, modules: list[str]) -> dict[str, str]:
    """`__file__` of each module imported in a fresh interpreter with PYTHONPATH = tree (as the benchmarks'
    children run)."""
    code = f"import importlib, json; print(json.dumps({{m: importlib.import_module(m).__file__ for m in {modules!r}}}))"
    proc = subprocess.run([sys.executable, "-P", "-c", code], cwd=tree, capture_output=True, text=True,
                          env=dict(os.environ, PYTHONPATH=str(tree)), timeout=120, check=False)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _archive(rev: str, tree: Path) -> None:
    tree.mkdir()
    data = subprocess.run(["git", "-C", str(ROOT), "archive", rev, "checker", "sim"], capture_output=True,
                          check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(tree)], input=data, check=True)


@pytest.mark.parametrize("rev, rewritten", [(LAST_BEFORE_THE_MOVE, True), ("HEAD", False)])
def test_an_exported_revision_imports_from_its_own_folder(tmp_path, rev, rewritten):
    if subprocess.run(["git", "-C", str(ROOT), "cat-file", "-e", f"{rev}^{{commit}}"],
                      capture_output=True, check=False).returncode != 0:
        pytest.skip(f"{rev} is not in this clone's history")
    tree = tmp_path / "tree"
    _archive(rev, tree)
    assert relayout.relayout(tree) is rewritten
    files = _files(tree, ["cablecheck.run.runner", "cablecheck.checker.cable", "cablecheck.build.stages"])
    for name, f in files.items():
        assert Path(f).resolve().is_relative_to(tree.resolve()), (name, f)
    if rewritten:
        assert (tree / "sim" / "run" / "runner.py").is_file() and not (tree / "sim" / "run.py").exists()
        assert "from sim." not in (tree / "sim" / "run" / "runner.py").read_text()


def test_a_module_the_revision_lacks_fails_instead_of_loading_this_checkout(tmp_path):
    """The editable install would answer `cablecheck.about` (after the move) from this checkout."""
    tree = tmp_path / "tree"
    (tree / "sim" / "run").mkdir(parents=True)
    (tree / "checker").mkdir()
    for p in ("sim/__init__.py", "sim/run/__init__.py", "checker/__init__.py"):
        (tree / p).write_text("")
    assert relayout.relayout(tree) is False
    proc = subprocess.run([sys.executable, "-P", "-c", "import cablecheck.about"], cwd=tree, capture_output=True,
                          text=True, env=dict(os.environ, PYTHONPATH=str(tree)), timeout=60, check=False)
    assert proc.returncode != 0 and "ModuleNotFoundError" in proc.stderr


def test_the_rewrite_moves_by_the_table_keeps_unknown_names_and_resolves_facades(tmp_path):
    tree = tmp_path / "tree"
    (tree / "sim").mkdir(parents=True)
    (tree / "checker").mkdir()
    sources = {
        "sim/__init__.py": "",
        # a single-file scene beside meshfile (which the table puts in the scene package): its __init__
        "sim/scene.py": "from sim.meshfile import MESH\nSCENE = 'scene ' + MESH\n",
        "sim/meshfile.py": "MESH = 'mesh'\n",
        "sim/record.py": "import sim.run\nRECORD = sim.run.RUN  # sim.run.RUN\n",          # not in the table
        "sim/build.py": "from sim.scene import SCENE\nfrom checker.cable import CABLE\n",  # a facade
        "sim/run.py": ("from sim.build import SCENE, CABLE as C\nfrom sim import meshfile\n"
                       "RUN = (SCENE, C, meshfile.MESH, 'sim/run.py')\n"),
        "sim/benchsim.py": "from pathlib import Path\nREPO = Path(__file__).resolve().parents[1]\n",
        "checker/__init__.py": "",
        "checker/cable.py": "CABLE = 'cable'\n",
    }
    for p, text in sources.items():
        (tree / p).write_text(text)
    assert relayout.relayout(tree) is True
    sim = tree / "sim"
    assert sorted(str(p.relative_to(sim)) for p in sim.rglob("*.py") if "checker" not in p.parts) == [
        "__init__.py", "bench/__init__.py", "bench/sim_tables.py", "build/__init__.py", "build/stages.py",
        "record.py", "run/__init__.py", "run/runner.py", "scene/__init__.py", "scene/meshfile.py"]
    runner = (sim / "run" / "runner.py").read_text()
    assert "from cablecheck.scene import SCENE; from cablecheck.checker.cable import CABLE as C" in runner
    assert "from cablecheck.scene import meshfile" in runner and "'sim/run/runner.py'" in runner
    assert (sim / "record.py").read_text() == ("import cablecheck.run.runner\n"
                                               "RECORD = cablecheck.run.runner.RUN  # cablecheck.run.runner.RUN\n")
    assert "parents[2]" in (sim / "bench" / "sim_tables.py").read_text()
    code = ("import cablecheck.record, cablecheck.bench.sim_tables as b, pathlib; "
            "print(cablecheck.record.RECORD, b.REPO == pathlib.Path.cwd().resolve())")
    proc = subprocess.run([sys.executable, "-P", "-c", code], cwd=tree, capture_output=True, text=True,
                          env=dict(os.environ, PYTHONPATH=str(tree)), timeout=60, check=False)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "('scene mesh', 'cable', 'mesh', 'sim/run/runner.py') True"
