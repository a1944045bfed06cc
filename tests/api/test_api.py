"""The public Python API: each command's function gives what the command prints, tells its notes through
the `Report` it is handed, and raises the command's one-line error on a user mistake."""

from contextlib import contextmanager
from pathlib import Path

import pytest
from conftest import REPOSITORY
from typer.testing import CliRunner

from rlcontroller import api
from rlcontroller.cli import app
from rlcontroller.config import ConfigError, load_experiment

SMOKE = REPOSITORY / "configs" / "testing" / "smoke.yaml"


class Recorded(api.Report):
    """A report that keeps what it is told."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.notes: list[str] = []
        self.steps: dict[str, int] = {}

    def line(self, text: str) -> None:
        self.lines.append(text)

    def note(self, text: str) -> None:
        self.notes.append(text)

    @contextmanager
    def progress(self, description, total):
        self.steps[description] = 0

        def advance(amount=1, label=""):
            self.steps[description] += amount

        yield advance


def test_describe_is_what_rlc_info_prints():
    config = REPOSITORY / "configs" / "five_story.yaml"
    printed = CliRunner().invoke(app, ["info", str(config)])
    assert printed.exit_code == 0
    assert printed.output == api.describe(api.load(config)) + "\n"
    assert "1.444" in printed.output  # the paper's first period


@pytest.mark.slow
def test_compare_lqg_reports_its_notes_and_progress_and_prints_nothing(tmp_path, monkeypatch, capsys):
    monkeypatch.delenv("RLC_RECORDS", raising=False)
    report = Recorded()
    compared = api.compare_lqg(config=SMOKE, out=tmp_path / "out", report=report)
    assert capsys.readouterr() == ("", "")  # the library prints nothing itself
    assert report.notes == [
        "no --records given: using the embedded synthetic suite (labelled SYNTHETIC in every output)"
    ]
    assert report.steps == {"evaluating 7 motions": 7}
    assert compared.out == tmp_path / "out" and (compared.out / "metrics.csv").is_file()
    assert compared.sweep is None and compared.preview is None
    text = api.summary_text(compared.evaluation, compared.out)
    assert (
        text.startswith("# SYNTHETIC")
        and "| LQG |" in text
        and text.endswith(f"tables and plots in {compared.out}")
    )


def test_a_user_mistake_is_the_commands_one_line_error(tmp_path):
    with pytest.raises(ConfigError, match="either a run folder or --config, not both"):
        api.compare_lqg(run_dir=tmp_path, config=SMOKE)
    with pytest.raises(ConfigError, match="not a run folder: no config.yaml"):
        api.evaluate(run_dir=tmp_path)
    with pytest.raises(ConfigError, match="a wind suite is not taken by this command"):
        from rlcontroller.physics.motions.loads import load_suite

        load_suite(REPOSITORY / "configs" / "loads" / "wind.yaml")


def test_an_unchecked_policy_is_a_note_before_it_is_used(tmp_path):
    import shutil

    from rlcontroller.assets import DEFAULT_MODEL

    passed = api.unchecked_note(DEFAULT_MODEL, "best")  # the shipped default passed: the folder's claim
    assert passed.endswith(
        "policy passed the safety check, dominating: the folder's claim until re-run: "
        "'rlc check models/five_story_every_story --verify'"
    )
    copy = tmp_path / "model"
    shutil.copytree(DEFAULT_MODEL, copy)
    (copy / "best_check.yaml").unlink()
    report = Recorded()
    out = api.export(copy, tmp_path / "controller.onnx", report=report)
    assert out.is_file()
    assert report.notes == [
        f"note: {copy}'s best policy counts as never safety-checked; run 'rlc check {copy}'"
    ]
    assert report.lines == [
        f"wrote {out}: readings (SI) and state in, forces (N) out; see docs/deployment.md"
    ]


@pytest.mark.slow
def test_shipped_models_are_grouped_by_what_they_are_made_for_and_mark_the_default():
    lines = api.shipped_models()
    group = "paper five-story under ground motion, actuators on stories 1, 2, 3, 4, 5:"
    assert lines[lines.index(group) + 1].startswith("  five_story_every_story (default): ")
    assert all("never checked" not in line for line in lines)
    verdict, certificate = lines[lines.index(group) + 1].split("; ")
    assert verdict.endswith("safety check passed, dominates")  # the default dominates
    assert certificate.startswith("certified region: story drifts up to ")  # its certificate's X
    unserved = lines[lines.index("none ships yet (models/README.md says why) for:") + 1 : -1]
    # the FE frame, and the two mass drivers withdrawn when they met their end-stops (models/README.md)
    assert sorted(line.rsplit("(", 1)[1] for line in unserved) == sorted(
        ["nine_story_frame)", "five_story_amd)", "seventy_six_story_atmd)"]
    )
    wind = lines.index("paper five-story under wind, actuators on stories 1, 2, 3, 4, 5:")
    assert lines[wind + 1].startswith("  five_story_wind: DAgger, ") and lines[wind + 1].split("; ")[
        0
    ].endswith("check passed")
    mr = lines.index("paper five-story under ground motion, mr_damper on stories 1, 3, 5:")
    learned = lines[mr + 1]
    assert learned.startswith("  five_story_mr_standard: RandomSearch, ")
    assert learned.split("; ")[0].endswith("check passed, dominates")
    assert learned.split("; ")[1].startswith("none certified (semi-active dampers")
    assert "each verdict is its folder's claim until re-run: 'rlc check models/NAME --verify'" in lines
    assert lines[-1] == "nothing to command, its verdict from 'rlc compare passive': five_story_tmd"


@pytest.mark.slow
def test_an_experiment_yaml_names_the_controller_shipped_for_its_building_and_devices(tmp_path):
    from rlcontroller.api.common import shipped_for
    from rlcontroller.assets import DEFAULT_MODEL

    experiments = REPOSITORY / "configs" / "experiments"
    # other training, same hardware
    robust = load_experiment(experiments / "five_story_every_story_robust.yaml")
    assert shipped_for(robust) == DEFAULT_MODEL
    report = Recorded()
    assert api.model_folder(experiments / "five_story_every_story_robust.yaml", report) == DEFAULT_MODEL
    assert report.notes[0].endswith(
        f"using {DEFAULT_MODEL}, the shipped controller for its paper five-story "
        "under ground motion, actuators on stories 1, 2, 3, 4, 5"
    )
    # the plant tells it from the default
    yielding = load_experiment(experiments / "five_story_yielding.yaml")
    assert shipped_for(yielding) == DEFAULT_MODEL.parent / "five_story_yielding"
    wind = load_experiment(experiments / "five_story_wind.yaml")  # the load tells it from the default
    assert shipped_for(wind) == DEFAULT_MODEL.parent / "five_story_wind"
    paper = load_experiment(experiments / "paper_sac.yaml")  # the paper's layout: its own controller
    assert shipped_for(paper) == DEFAULT_MODEL.parent / "five_story_paper_layout"
    dampers = load_experiment(experiments / "five_story_mr.yaml")
    assert shipped_for(dampers) == DEFAULT_MODEL.parent / "five_story_mr_standard"
    other = tmp_path / "stories_2_4.yaml"  # actuators on stories 2 and 4: nothing ships for them
    other.write_text(
        f"name: stories_2_4\nbuilding: {REPOSITORY}/configs/buildings/five_story.yaml\n"
        "actuators: [{story: 2}, {story: 4}]\n"
    )
    assert shipped_for(load_experiment(other)) is None
    with pytest.raises(
        ConfigError,
        match=r"stories_2_4.yaml: no shipped controller for its paper five-story "
        r"under "
        r"ground motion, actuators on stories 2, 4 \(rlc models\): train one",
    ):
        api.model_folder(other)


def test_the_api_is_what_the_commands_call():
    """Each command module only parses and prints: no physics, RL or evaluation imported at its top."""
    for module in ("experiments", "judging", "multirun", "shipping"):
        text = (REPOSITORY / "rlcontroller" / "cli" / f"{module}.py").read_text()
        assert "rlcontroller.physics" not in text and "rlcontroller.learning" not in text, module
        assert "rlcontroller.evaluation.evaluation" not in text and "Plant(" not in text, module
    assert Path(api.__file__).parent.name == "api"


@pytest.mark.slow
def test_a_controller_judged_on_loads_not_its_own_is_told_so_first(tmp_path, monkeypatch):
    """A wind experiment's controllers on ground-motion records (and a ground-motion experiment's on a wind
    suite): one note before the evaluation, which still runs."""
    monkeypatch.delenv("RLC_RECORDS", raising=False)
    wind = REPOSITORY / "configs" / "experiments" / "five_story_wind.yaml"
    report = Recorded()
    compared = api.compare_lqg(config=wind, out=tmp_path / "wind", report=report)
    # after the one naming the synthetic suite
    assert report.notes[1:] == [
        "note: the controllers were made for wind; these loads are ground motions: judged on loads not their "
        "own"
    ]
    assert (compared.out / "metrics.csv").is_file()
    report = Recorded()
    api.compare_lqg(config=SMOKE, out=tmp_path / "smoke", report=report)
    assert not any("not their own" in note for note in report.notes)


@pytest.mark.parametrize(
    "config",
    [
        REPOSITORY
        / "studies"
        / "identification"
        / "five_story_identified_design.yaml",  # a state-space building
        REPOSITORY / "configs" / "experiments" / "seventy_six_story_atmd.yaml",
        REPOSITORY / "configs" / "five_story.yaml",
    ],
)
def test_rlc_info_fits_on_a_screen_and_full_gives_everything(config):
    """Matrices by shape, source and digest, 76 story heights in one line, ten modes; --full: the resolved
    configuration entry by entry (it reads back as the experiment) and every mode."""
    import hashlib

    import numpy as np
    import yaml

    experiment = api.load(config)
    short = CliRunner().invoke(app, ["info", str(config)])
    full = CliRunner().invoke(app, ["info", str(config), "--full"])
    assert short.exit_code == full.exit_code == 0
    assert len(short.stdout.splitlines()) <= 150 < len(full.stdout.splitlines())
    building = experiment.building.model_dump(mode="json")
    name = next((key for key in ("state_matrix", "stiffness_matrix") if building.get(key)), None)
    if name is not None:  # given by matrices (the paper's building is given story by story)
        matrix = np.array(building[name], dtype=float)
        digest = hashlib.sha256(matrix.tobytes()).hexdigest()[:12]
        assert f"{name}: ({matrix.shape[0]} x {matrix.shape[1]} matrix, SI, from " in short.output
        assert f"sha256 {digest})" in short.output
    resolved = full.stdout.split("\n\n# modes")[0].removeprefix("# resolved configuration\n")
    assert yaml.safe_load(resolved) == experiment.model_dump(mode="json")
