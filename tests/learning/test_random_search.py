from collections import deque

import numpy as np
import pytest
import yaml
from conftest import REPOSITORY, SAME_PHYSICS
from typer.testing import CliRunner

from rlcontroller.cli import app
from rlcontroller.config import load_experiment
from rlcontroller.control.controllers import ConstantCommand, fail_safe_controller
from rlcontroller.control.policy_file import read_policy
from rlcontroller.learning.algorithms import build_model, make_vec_env
from rlcontroller.learning.random_search import STANDARD_PENALTY, RandomSearch, standard_cost
from rlcontroller.learning.training import train
from rlcontroller.physics.motions.records import synthetic_suite
from rlcontroller.physics.plant import Plant
from rlcontroller.simulation.rollout import batch_rollout

MODEL_FREE = REPOSITORY / "studies" / "model_free" / "five_story_model_free_random_search.yaml"


def tiny(config=MODEL_FREE, **algorithm):
    """A random search on 2-3 s motions: a run of a few seconds."""
    experiment = load_experiment(config)
    settings = experiment.algorithm.model_dump() | {"eval_every": 4000, "checkpoint_every": 8000} | algorithm
    # the learner's defaults
    settings["kwargs"] = {"n_delta": 2, "n_motions": 2} | algorithm.get("kwargs", {})
    excitation = experiment.excitation.model_dump() | {
        "generator": {"kind": "noise_impulses", "duration": [2.0, 3.0]},
        "validation_generator": {"kind": "noise_impulses", "duration": [2.0, 3.0]},
        "validation_motions": 2,
    }
    return experiment.model_validate(
        experiment.model_dump() | {"algorithm": settings, "excitation": excitation}
    )


def new_model(experiment, seed: int = 0):
    model = build_model(experiment, make_vec_env(Plant(experiment), seed), seed, "cpu", tensorboard=None)
    model.ep_info_buffer = deque(maxlen=100)
    return model


@pytest.mark.slow
def test_plus_and_minus_run_on_the_same_motions_and_noise():
    model = new_model(tiny())
    rng = np.random.default_rng(3)
    model.weights = 0.05 * rng.standard_normal(model.weights.shape)
    direction = 0.05 * rng.standard_normal((1, *model.weights.shape))
    motions, seeds = synthetic_suite(count=2), [11, 12]
    plus, minus, steps = model.paired_log_costs(direction, motions, seeds)
    swapped_plus, swapped_minus, _ = model.paired_log_costs(-direction, motions, seeds)
    assert plus[0] != minus[0]
    # the same motion and noise in both lanes
    assert swapped_plus[0] == minus[0] and swapped_minus[0] == plus[0]
    zero_plus, zero_minus, _ = model.paired_log_costs(np.zeros_like(direction), motions, seeds)
    assert zero_plus[0] == zero_minus[0]
    control_steps = sum(round(m.duration / 0.02) for m in motions)
    assert abs(steps - 2 * control_steps) <= 4  # both lanes, every motion, counted once


def test_an_iteration_steps_downhill_on_its_own_motions():
    """For a small step the update lowers the mean log cost on the motions it was computed from."""
    model = new_model(tiny(kwargs={"learning_rate": 0.002}), seed=1)
    seen = []
    paired_log_costs = model.paired_log_costs
    model.paired_log_costs = lambda deltas, motions, seeds: (
        seen.append((motions, seeds)) or paired_log_costs(deltas, motions, seeds)
    )
    model.iterate()
    zero = np.zeros((1, *model.weights.shape))
    after = paired_log_costs(zero, *seen[0])[0][0]
    model.weights = np.zeros_like(model.weights)
    before = paired_log_costs(zero, *seen[0])[0][0]
    assert after < before


def pushed(model, motions, seeds):
    """f(W + d), f(W - d) of a candidate d that drives every actuator by the first reading (energy in), and
    that candidate's and the building failed safe's runs on the same motions and seeds."""
    pushing = np.zeros((1, *model.weights.shape))
    pushing[0, :, 0] = 5.0
    plus, minus, _ = model.paired_log_costs(pushing, motions, seeds)
    controllers = [model_controller(model, pushing[0]), fail_safe_controller(model.plant)]
    return plus, minus, batch_rollout(model.plant, motions, controllers, seeds=seeds, randomize=True)


