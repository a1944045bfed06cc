"""The command line as a user meets it: at a real terminal (a pseudo-terminal), with help and version."""

import importlib.metadata
import re
import shutil
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
import yaml
from conftest import REPOSITORY, records_folder, run_at_a_terminal
from typer.testing import CliRunner

from rlcontroller.cli import app


@pytest.mark.slow
def test_the_readme_main_command_works_at_a_terminal(tmp_path, monkeypatch):
    """`rlc demo` at a terminal shows the progress bar (tqdm and rich) and ends with the tables."""
    monkeypatch.delenv("RLC_RECORDS", raising=False)
    code, output = run_at_a_terminal(["demo"], tmp_path)
    assert code == 0, output
    assert "Traceback" not in output and "Error" not in output
    assert re.search(r"3,\d{3},\d{3}/3,500,0", output)  # the progress bar was drawn (simulated steps)
    assert "learned: validation J1 1.000 at step 0 -> 0." in output  # training changed the controller
    assert "tables and plots in runs" in output and "| RL |" in output
    assert "safety check of RL: PASSED" in output and "verdict in runs" in output
    (run,) = (tmp_path / "runs").iterdir()
    assert (run / "evaluation" / "summary.md").is_file() and (run / "best_check.yaml").is_file()
    metrics = pd.read_csv(run / "evaluation" / "metrics.csv")  # on every record shown: better than no control
    rl = (
        metrics[(metrics["controller"] == "RL") & (metrics["metric"] == "J1")]
        .groupby("record")["value"]
        .mean()
    )
    assert len(rl) > 0 and (rl < 1.0).all()


@pytest.mark.slow
def test_a_user_mistake_at_a_terminal_is_one_line(tmp_path):
    (tmp_path / "bad.yaml").write_text("building: {masses: [1.0e4, .inf]}\n")
    code, output = run_at_a_terminal(["train", "bad.yaml"], tmp_path, timeout_s=120)
    assert code == 2 and output.strip().splitlines() == [
        "error: bad.yaml: building.masses[1]: Input should be a finite number (got inf)"
    ]
    assert list(tmp_path.iterdir()) == [tmp_path / "bad.yaml"]


def test_version():
    result = CliRunner().invoke(app, ["--version"])
    assert result.exit_code == 0 and result.output == f"rlc {importlib.metadata.version('rlcontroller')}\n"


def test_help_is_wrapped_not_cut_and_shows_the_real_progress_default():
    result = CliRunner().invoke(app, ["train", "--help"], terminal_width=80)
    assert result.exit_code == 0
    assert "…" not in result.output and "<bool>" not in result.output
    assert "--progress / --no-progress" in result.output and "[default: (on a terminal)]" in result.output
    assert "runs/NAME-seedS-TIME" in result.output.replace("\n", "").replace(" ", "")


def test_train_without_a_config_is_a_usage_error_not_a_four_hour_run(tmp_path):
    result = CliRunner().invoke(app, ["train", "--run-dir", str(tmp_path / "run")])
    assert result.exit_code == 2 and "expected an experiment YAML" in result.output
    assert not (tmp_path / "run").exists()


def test_the_default_model_follows_the_stated_rule_on_the_committed_verdicts():
    """models/README.md: among the shipped controllers made for one building and its devices, the one that
    passes the safety check with the lowest mean J1 + mean J2 on the check suite; while none passes, the one
    with the fewest failing check motions."""
    import yaml

    from rlcontroller.api.common import folder_experiment, shipped_folders
    from rlcontroller.cli import DEFAULT_MODEL

    assert all((folder / "card.md").is_file() for folder in shipped_folders())
    made_for = folder_experiment(DEFAULT_MODEL).hardware()
    verdicts = {
        folder: yaml.safe_load((folder / "best_check.yaml").read_text())
        for folder in shipped_folders()
        if folder_experiment(folder).hardware() == made_for
    }

    def rank(folder):
        suite = verdicts[folder]["criteria"]["check suite"]
        return (not verdicts[folder]["passed"], suite["failure_count"], suite["mean_J1"] + suite["mean_J2"])

    assert min(verdicts, key=rank) == DEFAULT_MODEL


