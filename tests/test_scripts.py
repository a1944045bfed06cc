import importlib.util
from pathlib import Path

import numpy as np

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"


def load_script(name: str):
    spec = importlib.util.spec_from_file_location(name, SCRIPTS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_prediction_r2_is_one_for_a_sine_and_zero_for_white_noise():
    prediction_r2 = load_script("ground_predictability").prediction_r2
    time = np.arange(3000) * 0.02
    assert prediction_r2(np.sin(7.0 * time), horizon=10) > 0.999
    noise = np.random.default_rng(0).standard_normal(3000)
    assert abs(prediction_r2(noise, horizon=1)) < 0.02


def test_generated_records_are_read_back_as_written(tmp_path):
    import subprocess
    import sys

    from rlcontroller.physics.excitation import STANDARD_GRAVITY
    from rlcontroller.physics.records import load_records

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


def test_random_search_runs_plus_and_minus_on_the_same_motions_and_noise():
    from rlcontroller.config import Experiment
    from rlcontroller.physics.plant import Plant
    from rlcontroller.physics.records import synthetic_suite

    paired_log_costs = load_script("linear_random_search").paired_log_costs
    plant = Plant(Experiment())
    rng = np.random.default_rng(3)
    weights = 0.05 * rng.standard_normal((plant.building.n_actuators, plant.layout.size))
    direction = 0.05 * rng.standard_normal((1, *weights.shape))
    motions, seeds = synthetic_suite(count=2), [11, 12]
    plus, minus = paired_log_costs(plant, weights, direction, motions, seeds)
    swapped_plus, swapped_minus = paired_log_costs(plant, weights, -direction, motions, seeds)
    assert plus[0] != minus[0]
    assert swapped_plus[0] == minus[0] and swapped_minus[0] == plus[0]  # the same motion and noise in both lanes
    zero_plus, zero_minus = paired_log_costs(plant, weights, np.zeros_like(direction), motions, seeds)
    assert zero_plus[0] == zero_minus[0]


def test_a_random_search_policy_is_saved_as_a_model_that_acts_as_clip_w_o(tmp_path):
    from conftest import REPOSITORY

    from rlcontroller.config import load_experiment
    from rlcontroller.learning.policy import PolicyController

    script = load_script("linear_random_search")
    experiment = load_experiment(REPOSITORY / "configs" / "five_story_model_free.yaml")
    rng = np.random.default_rng(5)
    n = script.Plant(experiment).layout.size
    weights = 0.3 * rng.standard_normal((3, n))
    script.as_model(experiment, weights).save(tmp_path / "best_model.zip")
    (tmp_path / "config.yaml").write_text(experiment.to_yaml())
    controller = PolicyController.load(tmp_path / "best_model.zip")
    observations = rng.standard_normal((6, n)).astype(np.float32)
    expected = np.clip(observations @ weights.T, -1.0, 1.0)
    np.testing.assert_allclose(controller.act(observations), expected, rtol=1e-5, atol=1e-5)