def test_the_standard_objective_prices_every_motion_made_worse_than_failing_safe():
    """f of a candidate that never acts is exactly 1 (J1 of the building failed safe against itself, nothing
    priced); a candidate that pushes the building is priced by the check's own measure."""
    model = new_model(tiny(residual_lqg=False, kwargs={"objective": "standard"}))
    motions, seeds = synthetic_suite(count=2), [11, 12]
    plus, minus, _ = model.paired_log_costs(np.zeros((1, *model.weights.shape)), motions, seeds)
    assert plus[0] == minus[0] == 1.0
    plus, minus, runs = pushed(model, motions, seeds)
    assert plus[0] == pytest.approx(standard_cost(runs[0], runs[1]), rel=1e-12)
    assert max(plus[0], minus[0]) > 1.0 + STANDARD_PENALTY * 0.01  # priced beyond its J1


def test_the_peaks_objective_adds_each_motions_floor_acceleration_ratio():
    """`objective: peaks`: a candidate that never acts costs exactly 2 (J1 and J2 of the building failed safe
    against itself); one that acts costs its standard cost plus its mean J2, motion by motion."""
    model = new_model(tiny(residual_lqg=False, kwargs={"objective": "peaks"}))
    motions, seeds = synthetic_suite(count=2), [11, 12]
    plus, minus, _ = model.paired_log_costs(np.zeros((1, *model.weights.shape)), motions, seeds)
    assert plus[0] == minus[0] == 2.0
    plus, _, runs = pushed(model, motions, seeds)
    j2 = [
        np.mean(
            np.max(np.abs(r.absolute_acceleration), axis=0) / np.max(np.abs(f.absolute_acceleration), axis=0)
        )
        for (r, _), (f, _) in zip(runs[0], runs[1], strict=True)
    ]
    assert j2[0] != pytest.approx(1.0, abs=1e-3)  # the push moves the floors
    assert plus[0] == pytest.approx(standard_cost(runs[0], runs[1]) + np.mean(j2), rel=1e-12)


def model_controller(model, weights):
    from rlcontroller.control.controllers import LinearFeedback

    return LinearFeedback(weights, prior=model.prior, bias=None)


def saved_policy(run, model):
    """The run's saved policy, as evaluation reads it (data, no unpickling)."""
    return read_policy(run, model, Plant(load_experiment(run / "config.yaml")))


@pytest.mark.slow
def test_a_run_learns_to_control_and_its_model_acts_as_clip_w_o(tmp_path):
    summary = train(experiment=tiny(total_steps=40000), run_dir=tmp_path / "run")
    assert summary.steps >= 40000 and summary.best["eval_J1"] < 0.95  # no control: 1
    controller = saved_policy(tmp_path / "run", "best")
    weights = RandomSearch.load(tmp_path / "run" / "best_model.zip", device="cpu").weights
    observations = np.random.default_rng(5).standard_normal((6, weights.shape[1])).astype(np.float32) * 30
    expected = np.clip(observations @ weights.T, -1.0, 1.0)
    np.testing.assert_allclose(controller.act(observations), expected, rtol=1e-5, atol=1e-5)
    assert controller.actor.odd and np.all(controller.act(np.zeros(weights.shape[1], np.float32)) == 0.0)


def test_a_network_search_on_dampers_starts_at_its_initial_bias_as_its_saved_policy_acts():
    dampers = REPOSITORY / "configs" / "experiments" / "five_story_mr.yaml"
    policy = {"actor_arch": [8], "odd": False}
    # passive-off, any hidden layer
    model = new_model(tiny(dampers, policy=policy, kwargs={"initial_bias": -1.0}))
    motions, seeds = synthetic_suite(count=2), [4, 5]
    passive_off = batch_rollout(model.plant, motions, [ConstantCommand(-1.0, 3, "off")], seeds=seeds)[0]
    start = np.zeros((1, *model.weights.shape))
    assert model.paired_log_costs(start, motions, seeds)[0][0] == pytest.approx(
        np.mean([np.log(-total) for _, total in passive_off]), rel=1e-12
    )
    observations = np.random.default_rng(5).standard_normal((4, model.observation_space.shape[0]))
    np.testing.assert_array_equal(model.candidate(model.weights).act(observations.astype(np.float32)), -1.0)