@pytest.mark.slow
def test_rlc_models_lists_every_shipped_controller_and_marks_the_default():
    from rlcontroller.cli import MODELS

    result = CliRunner().invoke(app, ["models"])
    assert result.exit_code == 0
    assert "five_story_every_story (default): DAgger, 104,933 steps, safety check passed" in result.output
    shipped = [path for path in MODELS.iterdir() if (path / "best_policy.yaml").is_file()]
    assert result.output.count("safety check passed") == len(shipped) and "FAILED" not in result.output


def test_compare_lqg_takes_a_run_or_a_config_not_both(tmp_path):
    from rlcontroller.cli import DEFAULT_MODEL

    model = DEFAULT_MODEL
    result = CliRunner().invoke(app, ["compare", "lqg", str(model), "--config", str(model / "config.yaml")])
    assert result.exit_code == 2 and "either a run folder or --config" in result.output


@pytest.mark.slow
def test_a_long_command_shows_its_progress_at_a_terminal_and_nothing_when_captured(tmp_path):
    scenarios = tmp_path / "two.yaml"
    scenarios.write_text("scenarios:\n  - {name: nominal}\n  - {name: softer, plant: {stiffness: 0.8}}\n")
    arguments = ["robustness", "--scenarios", str(scenarios)]
    code, output = run_at_a_terminal([*arguments, "--out", str(tmp_path / "pty")], tmp_path, timeout_s=240)
    assert code == 0 and "2 scenarios" in output and "━" in output and "/2" in output, output
    captured = subprocess.run(
        [sys.executable, "-m", "rlcontroller", *arguments, "--out", str(tmp_path / "captured")],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert captured.returncode == 0 and "━" not in captured.stdout + captured.stderr


def test_progress_asked_for_into_a_file_is_a_line_per_step(tmp_path, records):
    """`--progress` into a log (nohup): a live bar draws nothing there, so each finished step is a line on
    stderr."""
    kobe = str(records / "RSN1106_KOBE_KJM000.AT2")
    arguments = ["evaluate", "--records", kobe, "--out", str(tmp_path / "out")]
    asked = CliRunner().invoke(app, [*arguments, "--progress"])
    assert asked.exit_code == 0 and re.search(r"^evaluating 1 motion: 1/1, \d+ s$", asked.stderr, re.M), (
        asked.stderr
    )
    quiet = CliRunner().invoke(app, [*arguments[:-1], str(tmp_path / "quiet")])
    assert quiet.exit_code == 0 and "1/1" not in quiet.stderr


def test_top_level_help_cuts_nothing_and_says_where_to_start():
    result = CliRunner().invoke(app, ["--help"], terminal_width=80)
    commands = result.output.split("Commands:")[1].strip().splitlines()
    assert result.exit_code == 0 and "…" not in result.output and len(commands) == 18
    assert not any(line.endswith("...") for line in commands) and "Start with 'rlc demo'" in result.output


def test_an_experiment_yaml_without_a_shipped_controller_says_what_to_do(tmp_path):
    config = tmp_path / "stories_2_4.yaml"  # actuators on stories 2 and 4: nothing ships for them
    building = REPOSITORY / "configs" / "buildings" / "five_story.yaml"
    config.write_text(f"name: stories_2_4\nbuilding: {building}\nactuators: [{{story: 2}}, {{story: 4}}]\n")
    result = CliRunner().invoke(app, ["evaluate", str(config), "--out", str(tmp_path / "out")])
    assert result.exit_code == 2 and "no shipped controller for its paper five-story" in result.output
    assert f"rlc compare lqg --config {config}" in result.output and len(result.output.splitlines()) == 1


@pytest.mark.slow
def test_output_cut_short_by_the_reader_is_no_error():
    head = subprocess.run(
        f"{sys.executable} -m rlcontroller info | head -1",
        shell=True,
        capture_output=True,
        text=True,
        check=False,
    )
    assert head.stdout == "# resolved configuration\n" and "error" not in head.stderr


@pytest.mark.parametrize("name", ["five_story_tmd", "five_story_amd", "five_story_mr"])
def test_info_lists_each_device_as_built(name):
    result = CliRunner().invoke(app, ["info", str(REPOSITORY / "configs" / "experiments" / f"{name}.yaml")])
    assert result.exit_code == 0, result.output
    devices = result.output.split("# devices")[1].strip().splitlines()[1:]
    expected = {
        "five_story_tmd": ["tuned_mass on floor 5, 0.9195 t"],
        "five_story_amd": ["active_mass on floor 5"],
    }
    expected["five_story_mr"] = [f"mr_damper on story {s}, capacity 100 kN" for s in (1, 3, 5)]
    assert [
        line.split(": ", 1)[1][: len(e)] for line, e in zip(devices, expected[name], strict=True)
    ] == expected[name]


@pytest.mark.slow
def test_compare_lqg_shows_its_evaluation_and_sweep_progress_at_a_terminal(tmp_path, records):
    kobe = str(records / "RSN1106_KOBE_KJM000.AT2")
    arguments = ["compare", "lqg", "--records", kobe, "--sweep", "--out", str(tmp_path / "out")]
    code, output = run_at_a_terminal(arguments, tmp_path, timeout_s=240)
    assert (
        code == 0
        and "evaluating 1 motion " in output
        and "1 motions" not in output
        and "LQG trade-off" in output
        and "9/9" in output
    ), output


@pytest.mark.slow
def test_the_specifications_commands_run_as_written(tmp_path, monkeypatch):
    """The four commands the project's specification names, verbatim, from a folder holding configs/ and
    records/ as the checkout does (records/ as committed: the manifest, not the PEER files)."""
    monkeypatch.delenv("RLC_RECORDS", raising=False)
    (tmp_path / "configs").symlink_to(REPOSITORY / "configs")
    shutil.copytree(REPOSITORY / "records", tmp_path / "records")

    def rlc(command: str) -> subprocess.CompletedProcess:
        arguments = [sys.executable, "-m", "rlcontroller", *command.split()]
        return subprocess.run(arguments, cwd=tmp_path, capture_output=True, text=True, timeout=300)

    info = rlc("info configs/five_story.yaml")
    assert info.returncode == 0 and "1.444" in info.stdout and "name: five_story" in info.stdout
    train = rlc("train configs/five_story.yaml --total-steps 2000")  # the specification's, shortened
    assert train.returncode == 0 and "trained: 2048 steps" in train.stdout, train.stderr
    (run,) = (tmp_path / "runs").iterdir()
    assert (run / "config.yaml").is_file() and (run / "best_policy.npz").is_file()
    certified = rlc(f"certify {run} --design-only")  # a controller trained by rlc train, certified
    assert certified.returncode == 0 and "design model: " in certified.stdout, certified.stderr
    assert (run / "best_certificate.yaml").is_file()
    missing = rlc("evaluate --records records/")
    assert missing.returncode == 2 and missing.stdout == ""
    assert missing.stderr.startswith(
        "error: records: 7 of 7 records of manifest.csv missing: RSN753_LOMAP_CLS000.AT2"
    )
    assert len(missing.stderr.splitlines()) == 1
    compared = rlc("compare lqg")
    assert (
        compared.returncode == 0
        and "| LQG + ground model |" in compared.stdout
        and "SYNTHETIC" in compared.stdout
    )
    shared = records_folder()
    if not (shared / "manifest.csv").is_file():
        pytest.skip(f"no PEER records at {shared}: the table on the seven records is not run")
    for record in shared.glob("*.AT2"):
        shutil.copy(record, tmp_path / "records")
    evaluated = rlc("evaluate --records records/")
    assert evaluated.returncode == 0 and "| uncontrolled | 1.000 | 1.000 |" in evaluated.stdout
    assert "evaluated 7 motions" in evaluated.stdout


def test_an_internal_error_is_one_line_naming_its_traceback_file(monkeypatch, tmp_path):
    """A failure that is not the user's: one line, exit 3, the traceback in the file it names; --debug (or
    RLC_DEBUG=1) lets it through with its traceback."""
    import rlcontroller.config as config

    monkeypatch.delenv("RLC_DEBUG", raising=False)
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))

    def planted(*args, **kwargs):
        raise RuntimeError("planted failure\nsecond line")

    monkeypatch.setattr("rlcontroller.api.common.load_experiment", planted)
    assert config.load_experiment is not planted
    result = CliRunner().invoke(app, ["info", "configs/five_story.yaml"])
    (line,) = result.output.splitlines()
    assert result.exit_code == 3
    assert line.startswith("internal error: RuntimeError: planted failure (full traceback in ")
    (file,) = tmp_path.glob("rlc-traceback-*.txt")
    assert str(file) in line and "Traceback" in file.read_text() and "second line" in file.read_text()
    debugged = CliRunner().invoke(app, ["--debug", "info", "configs/five_story.yaml"])
    assert isinstance(debugged.exception, RuntimeError) and "internal error" not in debugged.output
    monkeypatch.setenv("RLC_DEBUG", "1")
    assert isinstance(CliRunner().invoke(app, ["info", "configs/five_story.yaml"]).exception, RuntimeError)


