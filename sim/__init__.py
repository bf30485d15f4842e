"""cablecheck: dynamic interference checking of flexible cables and rigid parts.

The folder `sim/` installs as this package, `cablecheck`; the folder
`checker/` as `cablecheck.checker`. Sub-packages follow the path a scene
takes: `scene` (read and check a scene file) -> `build` (MuJoCo models) ->
`run` (simulate, check each step) with `detection` (MuJoCo's own contacts)
and `checker` (the geometry) -> `report` and `record` (the JSON report, the
rerun recording); `study` runs variants of a scene, `bench` measures,
`cli` is the command line.

This module holds no code of its own beyond the names of the public API.

The public API, imported from here (each name loads its module on first use,
so `import cablecheck` costs nothing and the checker stays MuJoCo-free)::

    import cablecheck
    scene = cablecheck.load_scene("scenes/drawer.toml")
    report = cablecheck.run_scene(scene, cablecheck.RunOptions(report="drawer.json", record=None))
    outcome = cablecheck.run_outcome(scene, cablecheck.RunOptions(report="drawer.json", record=None))
    study = cablecheck.run_study("scenes/studies/drawer_length_study.toml", out="studies")

See docs/api.md.
"""

if __name__ != "cablecheck":   # one name for one module: a second import as `sim` would duplicate every class
    raise ImportError(f"the folder sim/ is the package `cablecheck` (pip install -e .): import cablecheck, "
                      f"not {__name__}")

import importlib  # noqa: E402  (after the guard: nothing is imported under a wrong name)

_API = {
    "load_scene": "cablecheck.scene.load",
    "parse_scene": "cablecheck.scene.load",
    "Scene": "cablecheck.scene.records",
    "SceneError": "cablecheck.scene.errors",
    "RunOptions": "cablecheck.run.runner",
    "run_scene": "cablecheck.run.runner",
    "run_outcome": "cablecheck.run.runner",
    "RunOutcome": "cablecheck.report.document",
    "report_of": "cablecheck.report.document",
    "load_study": "cablecheck.study.definition",
    "run_study": "cablecheck.study.run",
    "StudyOutcome": "cablecheck.study.run",
    "version": "cablecheck.about",
}

__all__ = sorted(_API)


def __getattr__(name: str):
    """The public API's names, each imported from its module on first use (PEP 562)."""
    if name not in _API:
        raise AttributeError(f"module 'cablecheck' has no attribute {name!r}")
    value = getattr(importlib.import_module(_API[name]), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_API))
