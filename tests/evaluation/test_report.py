"""End to end: a smoke run's policy through `rlc evaluate` and `rlc compare lqg` on the records."""

import errno
import os
import shutil

import numpy as np
import pandas as pd
import pytest
from conftest import REPOSITORY
from typer.testing import CliRunner

from rlcontroller.cli import app
from rlcontroller.config import Experiment, load_experiment
from rlcontroller.evaluation import report, study_report, tables
from rlcontroller.learning.training import train

DEFAULT_NAME = "RL"  # the default model, the learned MPC


@pytest.fixture(scope="module")
def smoke_run(tmp_path_factory):
    experiment = load_experiment(REPOSITORY / "configs" / "testing" / "smoke.yaml")
    run = tmp_path_factory.mktemp("smoke") / "run"
    train(
        experiment=experiment.model_copy(
            update={"algorithm": experiment.algorithm.model_copy(update={"total_steps": 500})}
        ),
        run_dir=run,
    )
    return run


@pytest.mark.slow
def test_evaluate_writes_tables_and_plots_with_finite_numbers(smoke_run, records, tmp_path):
    out = tmp_path / "evaluation"
    result = CliRunner().invoke(
        app, ["evaluate", str(smoke_run), "--records", str(records), "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    for name in (
        "metrics.csv",
        "per_record.csv",
        "summary.csv",
        "summary.md",
        "per_record.md",
        "j1_by_pga.csv",
        "j2_by_pga.csv",
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
    assert metrics["value"].notna().all()
    bare = metrics[metrics["controller"] == "uncontrolled"]
    assert (bare.loc[bare["metric"] != "J3", "value"] == 1.0).all() and (
        bare.loc[bare["metric"] == "J3", "value"] == 0
    ).all()
    lqg_j1 = (
        metrics[(metrics["controller"] == "LQG") & (metrics["metric"] == "J1")]
        .groupby("record")["value"]
        .mean()
    )
    assert len(lqg_j1) == 7 and (lqg_j1 < 0.8).all()  # LQG reduces the mean drift on every record
    assert len(set(metrics["record"])) == 7 and set(metrics["suite"]) == {
        f"7 records from {records}, as recorded"
    }
    summary = (out / "summary.md").read_text()
    assert "RL better than LQG (%)" in summary and f"7 records from {records}" in summary
    assert f"Evaluated RL: {smoke_run / 'best_policy.yaml'} (" in summary and "training steps)" in summary
    assert "RL better than LQG" in result.output
    assert "J1 peak inter-story drift, J2 peak absolute floor acceleration" in summary
    assert "J3 energy of the actuator force over that of the uncontrolled base shear" in result.output
    reductions = [line for line in summary.splitlines() if line.startswith("| LQG |")][0].split("|")[2:-1]
    assert [len(cell.strip().split(".")[1]) for cell in reductions] == [3, 3, 3, 3, 1, 1, 1]


@pytest.mark.slow
def test_compare_lqg_sweep_and_preview_mark_the_policy(smoke_run, records, tmp_path):
    out = tmp_path / "compare"
    result = CliRunner().invoke(
        app,
        [
            "compare",
            "lqg",
            str(smoke_run),
            "--records",
            str(records),
            "--out",
            str(out),
            "--sweep",
            "--preview",
        ],
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


@pytest.mark.slow
def test_compare_lqg_without_a_run_on_the_synthetic_suite(tmp_path, monkeypatch):
    monkeypatch.delenv("RLC_RECORDS", raising=False)
    result = CliRunner().invoke(app, ["compare", "lqg", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert "SYNTHETIC" in (tmp_path / "summary.md").read_text()
    assert "SYNTHETIC" in pd.read_csv(tmp_path / "metrics.csv")["suite"].iloc[0]


@pytest.mark.slow
def test_missing_records_exit_2_with_one_line(smoke_run, records, tmp_path):
    shutil.copy(records / "manifest.csv", tmp_path)
    result = CliRunner().invoke(
        app, ["evaluate", str(smoke_run), "--records", str(tmp_path), "--out", str(tmp_path / "o")]
    )
    assert result.exit_code == 2
    lines = result.output.strip().splitlines()
    assert lines[-1].startswith("error: ") and "7 of 7 records of manifest.csv missing" in lines[-1]
    assert "$RLC_RECORDS" in lines[-1] and not (tmp_path / "o").exists()


@pytest.mark.slow
def test_default_outputs_go_to_new_folders_under_results_never_into_the_model(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("RLC_RECORDS", raising=False)
    default = REPOSITORY / "models" / "five_story_every_story"
    committed = {p.name for p in default.iterdir()}
    first = CliRunner().invoke(app, ["compare", "lqg"])
    second = CliRunner().invoke(app, ["compare", "lqg"])
    evaluated = CliRunner().invoke(app, ["evaluate"])
    for result in (first, second, evaluated):
        assert result.exit_code == 0, result.output
    folders = sorted(p.name for p in (tmp_path / "results").iterdir())
    name = "five_story_every_story-"
    assert len(folders) == 3 and sum(folder.startswith(f"compare_lqg-{name}") for folder in folders) == 2
    assert any(folder.startswith(f"evaluate-{name}") for folder in folders)
    assert f"tables and plots in results{os.sep}evaluate-{name}" in evaluated.output
    assert {p.name for p in default.iterdir()} == committed


@pytest.mark.slow
def test_an_output_folder_is_never_overwritten_and_never_half_written(tmp_path, monkeypatch):
    monkeypatch.delenv("RLC_RECORDS", raising=False)
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "mine.txt").write_text("keep")
    (tmp_path / "a_file").write_text("keep")
    for out, expected in ((tmp_path / "full", "exists and is not empty"), (tmp_path / "a_file", "is a file")):
        result = CliRunner().invoke(app, ["compare", "lqg", "--out", str(out)])
        assert result.exit_code == 2 and expected in result.output and "Traceback" not in result.output
    assert (tmp_path / "full" / "mine.txt").read_text() == "keep" and (
        tmp_path / "a_file"
    ).read_text() == "keep"
    nested = CliRunner().invoke(app, ["compare", "lqg", "--out", str(tmp_path / "a_file" / "sub")])
    assert nested.exit_code == 2 and nested.output.strip().splitlines()[-1].endswith(
        "a_file is a file, so it cannot hold the output folder"
    )

    def disk_full(path, text):
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr(report, "atomic_write", disk_full)
    result = CliRunner().invoke(app, ["compare", "lqg", "--out", str(tmp_path / "new")])
    assert result.exit_code == 1 and "No space left on device" in result.output
    assert result.output.strip().splitlines()[-1].startswith("error: ") and "Traceback" not in result.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_file", "full"]  # nothing half-written


def test_evaluate_refuses_a_folder_that_is_not_a_run(tmp_path):
    result = CliRunner().invoke(app, ["evaluate", str(tmp_path)])
    assert result.exit_code == 2 and "not a run folder" in result.output


@pytest.mark.slow
def test_the_committed_model_evaluates_from_a_fresh_clone(records, tmp_path):
    """`rlc evaluate` without RUN_DIR uses the default model, which passed the safety check."""
    result = CliRunner().invoke(app, ["evaluate", "--records", str(records), "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert "five_story_every_story/best_policy.yaml" in result.output
    assert "FAILED" not in result.output and "never safety-checked" not in result.output
    assert "passed the safety check, dominating: the folder's claim until re-run: 'rlc check" in result.output
    summary = pd.read_csv(tmp_path / "summary.csv", index_col="controller")
    # the learned MPC: LQG + ground model's drift, fewer floor accelerations
    default = summary.loc[DEFAULT_NAME]
    assert default["J1"] < 0.5 and default["J1"] < summary.loc["LQG", "J1"]
    assert default["J1"] == pytest.approx(summary.loc["LQG + ground model", "J1"], rel=0.02)
    assert default["J2"] < 0.95 * summary.loc["LQG + ground model", "J2"]


@pytest.mark.slow
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


@pytest.mark.slow
def test_the_same_inputs_give_byte_identical_j_tables(smoke_run, tmp_path, monkeypatch):
    """Sensor noise is seeded per record: two evaluations of the same run write the same bytes."""
    monkeypatch.delenv("RLC_RECORDS", raising=False)
    for out in ("a", "b"):
        result = CliRunner().invoke(app, ["compare", "lqg", str(smoke_run), "--out", str(tmp_path / out)])
        assert result.exit_code == 0, result.output
    for name in ("metrics.csv", "per_record.csv", "summary.csv"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes(), name


def test_markdown_table_rounds_percentages_to_one_decimal():
    frame = pd.DataFrame(
        {"J1": [0.45678], "J1 reduction %": [54.3219]}, index=pd.Index(["RL"], name="controller")
    )
    assert tables.markdown_table(frame).splitlines() == [
        "| controller | J1 | J1 reduction % |",
        "|---|---|---|",
        "| RL | 0.457 | 54.3 |",
    ]


def test_strong_part_is_the_significant_duration_of_the_ground():
    time = np.arange(0.0, 60.0, 0.01)
    ground = np.where((time > 20.0) & (time < 25.0), np.sin(20.0 * time), 1e-3)
    start, end = report.strong_part(ground, time)
    assert 18.5 < start < 20.0 and 25.0 < end < 29.5  # D5-95 inside the burst, padded 1 s / 4 s
    quiet_start, quiet_end = report.strong_part(np.zeros_like(time), time)
    assert (quiet_start, quiet_end) == (0.0, time[-1])


def test_lqg_j1_at_interpolates_in_log_j3_and_clamps():
    sweep = pd.DataFrame({"J3": [0.01, 0.1, 1.0], "J1": [0.6, 0.5, 0.3]})
    assert study_report.lqg_j1_at(sweep, 0.1) == pytest.approx(0.5)
    assert study_report.lqg_j1_at(sweep, np.sqrt(0.1 * 1.0)) == pytest.approx(0.4)  # halfway in log J3
    assert study_report.lqg_j1_at(sweep, 10.0) == pytest.approx(0.3)


def test_equivalent_preview_reads_the_preview_curve_backwards():
    preview = pd.DataFrame({"preview_s": [0.0, 0.1, 0.2, np.inf], "J1": [0.45, 0.40, 0.30, 0.27]})
    assert study_report.equivalent_preview(preview, 0.35) == pytest.approx(0.15)
    assert study_report.equivalent_preview(preview, 0.46) is None


def test_j1_and_j2_by_pga_band_count_records_and_flag_controllers_worse_than_none():
    from rlcontroller.control.controllers import Uncontrolled
    from rlcontroller.evaluation.evaluation import evaluate
    from rlcontroller.evaluation.tables import by_pga
    from rlcontroller.physics.motions.excitation import STANDARD_GRAVITY, scale_to_pga
    from rlcontroller.physics.motions.records import synthetic_suite
    from rlcontroller.physics.plant import Plant

    class Pushing(Uncontrolled):
        name = "pushes"  # full force on every actuator, whatever happens: worse than nothing

        def act(self, observation):
            return np.ones(np.shape(observation)[:-1] + (self.n_actuators,))

    motions = synthetic_suite(count=3)
    motions = [scale_to_pga(m, g * STANDARD_GRAVITY) for m, g in zip(motions, (0.01, 0.05, 0.5), strict=True)]
    evaluation = evaluate(Plant(Experiment()), motions, [Pushing(3)], "SYNTHETIC test", include_optimal=False)
    table = by_pga(evaluation)
    assert list(table.columns) == [
        "PGA 0–0.02 g (1)",
        "PGA 0.02–0.1 g (1)",
        "PGA 0.1–0.3 g (0)",
        "PGA ≥ 0.3 g (1)",
        "records with J1 > 1",
    ]
    assert (
        table.loc["uncontrolled", "records with J1 > 1"] == 0
        and table.loc["pushes", "records with J1 > 1"] >= 2
    )
    assert (
        np.isnan(table.loc["pushes", "PGA 0.1–0.3 g (0)"]) and table.loc["pushes", "PGA 0–0.02 g (1)"] > 1.0
    )
    accelerations = by_pga(evaluation, "J2")
    assert list(accelerations.columns) == [*table.columns[:-1], "records with J2 > 1"]
    j2 = (
        evaluation.metrics[evaluation.metrics["metric"] == "J2"]
        .groupby(["controller", "record"])["value"]
        .mean()
    )
    strong = motions[2].name
    assert accelerations.loc["pushes", "PGA ≥ 0.3 g (1)"] == pytest.approx(j2["pushes", strong])
    assert accelerations.loc["uncontrolled", "records with J2 > 1"] == 0


@pytest.mark.slow
def test_the_drawing_process_draws_the_same_plots_and_reports_its_failures(tmp_path):
    """`rlc evaluate`'s plots drawn by the forked drawing process are byte for byte the ones drawn here;
    a job that fails there is an error here, with its traceback, never a missing plot."""
    from rlcontroller.evaluation.evaluation import compare
    from rlcontroller.physics.motions.records import synthetic_suite
    from rlcontroller.physics.plant import Plant

    plant = Plant(Experiment())
    evaluation = compare(plant, synthetic_suite(count=2), "SYNTHETIC test")
    report.write_report(evaluation, tmp_path / "here")
    with report.Drawing() as drawing:
        written = report.write_report(evaluation, tmp_path / "there", drawing)
        for name in ("time_histories.png", "metrics_per_story.png"):
            assert (tmp_path / "there" / name) in written
            assert (tmp_path / "there" / name).read_bytes() == (tmp_path / "here" / name).read_bytes()
        drawing.submit([(report.draw_time_histories, {"lines": "not lines"}, tmp_path / "bad.png")])
        with pytest.raises(RuntimeError, match="drawing the plots failed:\nTraceback"):
            drawing.results()
    assert not (tmp_path / "bad.png").exists()