@pytest.mark.slow
def test_an_affine_search_on_dampers_learns_a_bias_and_its_model_acts_as_clip_w_o_plus_b(tmp_path):
    dampers = REPOSITORY / "configs" / "experiments" / "five_story_mr.yaml"
    policy = {"actor_arch": [], "odd": False}
    model = new_model(tiny(dampers, policy=policy, kwargs={"initial_bias": 1.0}))  # starts at full voltage
    motions, seeds = synthetic_suite(count=2), [4, 5]
    passive_on = batch_rollout(model.plant, motions, [ConstantCommand(1.0, 3, "on")], seeds=seeds)[0]
    assert model.paired_log_costs(np.zeros((1, *model.weights.shape)), motions, seeds)[0][0] == pytest.approx(
        np.mean([np.log(-total) for _, total in passive_on]), rel=1e-12
    )

    train(experiment=tiny(dampers, policy=policy, total_steps=8000), run_dir=tmp_path / "run")
    parameters = RandomSearch.load(tmp_path / "run" / "final_model.zip", device="cpu").weights
    weights, bias = parameters[:, :-1], parameters[:, -1]
    assert np.all(bias != 0.0)
    controller = saved_policy(tmp_path / "run", "final")
    observations = np.random.default_rng(5).standard_normal((6, weights.shape[1])).astype(np.float32)
    expected = np.clip(observations @ weights.T + bias, -1.0, 1.0)
    np.testing.assert_allclose(controller.act(observations), expected, rtol=1e-5, atol=1e-5)
    assert not controller.actor.odd


@pytest.mark.slow
def test_a_residual_search_starts_at_its_prior_and_saves_a_residual_model(tmp_path):
    from rlcontroller.control.controllers import LinearFeedback, LQGController
    from rlcontroller.control.lqg import design_lqg_ground_model

    # its sensors hold the Kalman estimate
    robust = REPOSITORY / "studies" / "robustness" / "five_story_robust.yaml"
    experiment = tiny(
        robust, name="RandomSearch", policy={"actor_arch": [], "odd": True}, normalize_rewards=False
    )
    experiment = experiment.model_validate(experiment.model_dump() | {"plant_randomization": None})
    model = new_model(experiment)
    motions, seeds = synthetic_suite(count=2), [4, 5]
    at_zero = model.paired_log_costs(np.zeros((1, *model.weights.shape)), motions, seeds)[0][0]
    lqg = LQGController(design_lqg_ground_model(model.plant.design), model.plant)
    lqg_runs = batch_rollout(model.plant, motions, [lqg], seeds=seeds)[0]
    assert at_zero == pytest.approx(np.mean([np.log(-total) for _, total in lqg_runs]), rel=SAME_PHYSICS)

    train(
        experiment=experiment.model_copy(
            update={"algorithm": experiment.algorithm.model_copy(update={"total_steps": 8000})}
        ),
        run_dir=tmp_path / "run",
    )
    controller = saved_policy(tmp_path / "run", "final")
    weights = RandomSearch.load(tmp_path / "run" / "final_model.zip", device="cpu").weights
    assert controller.prior is not None and np.any(weights != 0.0)
    observations = np.random.default_rng(2).standard_normal((6, weights.shape[1])).astype(np.float32)
    expected = LinearFeedback(weights, prior=controller.prior).act(observations)
    np.testing.assert_allclose(controller.act(observations), expected, rtol=1e-5, atol=1e-5)


