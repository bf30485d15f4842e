"""Benchmarks and validation cases: `cablecheck bench`, harness scenes of any size, analytic references.

`command` is the `bench` command, `table` and `plot` its output, `scenes`
its randomised scenes, `checker_tables`, `sim_tables` and `fcl` its
measurements, `reference` and `physics_cases` the cable model against closed
forms, `harness` a harness-like scene of any size.

Nothing in a run imports this package.
"""