def test_the_command_line_starts_without_the_library():
    """`rlc --help` must not wait for numpy, pandas, gymnasium, pydantic or torch: the command modules import
    the library inside each command (start-up is measured in scripts/bench_startup.py, not here)."""
    code = "import sys, rlcontroller.cli; print(sorted({m.split('.')[0] for m in sys.modules}))"
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    for heavy in ("numpy", "pandas", "gymnasium", "pydantic", "torch", "scipy", "yaml"):
        assert f"'{heavy}'" not in loaded, heavy


@pytest.mark.slow
def test_the_env_is_registered_by_the_learning_package_in_a_fresh_process():
    code = (
        "import rlcontroller.learning, gymnasium; env = gymnasium.make(rlcontroller.ENV_ID); "
        "print(env.observation_space.shape, rlcontroller.__version__)"
    )
    printed = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert printed.strip().endswith(importlib.metadata.version("rlcontroller"))


@pytest.mark.slow
def test_compare_passive_states_the_devices_own_verdict(records, tmp_path):
    config = REPOSITORY / "configs" / "experiments" / "five_story_tmd.yaml"
    out = tmp_path / "passive"
    result = CliRunner().invoke(
        app, ["compare", "passive", str(config), "--records", str(records), "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    verdict = yaml.safe_load((out / "passive_check.yaml").read_text())
    assert verdict["controller"] == "passive devices" and verdict["passed"] is False
    suite = verdict["criteria"]["check suite"]
    significant = suite["significant_motions"]
    words = (
        f"{suite['failure_count']} of {significant} significant worse than the building without its devices"
    )
    assert words in result.output
    assert len(suite["failures"]) == suite["failure_count"]  # every failing motion listed
    assert (out / "metrics_per_story.png").is_file()


def test_criteria_other_than_the_papers_and_the_benchmarks_or_without_story_heights_are_one_line(tmp_path):
    config = str(REPOSITORY / "configs" / "five_story.yaml")
    for criteria, message in (
        ("ohtori", "expected one of paper, benchmark"),
        ("benchmark", "no story_heights"),
    ):
        arguments = [
            "compare",
            "lqg",
            "--config",
            config,
            "--criteria",
            criteria,
            "--out",
            str(tmp_path / criteria),
        ]
        result = CliRunner().invoke(app, arguments)
        assert result.exit_code == 2 and message in result.output and len(result.output.splitlines()) == 1
        assert not (tmp_path / criteria).exists()


@pytest.mark.slow
def test_the_frames_benchmark_criteria_on_a_record(tmp_path, records, monkeypatch):
    """The FE frame's J1-J17 (`evaluation.benchmark`): its member ends read, the uncontrolled run kept with
    them."""
    monkeypatch.setenv("RLC_CACHE", str(tmp_path / "cache"))
    config = str(REPOSITORY / "configs" / "experiments" / "nine_story_frame.yaml")
    out = tmp_path / "out"
    arguments = ["compare", "lqg", "--config", config, "--records", str(records / "RSN1106_KOBE_KJM000.AT2")]
    result = CliRunner().invoke(app, [*arguments, "--out", str(out), "--criteria", "benchmark"])
    assert result.exit_code == 0, result.output
    assert "The benchmark's criteria J1-J17" in result.output
    table = pd.read_csv(out / "benchmark_criteria.csv").set_index(["controller", "criterion"])["value"]
    assert table.loc["uncontrolled"].loc[[f"J{i}" for i in range(1, 11)]].tolist() == [1.0] * 10
    lqg = table.loc["LQG"]
    # it yields, less than bare
    assert 0.5 < lqg["J1"] < 1.0 and 0.5 < lqg["J7"] < 1.0 and 0.0 < lqg["J8"] < 1.0
    assert (lqg["J15"], lqg["J16"]) == (9, 10) and lqg["J11"] > 0.0
    assert all(np.isfinite(lqg.loc[[f"J{i}" for i in range(1, 18)]]))
