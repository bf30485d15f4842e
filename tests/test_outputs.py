"""Output paths are checked before any work: folders, files in the way, permissions."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from cablecheck.report.outputs import OutputPathError, check_folder, check_output


def test_a_new_file_in_a_new_folder_is_fine(tmp_path: Path):
    assert check_output(tmp_path / "a" / "b" / "r.json", "--report") == tmp_path / "a" / "b" / "r.json"
    assert not (tmp_path / "a").exists()   # nothing is written by the check


def test_a_folder_is_not_a_file(tmp_path: Path):
    with pytest.raises(OutputPathError, match="is a folder"):
        check_output(tmp_path, "--report")


def test_a_file_in_the_way(tmp_path: Path):
    (tmp_path / "f").write_text("")
    with pytest.raises(OutputPathError, match="is a file, not a folder"):
        check_output(tmp_path / "f" / "g" / "r.json", "--record")
    with pytest.raises(OutputPathError, match="is a file; give a folder"):
        check_folder(tmp_path / "f", "--out")


def test_no_permission(tmp_path: Path, monkeypatch):
    """The deepest existing folder must be writable (asked of os.access, which
    answers True for root whatever the mode, hence answered here)."""
    locked = tmp_path / "locked"
    locked.mkdir()
    monkeypatch.setattr(os, "access", lambda path, mode: Path(path) != locked)
    with pytest.raises(OutputPathError, match=f"no permission to write in {locked}"):
        check_output(locked / "new" / "r.json", "--report")
