"""Writes never leave half-made work: a failed write keeps the old file and no temporary; a failed
folder leaves nothing; work is never overwritten."""

import pytest

from rlcontroller.config import ConfigError
from rlcontroller.files import atomic_write, check_new_folder, new_folder


def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path, monkeypatch):
    path = atomic_write(tmp_path / "table.csv", "old\n")
    original = type(path).write_text

    def half_then_fail(self, text, *args, **kwargs):
        original(self, text[:2], *args, **kwargs)
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(type(path), "write_text", half_then_fail)
    with pytest.raises(OSError):
        atomic_write(path, "new content\n")
    monkeypatch.undo()
    assert path.read_text() == "old\n" and [p.name for p in tmp_path.iterdir()] == ["table.csv"]
    assert atomic_write(path, b"bytes").read_bytes() == b"bytes"


def test_a_folder_that_fails_to_fill_leaves_nothing_and_a_full_one_is_never_overwritten(tmp_path):
    with pytest.raises(RuntimeError), new_folder(tmp_path / "out") as staging:
        (staging / "half.csv").write_text("1")
        raise RuntimeError("interrupted")
    assert list(tmp_path.iterdir()) == []
    with new_folder(tmp_path / "out") as staging:
        (staging / "whole.csv").write_text("1")
    assert [p.name for p in (tmp_path / "out").iterdir()] == ["whole.csv"]
    with pytest.raises(ConfigError, match="exists and is not empty"):
        check_new_folder(tmp_path / "out")
