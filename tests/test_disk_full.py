"""A full disk during a command that writes (aggregate, export, check, sweep, tune): one line naming
the path (exit code 1), nothing half-written, and the same command succeeds once there is space again.
The disk fills at the Nth write of the command (every write goes through `rlcontroller.files`): half the
bytes reach the temporary file, then ENOSPC (or EROFS / EACCES for a read-only or forbidden folder)."""

import errno
import os
import shutil

import pytest
from conftest import NETWORK_POLICY, REPOSITORY
from typer.testing import CliRunner

from rlcontroller import files
from rlcontroller.cli import app


def fill_disk_at(monkeypatch, write_number: int, error: int = errno.ENOSPC) -> None:
    """Writes before `write_number` succeed; that one and every later one find the disk full (or,
    with `error`, read-only or forbidden: the tests run as root, which ignores permissions)."""
    original = files._replace_with
    count = {"writes": 0}

    def full(path, temporary, write):
        count["writes"] += 1
        if count["writes"] < write_number:
            return original(path, temporary, write)
        temporary.write_bytes(b"half")
        temporary.unlink()
        raise OSError(error, os.strerror(error), str(path))

    monkeypatch.setattr(files, "_replace_with", full)


def files_under(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


def one_filesystem_line(result, message: str = "No space left on device") -> str:
    assert result.exit_code == 1 and "Traceback" not in result.output, result.output
    line = result.output.strip().splitlines()[-1]
    assert line.startswith("error: ") and message in line, result.output
    return line


def aggregate_inputs(tmp_path):
    from multirun.test_aggregate import write_metrics

    return [str(write_metrics(tmp_path / f"seed{s}", {"RL": [0.4 + 0.05 * s, 0.6]})) for s in range(3)]


@pytest.mark.slow
@pytest.mark.parametrize("write_number", [1, 2, 3])
def test_aggregate_on_a_full_disk(tmp_path, monkeypatch, write_number):
    runs = aggregate_inputs(tmp_path)
    out = tmp_path / "aggregate"
    before = files_under(tmp_path)
    fill_disk_at(monkeypatch, write_number)
    line = one_filesystem_line(CliRunner().invoke(app, ["aggregate", *runs, "--out", str(out)]))
    assert "aggregate" in line and files_under(tmp_path) == before  # no output folder, no temporary
    monkeypatch.undo()
    assert CliRunner().invoke(app, ["aggregate", *runs, "--out", str(out)]).exit_code == 0
    assert {p.name for p in out.iterdir()} == {"aggregate.csv", "aggregate.md", "aggregate.png"}


@pytest.mark.parametrize("error", [errno.EROFS, errno.EACCES])
def test_aggregate_into_a_read_only_or_forbidden_folder(tmp_path, monkeypatch, error):
    runs = aggregate_inputs(tmp_path)
    out = tmp_path / "aggregate"
    before = files_under(tmp_path)
    fill_disk_at(monkeypatch, 1, error)
    line = one_filesystem_line(
        CliRunner().invoke(app, ["aggregate", *runs, "--out", str(out)]), os.strerror(error)
    )
    assert "aggregate" in line and files_under(tmp_path) == before
    monkeypatch.undo()
    assert CliRunner().invoke(app, ["aggregate", *runs, "--out", str(out)]).exit_code == 0


def test_export_on_a_full_disk(tmp_path, monkeypatch):
    pytest.importorskip("onnx")
    folder = tmp_path / "model"
    shutil.copytree(REPOSITORY / "models" / "five_story_every_story", folder)
    out = tmp_path / "controller.onnx"
    before = files_under(tmp_path)
    fill_disk_at(monkeypatch, 1)
    line = one_filesystem_line(CliRunner().invoke(app, ["export", str(folder), "--out", str(out)]))
    assert "controller.onnx" in line and files_under(tmp_path) == before
    monkeypatch.undo()
    assert (
        CliRunner().invoke(app, ["export", str(folder), "--out", str(out)]).exit_code == 0 and out.is_file()
    )


@pytest.mark.slow
def test_check_on_a_full_disk_keeps_the_old_verdict(tmp_path, monkeypatch):
    import yaml

    folder = tmp_path / "model"
    shutil.copytree(NETWORK_POLICY, folder)
    old = folder / "best_check-quick.yaml"  # the verdict under the standard quick.yaml
    old.write_text("passed: true\n")  # an old verdict, to be replaced
    quick = tmp_path / "quick.yaml"
    standard = yaml.safe_load((REPOSITORY / "configs" / "checks" / "standard.yaml").read_text())
    quick.write_text(yaml.safe_dump(standard | {"motions": 2, "rest_runs": 1, "rest_duration": 2.0}))
    before = files_under(tmp_path)
    fill_disk_at(monkeypatch, 1)
    arguments = ["check", str(folder), "--standard", str(quick)]
    line = one_filesystem_line(CliRunner().invoke(app, arguments))
    assert "best_check-quick.yaml" in line and files_under(tmp_path) == before
    assert old.read_text() == "passed: true\n"
    monkeypatch.undo()
    assert CliRunner().invoke(app, arguments).exit_code in (0, 1)  # the verdict is written either way
    assert old.read_text() != "passed: true\n"


@pytest.mark.slow
def test_a_sweep_whose_disk_fills_at_its_table_resumes_without_retraining(tmp_path, monkeypatch):
    import yaml

    config = tmp_path / "tiny.yaml"
    config.write_text((REPOSITORY / "configs" / "testing" / "tiny.yaml").read_text())
    out = tmp_path / "sweep"
    fill_disk_at(monkeypatch, 1)  # the workers (other processes) write their runs; the sweep's table fails
    line = one_filesystem_line(
        CliRunner().invoke(app, ["sweep", str(config), "--seeds", "0", "--out", str(out)])
    )
    assert "sweep.csv" in line and not (out / ".lock").exists() and not (out / "sweep.csv").exists()
    model = out / "seed0" / "final_model.zip"
    stamp = model.stat().st_mtime_ns
    monkeypatch.undo()
    again = CliRunner().invoke(app, ["sweep", str(config), "--seeds", "0", "--out", str(out)])
    assert again.exit_code == 0 and "finished before" in again.output, again.output
    assert model.stat().st_mtime_ns == stamp and yaml.safe_load(
        (out / "sweep.csv").read_text().splitlines()[0]
    )


@pytest.mark.slow
def test_tune_on_a_full_disk_fails_the_trial_and_the_same_command_finishes_the_study(tmp_path, monkeypatch):
    import yaml
    from multirun.test_tuning import TUNED

    config = tmp_path / "tuned.yaml"
    config.write_text(yaml.safe_dump(TUNED))
    out = tmp_path / "tune"
    arguments = ["tune", str(config), "--trials", "1", "--out", str(out)]
    fill_disk_at(monkeypatch, 1)  # the trial's first write fails, and so does writing trials.csv after it
    line = one_filesystem_line(CliRunner().invoke(app, arguments))
    assert "tune" in line and not [p for p in out.rglob("*") if ".tmp" in p.name]  # no half-written file
    assert not (out / "trials.csv").exists()
    monkeypatch.undo()
    again = CliRunner().invoke(app, arguments)
    assert again.exit_code == 0, again.output
    states = [row.split(",")[1] for row in (out / "trials.csv").read_text().splitlines()[1:]]
    assert sorted(states) == ["COMPLETE", "FAIL"]  # the full disk's trial is kept as failed, one more ran