@pytest.mark.slow
def test_a_network_search_starts_at_its_prior_and_its_saved_policy_acts_as_its_candidates(tmp_path):
    """With hidden layers every weight and bias is searched: the action layer starts at zero (the prior acts
    alone), and the saved policy (numpy, as exported) acts as the candidate the search ran."""
    robust = REPOSITORY / "studies" / "robustness" / "five_story_robust.yaml"
    network = {"actor_arch": [16, 16], "odd": True}
    experiment = tiny(robust, name="RandomSearch", policy=network, normalize_rewards=False)
    experiment = experiment.model_validate(experiment.model_dump() | {"plant_randomization": None})
    model = new_model(experiment)
    observations = np.random.default_rng(2).standard_normal((6, model.plant.layout.size)).astype(np.float32)
    at_start = model.candidate(model.weights)
    np.testing.assert_allclose(
        at_start.act(observations), np.clip(at_start.prior(observations), -1.0, 1.0), atol=1e-6
    )
    hidden = model.weights.size - model.plant.building.n_actuators * 17  # all but the action layer's W and b
    assert hidden == 16 * model.plant.layout.size + 16 + 16 * 16 + 16

    train(
        experiment=experiment.model_copy(
            update={"algorithm": experiment.algorithm.model_copy(update={"total_steps": 8000})}
        ),
        run_dir=tmp_path / "run",
    )
    searched = RandomSearch.load(tmp_path / "run" / "final_model.zip", device="cpu")
    assert np.any(searched.weights[hidden:] != 0.0)  # the action layer moved off zero
    expected = model.candidate(searched.weights).act(observations)  # a loaded model has no plant, so no prior
    np.testing.assert_allclose(saved_policy(tmp_path / "run", "final").act(observations), expected, atol=1e-5)


@pytest.mark.slow
def test_a_stopped_run_resumes_to_the_same_weights_as_an_uninterrupted_one(tmp_path):
    experiment = tiny(total_steps=24000)
    whole = train(experiment=experiment, run_dir=tmp_path / "whole")
    # stops after one iteration
    stopped = train(experiment=experiment, run_dir=tmp_path / "stop", time_limit_s=0.0)
    assert stopped.time_limit_reached and stopped.steps < 24000
    resumed = train(resume=tmp_path / "stop")
    assert resumed.steps == whole.steps
    final = [
        RandomSearch.load(tmp_path / run / "final_model.zip", device="cpu").weights
        for run in ("whole", "stop")
    ]
    np.testing.assert_array_equal(final[0], final[1])


@pytest.mark.slow
def test_the_progress_bar_counts_simulated_steps(tmp_path, capsys):
    import re

    summary = train(experiment=tiny(total_steps=8000), run_dir=tmp_path / "run", progress_bar=True)
    output = capsys.readouterr()
    shown = re.findall(r"([\d,]+)/8,000", output.out + output.err)
    assert shown and int(shown[-1].replace(",", "")) == summary.steps >= 8000  # not one tick per iteration


@pytest.mark.parametrize(
    ("algorithm", "expected"),
    [
        ("{normalize_rewards: true}", "algorithm.normalize_rewards: not for RandomSearch"),
        ("{vec_env: dummy}", "algorithm.vec_env: not for RandomSearch"),
        ("{kwargs: {delta_std: 0}}", "algorithm.kwargs.delta_std: expected a number in"),
        ("{kwargs: {n_delta: 2.5}}", "algorithm.kwargs.n_delta: expected an integer in"),
        ("{kwargs: {initial_bias: 2}}", "algorithm.kwargs.initial_bias: expected a number in [-1.0, 1.0]"),
        ("{kwargs: {initial_bias: 0.5}}", "initial_bias 0.5 needs an affine policy (policy.odd: false)"),
        ("{kwargs: {batch_size: 64}}", "algorithm.kwargs.batch_size: not a keyword argument of RandomSearch"),
        (
            "{kwargs: {objective: check}}",
            "algorithm.kwargs.objective: expected one of return, standard, peaks, got 'check'",
        ),
    ],
)
def test_bad_random_search_settings_exit_2_naming_the_key(tmp_path, algorithm, expected):
    settings = yaml.safe_load(algorithm)
    base = {"name": "RandomSearch", "policy": {"actor_arch": [], "odd": True}}
    path = tmp_path / "bad.yaml"
    sensors = REPOSITORY / "configs" / "sensors" / "floor_accelerations_integrated.yaml"
    path.write_text(yaml.safe_dump({"sensors": str(sensors), "algorithm": base | settings}))
    result = CliRunner().invoke(app, ["train", str(path), "--run-dir", str(tmp_path / "run")])
    assert result.exit_code == 2, result.output
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and expected in lines[0] and "bad.yaml" in lines[0], lines
    assert not (tmp_path / "run").exists()
