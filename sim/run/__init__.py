"""The run stage: simulate a built scene, check each step, and hand on one frozen outcome.

`runner` (`run_scene`, `run_outcome`, `RunOptions`) owns the order of a run;
`loop` and `kinematic` step it (with MuJoCo, or moving bodies by script
alone), `motion` and `curves` apply the script, `ahead` steps on a thread of
its own, `stepcheck` checks batches of states, `divergence` finds a diverged
simulation, `jointspace` logs the moving joints, `mjlog` takes MuJoCo's
messages, `stop` takes Ctrl-C and SIGTERM. `sweep` is the `sweep` command's
run: parts moved along a line, no simulation.

This package does not parse arguments or print (`cablecheck.cli`), lay out
the report (`cablecheck.report`) or draw (`cablecheck.record`).
"""
