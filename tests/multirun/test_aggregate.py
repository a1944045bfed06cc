"""Statistics over seeds: the interquartile mean, stratified-bootstrap intervals that cover, and the
tables from evaluation folders."""

import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
from conftest import run_at_a_terminal

from rlcontroller.config import ConfigError
from rlcontroller.multirun.aggregate import aggregate, interquartile_mean, scores, stratified_bootstrap


def test_the_interquartile_mean_drops_a_quarter_at_each_end():
    assert interquartile_mean(np.arange(1.0, 9.0)) == pytest.approx(4.5)  # mean of 3, 4, 5, 6
    assert interquartile_mean(np.array([0.4, 0.5, 0.5, 0.6, 0.5, 0.5, 0.5, 90.0])) == pytest.approx(0.5)


def test_identical_runs_give_intervals_of_zero_width():
    matrix = np.tile(np.array([0.3, 0.5, 0.7]), (4, 1))  # 4 runs, 3 records, every run the same
    intervals = stratified_bootstrap(matrix, np.random.default_rng(0), reps=200)
    assert intervals["mean_low"] == pytest.approx(0.5) and intervals["mean_high"] == pytest.approx(0.5)


def test_the_intervals_cover_the_true_mean_about_95_percent_of_the_time():
    rng = np.random.default_rng(1)
    record_means = np.array([0.3, 0.5, 0.7, 0.9, 0.4])
    covered = 0
    for _ in range(200):
        matrix = record_means + rng.normal(0.0, 0.1, (10, 5))  # 10 runs: seed-to-seed spread per record
        intervals = stratified_bootstrap(matrix, rng, reps=400)
        covered += intervals["mean_low"] <= record_means.mean() <= intervals["mean_high"]
    assert 0.85 <= covered / 200 <= 0.99


def write_metrics(folder, values: dict[str, list[float]], records=("a", "b")):
    """An evaluation folder: metrics.csv with one value per controller, record and story."""
    rows = []
    for controller, per_record in values.items():
        for record, value in zip(records, per_record, strict=True):
            for metric in ("J1", "J2"):
                rows += [
                    {
                        "controller": controller,
                        "record": record,
                        "metric": metric,
                        "index": i,
                        "value": value + i * 0.01,
                    }
                    for i in (1, 2, 3)
                ]
    folder.mkdir(parents=True)
    pd.DataFrame(rows).to_csv(folder / "metrics.csv", index=False)
    return folder


def test_scores_are_means_over_stories_and_statistics_are_over_runs(tmp_path):
    runs = [
        write_metrics(tmp_path / f"seed{s}", {"RL": [0.4 + 0.1 * s, 0.6], "LQG": [0.5, 0.5]})
        for s in range(3)
    ]
    table = aggregate(scores(runs), reps=300)
    rl_j1 = table[(table["controller"] == "RL") & (table["metric"] == "J1")].iloc[0]
    run_means = [np.mean([0.42 + 0.1 * s, 0.62]) for s in range(3)]  # stories 1..3 add 0.01, 0.02, 0.03
    assert rl_j1["runs"] == 3 and rl_j1["mean"] == pytest.approx(np.mean(run_means))
    assert rl_j1["std"] == pytest.approx(np.std(run_means, ddof=1))
    assert rl_j1["mean_low"] <= rl_j1["mean"] <= rl_j1["mean_high"]
    assert list(dict.fromkeys(table["controller"])) == ["RL", "LQG"]


def test_runs_on_different_records_are_refused(tmp_path):
    one = write_metrics(tmp_path / "one", {"RL": [0.4, 0.5]})
    other = write_metrics(tmp_path / "other", {"RL": [0.4, 0.5]}, records=("a", "c"))
    with pytest.raises(ConfigError, match="different records"):
        scores([one, other])


@pytest.mark.slow
def test_rlc_aggregate_writes_the_tables_and_the_plot(tmp_path):
    runs = [write_metrics(tmp_path / f"seed{s}", {"RL": [0.4 + 0.05 * s, 0.6]}) for s in range(3)]
    out = tmp_path / "aggregate"
    command = [sys.executable, "-m", "rlcontroller", "aggregate", *map(str, runs), "--out", str(out)]
    done = subprocess.run(command, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "Interquartile mean" in done.stdout and "| RL | 3 |" in done.stdout
    assert {p.name for p in out.iterdir()} == {"aggregate.csv", "aggregate.md", "aggregate.png"}
    again = subprocess.run(command, capture_output=True, text=True)
    assert again.returncode == 2 and "never overwritten" in again.stderr and "Traceback" not in again.stderr
    missing = subprocess.run(
        [sys.executable, "-m", "rlcontroller", "aggregate", str(tmp_path / "nothing")],
        capture_output=True,
        text=True,
    )
    assert (
        missing.returncode == 2 and "no metrics.csv" in missing.stderr and "Traceback" not in missing.stderr
    )


def test_robustness_results_aggregate_per_scenario_and_over_all_scenarios(tmp_path):
    """robustness.csv: one group per scenario and "all scenarios" = every scenario's records pooled."""
    for run, offset in enumerate([0.0, 0.1]):
        rows = [
            {
                "scenario": scenario,
                "controller": "RL",
                "record": record,
                "metric": "J1",
                "index": story,
                "value": base + offset + 0.01 * story,
            }
            for scenario, base in (("nominal", 0.4), ("soft", 0.8))
            for record in ("a", "b")
            for story in (1, 2)
        ]
        (tmp_path / f"seed{run}").mkdir()
        pd.DataFrame(rows).to_csv(tmp_path / f"seed{run}" / "robustness.csv", index=False)
    frame = aggregate(scores([tmp_path / "seed0", tmp_path / "seed1"]), reps=50).set_index("group")
    assert frame.loc["nominal", "mean"] == pytest.approx(0.465)  # 0.4 + 0.05 (seeds) + 0.015 (stories)
    assert frame.loc["soft", "mean"] == pytest.approx(0.865)
    assert frame.loc["all scenarios", "mean"] == pytest.approx(0.665)
    assert frame.loc["all scenarios", "std"] == pytest.approx(np.std([0.615, 0.715], ddof=1))


def test_a_folder_of_runs_or_of_nothing_is_refused_with_the_way_out(tmp_path):
    from typer.testing import CliRunner

    from rlcontroller.cli import app

    (tmp_path / "sweep" / "seed0" / "evaluation").mkdir(parents=True)
    (tmp_path / "sweep" / "seed0" / "evaluation" / "metrics.csv").write_text("")
    (tmp_path / "empty").mkdir()
    for folder, expected in (
        ("sweep", "a folder of runs (seed0); give the runs: 'rlc aggregate"),
        ("empty", "no metrics.csv"),
    ):
        result = CliRunner().invoke(
            app, ["aggregate", str(tmp_path / folder), "--out", str(tmp_path / "out")]
        )
        assert result.exit_code == 2 and expected in result.output and "rlc evaluate" not in result.output


@pytest.mark.slow
def test_aggregate_shows_its_bootstrap_progress_at_a_terminal(tmp_path):
    runs = [write_metrics(tmp_path / f"seed{s}", {"RL": [0.4 + 0.05 * s, 0.6]}) for s in range(3)]
    code, output = run_at_a_terminal(["aggregate", *map(str, runs)], tmp_path, timeout_s=120)
    assert code == 0 and "bootstrap intervals" in output and "━" in output, output
