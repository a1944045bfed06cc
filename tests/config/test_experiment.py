import re
from pathlib import Path

import numpy as np
import pytest
from conftest import REPOSITORY
from typer.testing import CliRunner

from rlcontroller.cli import app
from rlcontroller.config import ConfigError, Experiment, build_experiment, load_experiment
from tests.conftest import NO_SYSTEM_BLAS, OPENSEES_MISSING

CONFIGS = REPOSITORY / "configs"


def test_the_paper_config_is_the_embedded_default():
    default = Experiment().model_dump()
    default["algorithm"]["backend"] = "sbx"  # the paper's recipe, compiled by JAX
    assert load_experiment(CONFIGS / "experiments" / "paper_sac.yaml").model_dump() == default


def test_the_benchmark_shares_the_paper_building_actuators_and_lqg_cost():
    from rlcontroller.control.lqg import design_lqg
    from rlcontroller.physics.plant import Plant

    benchmark, paper = load_experiment(CONFIGS / "five_story.yaml"), Experiment()
    assert benchmark.building == paper.building and benchmark.actuators == paper.actuators
    assert benchmark.sensors.measurements == paper.sensors.measurements
    np.testing.assert_allclose(
        design_lqg(Plant(benchmark)).feedback, design_lqg(Plant(paper)).feedback, rtol=1e-6
    )


EXPERIMENTS = [
    CONFIGS / "five_story.yaml",
    *sorted((CONFIGS / "experiments").glob("*.yaml")),
    *sorted((CONFIGS / "testing").glob("*.yaml")),
    *sorted((CONFIGS.parent / "studies").glob("*/*.yaml")),
]


def test_the_experiments_a_user_starts_from_are_few_and_each_is_named_in_the_configs_readme():
    """configs/experiments/ holds what a user starts from; the configs behind one docs number live in
    studies/."""
    starts = sorted((CONFIGS / "experiments").glob("*.yaml"))
    assert 0 < len(starts) <= 11
    readme = (CONFIGS / "README.md").read_text()
    assert all(f"experiments/{path.name}" in readme for path in starts)
    assert len(EXPERIMENTS) > len(starts) + 20  # the studies' configs are still checked below


@pytest.mark.parametrize("path", EXPERIMENTS, ids=lambda p: p.name)
def test_every_experiment_config_loads_as_the_paper_building_with_its_own_name(path: Path):
    from rlcontroller.api import load  # with the OpenSees reduction, as the commands load an experiment

    if path.stem.startswith("nine_story_frame") and NO_SYSTEM_BLAS:
        pytest.skip(OPENSEES_MISSING)
    experiment = load(path)
    assert experiment.name == path.stem
    if path.stem.startswith("seventy_six_story"):  # the wind benchmark's building, given by matrices
        assert len(experiment.building.masses) == 76 and experiment.devices[0].floor == 75
        return
    # the OpenSees frame's reduced model, nine floors above ground,
    if path.stem.startswith("nine_story_frame"):
        plant = experiment.plant  # the frame itself as the plant, or its nonlinear reduced model (rlc reduce)
        assert len(experiment.building.masses) == 9 and (
            plant.opensees is not None or plant.hysteresis is not None
        )
        return
    if path.parent.name == "identification":  # designed on a model identified from the paper's building
        assert experiment.building.state == "physical" and experiment.building.n_floors == 5
        assert experiment.plant is None or experiment.plant.building == Experiment().building
        return
    stories = [a.story for a in experiment.actuators]
    assert experiment.building == Experiment().building and stories in ([1, 3, 5], [1, 2, 3, 4, 5], [])
    if stories == [1, 2, 3, 4, 5]:  # actuators on every story stand behind a supervisor (the check)
        assert experiment.supervisor is not None
    if experiment.excitation.generator.kind == "wind":  # whose trigger watches the floors (wind.yaml's)
        assert experiment.supervisor.trigger == (0.3, 1.0) and experiment.sensors.ground_model
    if experiment.supervisor is not None:  # on actuators or active mass drivers, never on dampers
        assert stories or not experiment.has_dampers
    assert bool(experiment.devices) == (stories == [])  # the device experiments have no inter-story actuators
    assert experiment.to_yaml() == load(path).to_yaml()  # loading is deterministic


def write(tmp_path: Path, text: str, name: str = "bad.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("building:\n  masss: [1]\n", "building.masss: unknown key"),
        ("seed: zero\n", "seed: Input should be a valid integer"),
        (
            "building:\n  masses: [1.0, -2.0, 3.0, 4.0, 5.0]\n",
            "building.masses[1]: Input should be greater than or equal to 1 (got -2.0)",
        ),
        (
            "building:\n  stiffnesses: [1.0, 0, 3.0, 4.0, 5.0]\n",
            "building.stiffnesses[1]: Input should be greater than or equal to 1",
        ),
        ("actuators:\n  - {story: 7}\n", "actuators[0].story: story 7 does not exist, expected 1..5"),
        (
            "building:\n  damping: {rayleigh: [{mode: 1, ratio: 1.0}, {mode: 2, ratio: 0.05}]}\n",
            "rayleigh[0].ratio: Input should be less than 1",
        ),
        (
            "building:\n  damping: {rayleigh: [{mode: 1, ratio: 0.01}, {mode: 6, ratio: 0.05}]}\n",
            "damping mode 6 does not exist",
        ),
        ("building:\n  masses: [1.0, 2.0]\n", "'stiffnesses' has 5 values but 'masses' has 2"),
        (
            "excitation:\n  generator: {kind: kanai_tajimi, pga: [3, 1]}\n",
            "excitation.generator.pga: expected [low, high]",
        ),
        (
            "sensors:\n  measurements: [{quantity: drift, floors: [9], scale: 1}]\n",
            "sensors.measurements[0].floors: floor 9 does not exist",
        ),
        (
            "algorithm:\n  name: DQN\n",
            "algorithm.name: Input should be 'SAC', 'PPO', 'TD3', 'DDPG', 'A2C', 'TQC', 'RandomSearch' or "
            "'DAgger'",
        ),
        ("building: [1, 2\n", "bad.yaml:2: invalid YAML"),
        ("- 1\n", "expected a mapping of experiment keys"),
    ],
)
def test_bad_configs_give_one_line_naming_file_and_key(tmp_path, text, expected):
    path = write(tmp_path, text)
    with pytest.raises(ConfigError) as error:
        load_experiment(path)
    message = str(error.value)
    assert message.startswith(str(path)) and expected in message and "\n" not in message


