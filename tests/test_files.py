"""Writes never leave half-made work: a failed write keeps the old file and no temporary; a failed
folder leaves nothing; work is never overwritten. A folder's lock keeps it to one writer and is taken
over when its holder is gone."""

import json
import os
import socket
import subprocess
import sys
import time

import pytest

from rlcontroller.config import ConfigError
from rlcontroller.files import LOCK, active_holder, atomic_write, check_new_folder, folder_lock, new_folder


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


def write_lock(folder, pid, host=None):
    holder = {
        "host": host or socket.gethostname(),
        "pid": pid,
        "what": "rlc sweep",
        "started": "2026-11-23T00:00:00",
    }
    (folder / LOCK).write_text(json.dumps(holder))


def test_a_live_holder_keeps_the_folder_and_is_named(tmp_path):
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        write_lock(tmp_path, sleeper.pid)
        with pytest.raises(ConfigError) as error, folder_lock(tmp_path, "rlc train"):
            pass
        message = str(error.value)
        assert (
            f"in use by rlc sweep on {socket.gethostname()} (pid {sleeper.pid}, since 2026-11-23" in message
        )
        assert "\n" not in message and active_holder(tmp_path) is not None
    finally:
        sleeper.kill()
        sleeper.wait()


def test_a_lock_left_by_a_dead_process_is_taken_over_and_released(tmp_path):
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    write_lock(tmp_path, gone.pid)
    assert active_holder(tmp_path) is None
    with folder_lock(tmp_path, "rlc train"):
        holder = json.loads((tmp_path / LOCK).read_text())
        assert holder["pid"] == os.getpid() and holder["what"] == "rlc train"
        with pytest.raises(ConfigError, match="in use by rlc train"), folder_lock(tmp_path, "rlc sweep"):
            pass  # not re-entrant: one writer
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_a_lock_on_another_host_is_respected(tmp_path):
    write_lock(tmp_path, 1, host="some-other-machine")
    with (
        pytest.raises(ConfigError, match="on some-other-machine \\(pid 1"),
        folder_lock(tmp_path, "rlc train"),
    ):
        pass


def test_an_unreadable_lock_is_stale_only_after_a_grace_period(tmp_path):
    (tmp_path / LOCK).write_text("")  # a holder killed between creating and writing it, or still writing
    with (
        pytest.raises(ConfigError, match="a process still writing its lock"),
        folder_lock(tmp_path, "rlc train"),
    ):
        pass
    old = time.time() - 60
    os.utime(tmp_path / LOCK, (old, old))
    with folder_lock(tmp_path, "rlc train"):
        pass
    assert not (tmp_path / LOCK).exists()
