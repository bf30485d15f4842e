"""Design studies: one scene, some of its values varied or searched, run on Dask, judged and summarised.

`definition` reads a study file, `goal` judges a variant's report against
its requirements and goal, `search` proposes variants where the answer is,
`execute` runs them (`run_study` the whole study), `cluster` is the Dask
cluster, `bundle` packs the files a variant needs, `result` and `plot` make
the rows, the answer, results.csv, study.json and study.png.

This package runs each variant as `cablecheck.run` does; it checks nothing
itself.
"""
