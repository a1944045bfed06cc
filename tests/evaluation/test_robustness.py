"""Robustness: the oracle equals the nominal design on the nominal plant, beats it off-design, and
survives a delay that makes the nominal LQG amplify the response."""

from pathlib import Path

import pandas as pd
import pytest
from conftest import SAME_PHYSICS
from typer.testing import CliRunner

from rlcontroller.cli import app
from rlcontroller.config import ConfigError, Experiment, Scenario, load_scenarios
from rlcontroller.evaluation.evaluation import compare, mean_metric
from rlcontroller.evaluation.robustness import (
    NOMINAL_GROUND_MODEL,
    NOMINAL_LQG,
    ORACLE_LQG,
    robustness,
    stiffness_curve,
    summary,
)
from rlcontroller.physics.motions.records import synthetic_suite
from rlcontroller.physics.plant import Plant


@pytest.fixture(scope="module")
def table():
    scenarios = [
        Scenario(name="nominal"),
        Scenario(name="soft", plant={"stiffness": 0.7}),
        Scenario(name="late", plant={"actuators": {"delay_steps": 2}}),
    ]
    result, _ = robustness(Experiment(), scenarios, synthetic_suite(count=2), "SYNTHETIC test")
    return summary(result), scenarios


def test_on_the_nominal_plant_the_oracle_is_the_nominal_design(table):
    means, _ = table
    pd.testing.assert_series_equal(
        means.loc[("nominal", NOMINAL_LQG)], means.loc[("nominal", ORACLE_LQG)], check_names=False
    )
    assert (means.xs("uncontrolled", level="controller")[["J1", "J2", "J4"]] == 1.0).all().all()


def test_off_design_the_oracle_wins_and_a_delay_makes_nominal_lqg_amplify(table):
    means, scenarios = table
    assert means.loc[("soft", ORACLE_LQG), "J1"] < means.loc[("soft", NOMINAL_LQG), "J1"] - 0.1
    assert means.loc[("late", NOMINAL_LQG), "J2"] > 1.0 > means.loc[("late", ORACLE_LQG), "J2"]
    curve = stiffness_curve(means, scenarios)
    assert list(curve.index) == [0.7, 1.0] and curve.loc[1.0, NOMINAL_LQG] == curve.loc[1.0, ORACLE_LQG]


def test_lqg_with_the_ground_model_is_the_one_evaluate_runs_designed_on_the_design_model():
    motions = synthetic_suite(count=2)
    scenarios = [Scenario(name="soft", plant={"stiffness": 0.7})]
    means = summary(robustness(Experiment(), scenarios, motions, "SYNTHETIC test")[0])
    softer = Plant(Experiment(plant={"stiffness": 0.7}))
    expected = mean_metric(compare(softer, motions, "SYNTHETIC test"), "LQG + ground model", "J1")
    assert means.loc[("soft", NOMINAL_GROUND_MODEL), "J1"] == pytest.approx(expected, rel=1e-12)
    assert means.loc[("soft", NOMINAL_GROUND_MODEL), "J1"] != means.loc[("soft", NOMINAL_LQG), "J1"]


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("scenarios: [{name: a}, {name: a}]\n", "scenarios: scenario name 'a' is used twice"),
        ("scenarios: [{name: a, plant: {stifness: 0.7}}]\n", "scenarios[0].plant.stifness: unknown key"),
        ("scenarios: [{name: a, plant: {stiffness: [1, 2]}}]\n", "scenarios[0].plant.stiffness: 2 factors"),
        (
            "scenarios: [{name: a, plant: {sensors: {dead_floors: [9]}}}]\n",
            "sensors.dead_floors: 9 does not exist",
        ),
        ("scenarios: [{name: a, plant: {stiffness: .inf}}]\n", "Input should be a finite number"),
        ("scenarios: []\n", "scenarios: List should have at least 1 item"),
    ],
)
def test_bad_scenario_files_give_one_line(tmp_path, text, expected):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError) as error:
        load_scenarios(path, Experiment())
    assert (
        str(error.value).startswith(str(path))
        and expected in str(error.value)
        and "\n" not in str(error.value)
    )


@pytest.mark.slow
def test_rlc_robustness_writes_the_three_files_for_the_committed_model(tmp_path):
    (tmp_path / "two.yaml").write_text(
        "scenarios:\n  - {name: nominal}\n  - {name: soft, plant: {stiffness: 0.7}}\n"
    )
    record = tmp_path / "short.csv"
    motion = synthetic_suite(count=1)[0]
    record.write_text(
        "time,acceleration [m/s2]\n"
        + "\n".join(f"{k * motion.dt:.4f},{a:.6f}" for k, a in enumerate(motion.acceleration))
    )
    out = tmp_path / "out"
    arguments = [
        "robustness",
        "--records",
        str(record),
        "--scenarios",
        str(tmp_path / "two.yaml"),
        "--out",
        str(out),
    ]
    result = CliRunner().invoke(app, arguments)
    assert result.exit_code == 0, result.output
    assert {p.name for p in out.iterdir()} == {"robustness.csv", "robustness.md", "robustness.png"}
    table = pd.read_csv(out / "robustness.csv")
    default = "RL"  # the default model, the learned MPC
    assert set(table["controller"]) == {
        "uncontrolled",
        NOMINAL_LQG,
        NOMINAL_GROUND_MODEL,
        ORACLE_LQG,
        default,
    }
    assert (
        set(table["scenario"]) == {"nominal", "soft"}
        and "## Mean J1 per scenario" in (out / "robustness.md").read_text()
    )


