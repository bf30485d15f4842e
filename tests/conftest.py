"""Test configuration: hypothesis runs without deadlines (2-core CI shares the
machine) and with fixed draws (HYPOTHESIS_PROFILE=random or long for new ones);
MuJoCo's default warning handler writes no MUJOCO_LOG.TXT into the
repository while the tests step models of their own (a run takes MuJoCo's
messages itself, `cablecheck.run.mjlog`)."""

import os

import pytest
from hypothesis import settings

# the README's test command (what CI runs) draws the same examples every time: a red run is
# the code's, reproducible, never a new draw's luck; HYPOTHESIS_PROFILE=random draws anew
settings.register_profile("ci", deadline=None, derandomize=True, print_blob=True)
settings.register_profile("random", deadline=None, print_blob=True)
# a longer local run of the property tests that read it (e.g. tests/test_reference_static.py):
# --hypothesis-profile=long, or HYPOTHESIS_PROFILE=long
settings.register_profile("long", deadline=None, max_examples=1000, print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE") or "ci")


@pytest.fixture(autouse=True, scope="session")
def _no_mujoco_log_file():
    from cablecheck.run.mjlog import log_file_off

    with log_file_off():
        yield
