"""Test configuration: hypothesis runs without deadlines (2-core CI shares the
machine) and, under CI, with a fixed seed so a red run can be reproduced."""

import os

from hypothesis import settings

settings.register_profile("default", deadline=None)
settings.register_profile("ci", deadline=None, derandomize=True, print_blob=True)
settings.load_profile("ci" if os.environ.get("CI") else "default")