def test_a_randomised_run_adds_lqg_designed_on_the_centre_of_its_ranges():
    from rlcontroller.evaluation.robustness import CENTRE_LQG
    from rlcontroller.physics.plant import Plant
    from rlcontroller.physics.variations import centre_of_ranges

    ranges = {
        "stiffness": {"low": 0.6, "high": 1.0},
        "delay_steps": [0, 2],
        "noise_factor": {"low": 1, "high": 4, "log": True},
    }
    experiment = Experiment.model_validate({"plant_randomization": ranges})
    part = centre_of_ranges(experiment.plant_randomization, None)
    assert part.stiffness == pytest.approx(0.8) and part.actuators.delay_steps == 0  # the nominal actuators
    assert part.sensors.noise_factor == pytest.approx(2.0)  # the geometric centre of a log range
    assert Plant(experiment.model_copy(update={"plant": part})).n_state == 10
    scenarios = [Scenario(name="soft", plant={"stiffness": 0.8, "sensors": {"noise_factor": 2.0}})]
    means = summary(robustness(experiment, scenarios, synthetic_suite(count=2), "SYNTHETIC test")[0])
    # on the plant at the centre the robust design is the oracle; the nominal design is worse there
    assert means.loc[("soft", CENTRE_LQG), "J1"] == pytest.approx(
        means.loc[("soft", ORACLE_LQG), "J1"], rel=SAME_PHYSICS
    )
    assert means.loc[("soft", CENTRE_LQG), "J1"] < means.loc[("soft", NOMINAL_LQG), "J1"]


@pytest.mark.slow
def test_under_wind_the_nominal_designs_are_lqg_and_lqg_with_the_wind_model():
    """An experiment trained under wind is judged on wind with LQG + wind model among the nominal
    designs; on the nominal plant it is the one evaluate runs."""
    from conftest import REPOSITORY

    from rlcontroller.config import load_experiment
    from rlcontroller.evaluation.robustness import NOMINAL_WIND_MODEL
    from rlcontroller.physics.motions.loads import generate_suite

    experiment = load_experiment(REPOSITORY / "configs" / "experiments" / "five_story_wind.yaml")
    plant = Plant(experiment)
    motions = generate_suite(experiment.excitation.generator, 1, 5, plant.building)
    scenarios = [Scenario(name="nominal"), Scenario(name="softer", plant={"stiffness": 0.85})]
    result, _ = robustness(experiment, scenarios, motions, "wind")
    means = summary(result)["J1"]
    assert {NOMINAL_LQG, NOMINAL_WIND_MODEL} <= set(result["controller"])
    evaluated = compare(plant, motions, "wind")
    assert means.loc[("nominal", NOMINAL_WIND_MODEL)] == pytest.approx(
        mean_metric(evaluated, "LQG + wind model", "J1")
    )
    assert means.loc[("softer", NOMINAL_WIND_MODEL)] < means.loc[("softer", NOMINAL_LQG)]


@pytest.mark.parametrize(
    ("scenarios", "experiment"),
    [
        ("standard.yaml", "../five_story.yaml"),
        ("devices.yaml", "five_story_amd.yaml"),
        ("dampers.yaml", "five_story_mr.yaml"),
        ("driver_detuning.yaml", "five_story_amd.yaml"),
    ],
)
def test_the_committed_scenario_files_load_for_their_experiments(scenarios, experiment):
    from rlcontroller.config import load_experiment

    configs = Path(__file__).resolve().parents[2] / "configs"
    loaded = load_scenarios(
        configs / "scenarios" / scenarios, load_experiment(configs / "experiments" / experiment)
    )
    assert "nominal" in [scenario.name for scenario in loaded]


def test_dampers_are_judged_by_their_own_classical_laws_and_no_lqg_is_designed_for_them():
    """MR dampers: passive-off, passive-on and clipped-optimal, nominal; an LQG with the ground model cannot
    be designed for a damper's command (it crashed here before, rlc robustness on five_story_mr.yaml
    included)."""
    from conftest import REPOSITORY

    from rlcontroller.config import load_experiment
    from rlcontroller.physics.motions.loads import generate_suite

    experiment = load_experiment(REPOSITORY / "configs" / "experiments" / "five_story_mr.yaml")
    plant = Plant(experiment)
    motions = generate_suite(experiment.excitation.generator, 1, 5, plant.building)
    result, _ = robustness(experiment, [Scenario(name="nominal")], motions, "dampers")
    controllers = set(result["controller"])
    assert controllers >= {"passive-off", "passive-on"} and NOMINAL_GROUND_MODEL not in controllers
