"""The product's version and MuJoCo's, as installed: for the report, the study summary and `--version`.

This module imports nothing heavy (the command line reads it before any
other work); it does not import MuJoCo to ask its version.
"""

from __future__ import annotations

from importlib import metadata


def version() -> str:
    """The installed product version."""
    try:
        return metadata.version("cablecheck")
    except metadata.PackageNotFoundError:   # run from a source tree that was never installed
        return "unknown"


def mujoco_version() -> str | None:
    """The installed MuJoCo distribution's version (the engine's package, or the meta-package), or None."""
    for name in ("mujoco-core", "mujoco"):
        try:
            return metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
    return None