def test_errors_in_a_part_file_name_that_file(tmp_path):
    write(tmp_path, "masses: [1.0]\nstiffnesses: [-1.0]\ndamping: {matrix: [[0.0]]}\n", "building.yaml")
    path = write(tmp_path, "building: building.yaml\nactuators: [{story: 1}]\n")
    with pytest.raises(
        ConfigError, match=r"building.yaml: stiffnesses\[0\]: Input should be greater than or equal"
    ):
        load_experiment(path)
    with pytest.raises(
        ConfigError, match="building: file not found: nowhere.yaml .*copy the parts along with it"
    ):
        load_experiment(write(tmp_path, "building: nowhere.yaml\n"))


def test_part_files_resolve_relative_to_the_experiment(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    experiment = load_experiment(CONFIGS / "five_story.yaml")
    assert experiment.building.masses[0] == 25.0e3


@pytest.mark.parametrize(
    "text",
    [
        "building:\n  colour: red\n",
        "seed: [1]\n",
        "building:\n  masses: [-1, 1, 1, 1, 1]\n",
        "actuators: [{story: 6}]\n",
    ],
)
def test_rlc_info_exits_2_with_one_line_and_no_traceback(tmp_path, text):
    result = CliRunner().invoke(app, ["info", str(write(tmp_path, text))])
    assert result.exit_code == 2
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "bad.yaml" in lines[0]
    assert "Traceback" not in result.output


def test_rlc_info_prints_periods_damping_and_actuators():
    result = CliRunner().invoke(app, ["info", str(CONFIGS / "five_story.yaml")])
    assert result.exit_code == 0, result.output
    assert "1.444" in result.output and "0.242" in result.output
    assert "0.0100" in result.output and "0.0500" in result.output
    assert "story 3, inter_story, limit 100 kN (+u on floor 3, -u on floor 2)" in result.output
    assert "masses:" in result.output


def test_rlc_info_shows_the_design_model_and_the_simulated_plant(tmp_path):
    path = tmp_path / "soft.yaml"
    path.write_text("plant: {stiffness: 0.7}\n")
    result = CliRunner().invoke(app, ["info", str(path)])
    assert result.exit_code == 0, result.output
    design, plant = result.output.split("# modes of the ")[1:]
    assert design.startswith("design model") and "1.444" in design
    assert plant.startswith("simulated plant") and f"{1.444 / 0.7**0.5:.3f}" in plant


def test_an_experiment_trains_on_the_check_suite_s_family():
    """The standard's site-based family is a valid training excitation, and check_family.yaml is the
    standard's."""
    from rlcontroller.config import ExcitationConfig, load_safety_check
    from rlcontroller.config.base import read_model

    standard = load_safety_check(REPOSITORY / "configs" / "checks" / "standard.yaml")
    excitation = {"generator": standard.generator.model_dump(), "validation_motions": 4}
    experiment = build_experiment({"excitation": excitation})
    assert [source.kind for source in experiment.excitation.sources()] == ["site_based"]
    family = read_model(
        REPOSITORY / "configs" / "excitations" / "check_family.yaml", ExcitationConfig, "'generator'"
    )
    assert family.generator == standard.generator == family.validation_generator


def test_the_wind_standard_also_judges_the_ground_motion_suite_and_a_bad_also_is_one_line(tmp_path):
    """wind.yaml names standard.yaml beside it; a name that is not a file beside it, or a standard that names
    another itself (which could loop), is a one-line error naming the file and the field."""
    from rlcontroller.config import load_safety_check

    checks = REPOSITORY / "configs" / "checks"
    wind = load_safety_check(checks / "wind.yaml")
    assert wind.also == load_safety_check(checks / "standard.yaml") and wind.also.also is None
    assert wind.generator.kind == "wind" and wind.also.motions == 320
    text = (checks / "wind.yaml").read_text()
    (tmp_path / "standard.yaml").write_text(text.replace("also: standard.yaml", "also: wind.yaml"))
    for also, expected in [
        ("missing.yaml", "'missing.yaml'"),
        ("standard.yaml", "'standard.yaml'"),
        ("[1]", "[1]"),
    ]:
        (tmp_path / "wind.yaml").write_text(text.replace("also: standard.yaml", f"also: {also}"))
        message = rf"wind.yaml: also: expected the file name of a standard beside it.*{re.escape(expected)}"
        with pytest.raises(ConfigError, match=message):
            load_safety_check(tmp_path / "wind.yaml")
