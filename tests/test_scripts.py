import importlib.util
from pathlib import Path

import numpy as np
import pytest

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"
STUDIES = SCRIPTS.parent / "studies"


def script_path(name: str) -> Path:
    """A benchmark or reproduction entry point in scripts/, or a study's own script in studies/PAGE/."""
    (path,) = [path for path in (SCRIPTS / f"{name}.py", *STUDIES.glob(f"*/{name}.py")) if path.is_file()]
    return path


def load_script(name: str):
    spec = importlib.util.spec_from_file_location(name, script_path(name))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_prediction_r2_is_one_for_a_sine_and_zero_for_white_noise():
    prediction_r2 = load_script("ground_predictability").prediction_r2
    time = np.arange(3000) * 0.02
    assert prediction_r2(np.sin(7.0 * time), horizon=10) > 0.999
    noise = np.random.default_rng(0).standard_normal(3000)
    assert abs(prediction_r2(noise, horizon=1)) < 0.02


@pytest.mark.slow
def test_generated_records_are_read_back_as_written(tmp_path):
    import subprocess
    import sys

    from rlcontroller.physics.motions.excitation import STANDARD_GRAVITY
    from rlcontroller.physics.motions.records import load_records

    out = tmp_path / "suite"
    script = [sys.executable, str(SCRIPTS / "generated_records.py"), str(out), "--count", "4", "--seed", "7"]
    done = subprocess.run(script, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    motions, label = load_records(out)
    assert len(motions) == 4 and "4 records" in label
    manifest = (out / "manifest.csv").read_text().splitlines()[1:]
    for motion, line in zip(motions, manifest, strict=True):
        assert abs(motion.pga / STANDARD_GRAVITY - float(line.split(",")[2])) < 1e-3
        assert abs(motion.dt - 0.02) < 1e-12


def test_randomized_lqg_is_the_validation_reference_on_more_motions():
    from rlcontroller.config import Experiment, PlantRandomization
    from rlcontroller.learning.validation import Validator
    from rlcontroller.physics.plant import Plant

    ranges = PlantRandomization(stiffness={"low": 0.7, "high": 1.2}, delay_steps=(0, 2))
    experiment = Experiment(plant_randomization=ranges)
    excitation = experiment.excitation.model_copy(update={"validation_motions": 3, "validation_seed": 5})
    experiment = experiment.model_copy(update={"excitation": excitation})
    names, j1, j2 = load_script("randomized_lqg").randomized_lqg(experiment, count=3, seed=5)
    reference = Validator(Plant(experiment)).reference
    assert names == ["LQG", "LQG + ground", "LQG + ground model"]
    for row, prefix in enumerate(("lqg", "lqg_ground", "lqg_ground_model")):
        assert abs(np.mean(j1[row]) - reference[f"{prefix}_J1"]) < 1e-12
        assert abs(np.mean(j2[row]) - reference[f"{prefix}_J2"]) < 1e-12


def test_the_linear_clone_fit_recovers_a_linear_teacher_and_ridge_shrinks_it():
    fit_linear = load_script("linear_clone").fit_linear
    rng = np.random.default_rng(1)
    weights = rng.standard_normal((3, 8))
    observations = rng.standard_normal((500, 8))
    np.testing.assert_allclose(fit_linear(observations, observations @ weights.T, 0.0), weights, atol=1e-10)
    shrunk = fit_linear(observations, observations @ weights.T, 1.0)
    assert np.linalg.norm(shrunk) < 0.7 * np.linalg.norm(weights)


def test_the_wind_benchmark_table_groups_records_by_their_mean_speed():
    import pandas as pd

    per_speed_table = load_script("wind_benchmark").per_speed_table

    class Evaluation:
        metrics = pd.DataFrame(
            [
                {"controller": c, "record": f"wind_{speed:g}ms_{n}", "metric": "rms_acceleration", "index": i}
                | {"value": v}
                for c, scale in (("uncontrolled", 1.0), ("LQG + wind model", 0.5))
                for speed in (15.0, 25.0)
                for n in (1, 2)
                for i, v in ((1, scale * speed), (2, scale * speed + n))
            ]
        )

    table = per_speed_table(Evaluation(), [15.0, 25.0])
    # floors, then records
    assert table.loc[(25.0, "LQG + wind model"), "rms_acceleration"] == 0.5 * 25.0 + 0.75
    assert table.loc[(15.0, "uncontrolled"), "rms_acceleration"] == 15.0 + 0.75


@pytest.mark.slow
def test_a_small_soak_kills_workers_and_ends_as_the_quiet_sweep(tmp_path):
    import subprocess
    import sys

    out = tmp_path / "soak"
    command = [
        sys.executable,
        str(SCRIPTS / "soak.py"),
        str(out),
        "--runs",
        "2",
        "--steps",
        # training lasts past the first kill, due 1-2 s after training starts, even on a fast idle machine
        "36864",
        "--checkpoint-every",
        "256",
    ]
    done = subprocess.run([*command, "--kill-every", "1", "2"], capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr
    report = (out / "soak.md").read_text()
    assert "every run finished and evaluated: yes" in report, report
    assert "evaluation metrics equal to the quiet sweep's:" in report and "aggregate equal to" in report, (
        report
    )
    assert " 0 workers killed" not in report, report


def classical_verdicts(experiment: str, motions: int, tmp_path: Path) -> dict:
    """check_classical.py's verdicts on `motions` check motions and one short run at rest."""
    import yaml

    standard = yaml.safe_load((SCRIPTS.parent / "configs" / "checks" / "standard.yaml").read_text())
    path = tmp_path / "small.yaml"
    path.write_text(yaml.safe_dump(standard | {"motions": motions, "rest_runs": 1, "rest_duration": 2.0}))
    config = SCRIPTS.parent / "configs" / "experiments" / experiment
    return {v.controller: v for v in load_script("check_classical").classical_verdicts(config, path)}


@pytest.mark.slow
def test_the_classical_dampers_are_checked_and_more_voltage_means_less_drift(tmp_path):
    verdicts = classical_verdicts("five_story_mr.yaml", 8, tmp_path)
    assert list(verdicts) == ["passive-off", "passive-on", "clipped-optimal"]
    # a damper cannot move a still building
    assert all(v.criteria["at rest"].passed for v in verdicts.values())
    suite = {name: v.criteria["check suite"] for name, v in verdicts.items()}
    assert suite["passive-on"].motions == 8
    assert suite["passive-off"].mean_J1 == pytest.approx(1.0, abs=1e-9)  # the reference itself
    assert suite["passive-on"].mean_J1 < 1.0


@pytest.mark.slow
def test_an_active_mass_driver_is_also_checked_switched_off(tmp_path):
    verdicts = classical_verdicts("five_story_amd.yaml", 6, tmp_path)
    assert list(verdicts) == ["LQG", "LQG + ground", "LQG + ground model", "drivers off (tuned masses)"]
    off = verdicts["drivers off (tuned masses)"].criteria
    assert off["at rest"].peak_drift_over_bound == 0.0  # no command: noise moves nothing
    assert off["check suite"].mean_J1 > verdicts["LQG + ground model"].criteria["check suite"].mean_J1


@pytest.mark.slow
def test_a_driver_switched_off_from_the_start_is_its_reference_and_never_switched_off_is_the_law(tmp_path):
    """driver_sensitivity.py's OffAbove: off from a ground reading of 0 it is the driver switched off (J1 1,
    none worse); from one never reached it is the law it wraps, motion for motion."""
    import yaml

    from rlcontroller.config import load_experiment, load_safety_check
    from rlcontroller.evaluation.evaluation import classical_controllers
    from rlcontroller.evaluation.safety import drift_bounds, suite_criterion
    from rlcontroller.physics.plant import Plant

    standard = yaml.safe_load((SCRIPTS.parent / "configs" / "checks" / "standard.yaml").read_text())
    path = tmp_path / "small.yaml"
    path.write_text(yaml.safe_dump(standard | {"motions": 6}))
    check = load_safety_check(path)
    plant = Plant(load_experiment(SCRIPTS.parent / "configs" / "experiments" / "five_story_amd.yaml"))
    bounds = drift_bounds(plant, check)
    law = next(c for c in classical_controllers(plant) if c.name == "LQG + ground model")
    off_above = load_script("driver_sensitivity").OffAbove
    alone, never, at_once = (
        suite_criterion(plant, controller, check, bounds)
        for controller in (law, off_above(law, plant, 1e9), off_above(law, plant, 0.0))
    )
    assert at_once.mean_J1 == pytest.approx(1.0, abs=1e-12) and at_once.strict_failure_count == 0
    assert alone.mean_J1 < 0.99  # the law acts
    ratios = [
        {name: row.ratio for name, row in suite.per_motion.items() if row.significant}
        for suite in (never, alone)
    ]
    assert ratios[0] and ratios[0] == pytest.approx(ratios[1], abs=1e-12)


def test_the_supervisor_study_chooses_by_its_rule_on_generated_motions_only():
    """Passing, weak-band J1 within 15 % of unsupervised LQG + ground model's, selection J2 no higher than
    its: the lowest selection J1 among those; the seven records play no part."""
    import pandas as pd

    study = load_script("supervisor_study")
    rows = [  # cost, supervisor, check, weak-band J1, selection J1, selection J2, seven records J1
        ("drift, shear, force", "none", "FAIL", 0.136, 0.221, 0.592, 0.10),
        ("drift, shear, force", "late trigger", "pass", 0.470, 0.200, 0.500, 0.10),  # weak band too far off
        ("drift, shear, force", "hard", "pass", 0.150, 0.210, 0.900, 0.10),  # J2 above unsupervised
        ("+ accelerations", "faded", "pass", 0.154, 0.218, 0.582, 0.90),
        ("+ accelerations", "faded, wider", "pass", 0.154, 0.220, 0.564, 0.01),  # best on records: not chosen
    ]
    columns = [
        "cost",
        "supervisor",
        "check",
        "0.02-0.1 g J1",
        "selection J1",
        "selection J2",
        "seven records J1",
    ]
    pick = study.chosen(pd.DataFrame(rows, columns=columns))
    assert (pick["cost"], pick["supervisor"]) == ("+ accelerations", "faded")


@pytest.mark.slow
def test_accelerations_in_lqg_s_cost_lower_j2_and_weight_zero_is_the_experiment_s_lqg():
    from rlcontroller.config import load_experiment
    from rlcontroller.control.lqg import design_lqg_ground_model
    from rlcontroller.physics.motions.records import synthetic_suite
    from rlcontroller.physics.plant import Plant

    sweep = load_script("lqg_acceleration_sweep")
    experiment = load_experiment(SCRIPTS.parent / "configs" / "five_story.yaml")
    plant = Plant(experiment)
    unweighted = sweep.with_acceleration_term(experiment, 0.0, 5.0)
    # the agent-only terms dropped
    assert [t.quantity for t in unweighted.terms] == ["drift", "base_shear", "force"]
    ours = design_lqg_ground_model(plant.design, reward=unweighted).feedback
    np.testing.assert_allclose(ours, design_lqg_ground_model(plant.design).feedback, rtol=1e-9)
    motions = synthetic_suite(count=3)
    rewards = [sweep.with_acceleration_term(experiment, weight, 5.0) for weight in (0.0, 0.3, 3.0)]
    j2 = [sweep.mean_metrics(plant, reward, motions)["J2"] for reward in rewards]
    assert j2[0] > j2[1] > j2[2]


def test_the_mass_driver_grid_keeps_every_stroke_in_its_housing():
    from rlcontroller.config import load_experiment
    from rlcontroller.physics.motions.records import synthetic_suite
    from rlcontroller.physics.plant import Plant

    study = load_script("mass_driver_lqg_grid")
    experiment = load_experiment(SCRIPTS.parent / "configs" / "experiments" / "five_story_amd.yaml")
    assert study.scaled_weights(experiment.reward, {"force": 1.0, "stroke": 1.0}) == experiment.reward
    tuned = Plant(experiment).building.devices[0].stiffness
    assert study.detuned(experiment, 0.9).building.devices[0].stiffness == pytest.approx(
        0.81 * tuned, rel=1e-12
    )
    controllers = study.grid(experiment, [1.0], [1.0, 30.0])
    passive, nominal, heavy = study.table(experiment, controllers, synthetic_suite(count=3), [0.85, 1.0])
    # the 1 m stroke limit is the driver's end-stop: every design stays within its housing (a few cm into a
    # stop)
    assert max(row["peak stroke (m)"] for row in (passive, nominal, heavy)) < 1.1
    assert nominal["J1 x1"] < passive["J1 x1"] < 1.0 and nominal["worst J1"] == nominal["J1 x0.85"]


def test_the_fallback_search_refuses_to_tune_on_the_check_suite():
    """The check suite is the judge: the search of the yielding building's fallback tunes on another seed."""
    import subprocess
    import sys

    script = script_path("search_fallback")
    done = subprocess.run(
        [sys.executable, str(script), "--suite-seed", "31337"], capture_output=True, text=True
    )
    assert (
        done.returncode == 2 and "--suite-seed 31337 is the check suite: tune on another seed" in done.stderr
    )


def test_the_strong_suites_draw_every_motion_strong_and_never_the_check_suite_s_seed(capsys, monkeypatch):
    from rlcontroller.config import load_experiment, load_safety_check
    from rlcontroller.evaluation.safety import check_suite
    from rlcontroller.physics.plant import Plant

    module = load_script("strong_suites")
    plant = Plant(load_experiment(module.EXPERIMENT))
    check = load_safety_check(SCRIPTS.parent / "configs" / "checks" / "standard.yaml")
    motions = check_suite(plant, module.strong_suite(check, 779, 24, 4.9, 14.71))
    pgas = np.array([motion.pga for motion in motions])
    assert len(motions) == 24 and pgas.min() >= 4.9 - 1e-9 and pgas.max() <= 14.71 + 1e-9
    assert pgas.max() > 2.0 * pgas.min()  # drawn over the range, not one level
    monkeypatch.setattr("sys.argv", ["strong_suites.py", "--seeds", str(check.seed)])
    with pytest.raises(SystemExit):
        module.main()
    assert "the check suite's" in capsys.readouterr().err


@pytest.mark.slow
def test_a_trigger_is_chosen_on_other_suites_and_a_margin_at_rest(capsys, monkeypatch):
    """The trigger selection never reads the check suite's seed; behind a trigger that switches nothing on (it
    never reaches full authority below 100 m/s^2), the shipped default is the building failed safe: each
    suite's mean J1 is 1, and at rest it drifts nothing, so no margin refuses it."""
    module = load_script("trigger_selection")
    default = SCRIPTS.parent / "models" / "five_story_every_story"
    monkeypatch.setattr(
        "sys.argv",
        [
            "trigger_selection.py",
            str(default / "config.yaml"),
            "--triggers",
            "0.1,0.3",
            "--seed",
            "777",
            "31337",
        ],
    )
    with pytest.raises(SystemExit):
        module.main()
    assert "seed 31337 is the check suite's" in capsys.readouterr().err
    *suites, rest = module.judged(default / "config.yaml", "", (50.0, 100.0), 777, model=default)
    assert suites[0].mean_J1 == pytest.approx(1.0, abs=1e-3) and rest.peak_drift_over_bound == 0.0


@pytest.mark.slow
def test_validation_rewards_reproduce_the_run_s_own_curve(tmp_path):
    """The kept policy, read back from its file and validated again, scores what the curve recorded when
    it was kept; LQG scores the curve's reference."""
    import csv

    from rlcontroller.config import load_experiment
    from rlcontroller.learning.training import train

    experiment = load_experiment(SCRIPTS.parent / "configs" / "testing" / "smoke.yaml")
    algorithm = experiment.algorithm.model_copy(
        update={"total_steps": 600, "checkpoint_every": 300, "eval_every": 300}
    )
    train(experiment=experiment.model_copy(update={"algorithm": algorithm}), run_dir=tmp_path / "run")
    with open(tmp_path / "run" / "learning_curve.csv", newline="") as handle:
        curve = list(csv.DictReader(handle))
    kept = max(curve, key=lambda row: float(row["eval_reward"]))
    rows = load_script("validation_rewards").validation_rows(tmp_path / "run")
    for key in ("eval_reward", "eval_J1", "eval_J2"):
        assert rows["run's best"][key] == pytest.approx(float(kept[key]), rel=1e-6)
    assert rows["LQG"]["eval_J1"] == pytest.approx(float(kept["lqg_J1"]), rel=1e-9)
    assert rows["LQG + ground model"]["eval_J2"] == pytest.approx(
        float(kept["lqg_ground_model_J2"]), rel=1e-9
    )
