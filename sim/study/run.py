"""A whole design study, as `cablecheck study` runs it: checked, its variants run, judged and written.

`run_study` reads the study file, checks every variant's scene and the
output folder before anything runs, runs the variants (a grid or a search)
on Dask, writes results.csv, study.json and study.png, and returns one frozen
`StudyOutcome`. It is the public API's `cablecheck.run_study`; the command line
calls it and prints.

This module prints nothing and picks no exit status (`cablecheck.cli.main`);
bad input raises `StudyError` (a `SceneError`), an unusable cluster
`StudyRunError`, an output path that cannot be written `OutputPathError`.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from cablecheck.about import version
from cablecheck.report.outputs import check_folder
from cablecheck.study.bundle import make_bundle
from cablecheck.study.cluster import check_address
from cablecheck.study.definition import (
    Method,
    Study,
    check_study_names,
    check_variants,
    load_study,
    variants,
    varied_cables,
)
from cablecheck.study.execute import VariantTask, run_search, run_variants
from cablecheck.study.plot import load_matplotlib, write_outputs
from cablecheck.study.result import Row, Window, length_window


@dataclass(frozen=True)
class StudyOutcome:
    """What a study found.

    Attributes:
      study: the study as read from its file.
      rows: one row per variant run (its values, judgement, measures and status).
      complete: False when the study was interrupted (no window, no recommendation then).
      window: the interference-free length window, for a study varying one cable's length; else None.
      units: the scene's length units.
      folder: where results.csv, study.json, study.png (and each variant's report) are.
      paths: the written outputs by kind ("csv", "json", "png", "map").
    """

    study: Study
    rows: list[Row]
    complete: bool
    window: Window | None
    units: str
    folder: Path
    paths: dict[str, Path]


def run_study(study_file: str | Path, out: str | Path = "studies", *, workers: int | None = None,
              scheduler: str | None = None, record: bool = True, resume: bool = False,
              fail_on: str = "hard", stop=None, progress: Callable | None = None,
              announce: Callable[[Study, int, str], None] | None = None) -> StudyOutcome:
    """Run the study `study_file` into `out`/<study name>/ on `workers` local processes (default: one per
    core) or the Dask `scheduler` at an address; `record` writes each variant's recording, `resume`
    keeps the variants an earlier, interrupted run finished. `stop` (`cablecheck.run.stop.StopRequest`)
    ends it early (the outcome then says `complete=False`); `progress(done, total)` is called as
    variants finish; `announce(study, runs, where)` once everything is checked, before any run."""
    out = Path(out)
    check_folder(out, "--out")
    if scheduler is not None:
        check_address(scheduler)   # the address's form, its host and TLS settings, before any work
    study = load_study(Path(study_file))
    folder = out / study.name
    check_folder(folder, "study folder (--out/<name>)")
    found = variants(study)   # a search's: the corners of its box
    scenes = check_variants(study, found)   # every variant's scene, before anything runs
    check_study_names(study, scenes[0])
    searching = study.search.method is Method.OPTIMISE
    local = f"{workers or os.cpu_count() or 1}"
    if announce is not None:
        announce(study, study.search.budget if searching else len(found),
                 f"the Dask scheduler at {scheduler}" if scheduler else f"{local} local worker process(es)")
    if searching:
        rows, complete = run_search(study, record, folder, workers=workers, scheduler=scheduler, stop=stop,
                                    progress=progress, resume=resume, spare=load_matplotlib)
    else:
        bundle, datas = make_bundle(study.scene_path, [v.data for v in found])
        tasks = [VariantTask(id=v.id, data=d, record=record) for v, d in zip(found, datas)]
        rows, complete = run_variants(tasks, {v.id: v.values for v in found}, bundle, folder, workers=workers,
                                      scheduler=scheduler, stop=stop, progress=progress,
                                      judged=(study.requirements, study.goal), resume=resume,
                                      spare=load_matplotlib)
    units = scenes[0].units
    window = None   # no window, and no recommendation, from an interrupted study
    vary = study.vary[0] if len(study.vary) == 1 else None
    if complete and not searching and vary is not None and vary.path.startswith("cables[") and \
            vary.path.endswith(".length") and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                 for x in vary.values):
        window = length_window(rows, cable=varied_cables(study)[0])   # the varied cable's own answer
    settings = {"fail_on": fail_on, "record": record, "cluster": scheduler or f"local, {local} workers",
                "version": version()}
    paths = write_outputs(folder, study, rows, complete=complete, units=units, window=window, settings=settings)
    return StudyOutcome(study=study, rows=rows, complete=complete, window=window, units=units, folder=folder,
                        paths=paths)
