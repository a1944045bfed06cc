"""End to end: a smoke run's policy through `rlc evaluate` and `rlc compare lqg` on the records."""

import pandas as pd
import pytest
from conftest import REPOSITORY
from typer.testing import CliRunner

from rlcontroller.cli import app
from rlcontroller.config import load_experiment
from rlcontroller.training import train


@pytest.fixture(scope="module")
def smoke_run(tmp_path_factory):
    experiment = load_experiment(REPOSITORY / "configs" / "smoke.yaml")
    run = tmp_path_factory.mktemp("smoke") / "run"
    train(
        experiment.model_copy(update={"algorithm": experiment.algorithm.model_copy(update={"total_steps": 500})}),
        run_dir=run,
    )
    return run


def test_evaluate_writes_tables_and_plots_with_finite_numbers(smoke_run, records, tmp_path):
    out = tmp_path / "evaluation"
    result = CliRunner().invoke(app, ["evaluate", str(smoke_run), "--records", str(records), "--out", str(out)])
    assert result.exit_code == 0, result.output
    for name in (
        "metrics.csv",
        "per_record.csv",
        "summary.csv",
        "summary.md",
        "per_record.md",
        "time_histories.png",
        "metrics_per_story.png",
    ):
        assert (out / name).is_file() and (out / name).stat().st_size > 0, name
    metrics = pd.read_csv(out / "metrics.csv")
    assert set(metrics["controller"]) == {
        "uncontrolled",
        "LQG",
        "LQG + ground",
        "LQG + ground model",
        "RL",
        "optimal (clairvoyant)",
    }
    assert metrics["value"].notna().all() and (metrics["value"] >= 0).all()
    assert len(set(metrics["record"])) == 7 and set(metrics["suite"]) == {"PEER NGA-West2 records (7), as recorded"}
    summary = (out / "summary.md").read_text()
    assert "RL better than LQG (%)" in summary and "PEER NGA-West2" in summary
    assert "RL better than LQG" in result.output


def test_compare_lqg_sweep_and_preview_mark_the_policy(smoke_run, records, tmp_path):
    out = tmp_path / "compare"
    result = CliRunner().invoke(
        app, ["compare", "lqg", str(smoke_run), "--records", str(records), "--out", str(out), "--sweep", "--preview"]
    )
    assert result.exit_code == 0, result.output
    sweep = pd.read_csv(out / "lqg_sweep.csv")
    assert len(sweep) == 9 and sweep[["J1", "J2", "J3", "J4"]].notna().all().all()
    assert (out / "lqg_sweep.png").is_file()
    assert "- RL: J3 =" in (out / "lqg_sweep.md").read_text()
    preview = pd.read_csv(out / "preview.csv")
    assert list(preview["preview_s"])[:2] == [0.0, 0.02] and preview["J1"].is_monotonic_decreasing
    assert (out / "preview.png").is_file()
    assert "- LQG + ground: J1 =" in (out / "preview.md").read_text()


def test_compare_lqg_without_a_run_on_the_synthetic_suite(tmp_path, monkeypatch):
    monkeypatch.delenv("RLC_RECORDS", raising=False)
    result = CliRunner().invoke(app, ["compare", "lqg", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert "SYNTHETIC" in (tmp_path / "summary.md").read_text()
    assert "SYNTHETIC" in pd.read_csv(tmp_path / "metrics.csv")["suite"].iloc[0]


def test_missing_records_exit_2_with_one_line(smoke_run, tmp_path):
    result = CliRunner().invoke(
        app, ["evaluate", str(smoke_run), "--records", str(tmp_path), "--out", str(tmp_path / "o")]
    )
    assert result.exit_code == 2
    lines = result.output.strip().splitlines()
    assert lines[-1].startswith("error: ") and "7 of 7 records missing" in lines[-1]


def test_evaluate_refuses_a_folder_that_is_not_a_run(tmp_path):
    result = CliRunner().invoke(app, ["evaluate", str(tmp_path)])
    assert result.exit_code == 2 and "not a run folder" in result.output


def test_the_committed_model_evaluates_from_a_fresh_clone(records, tmp_path):
    """`rlc evaluate` without RUN_DIR uses models/five_story: a residual PPO policy on LQG."""
    result = CliRunner().invoke(app, ["evaluate", "--records", str(records), "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    summary = pd.read_csv(tmp_path / "summary.csv", index_col="controller")
    assert summary.loc["RL", "J1"] < 0.5 and summary.loc["RL", "J2"] < 1.0
    assert summary.loc["RL", "J1"] < summary.loc["LQG", "J1"] + 0.02


def test_evaluate_scaled_records_with_the_final_model(smoke_run, records, tmp_path):
    args = [
        "evaluate",
        str(smoke_run),
        "--records",
        str(records),
        "--out",
        str(tmp_path),
        "--scale-pga",
        "0.3",
        "--model",
        "final",
    ]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    assert "scaled to PGA 0.3 g" in (tmp_path / "summary.md").read_text()
    bad = CliRunner().invoke(app, ["evaluate", str(smoke_run), "--model", "newest"])
    assert bad.exit_code == 2 and "--model: expected best or final" in bad.output
