"""DAgger: its loss is the env's action error; its iterations bring the policy's actions to MPC's on states
it visits itself; it trains, saves and reloads through `rlc train` like any learner."""

from collections import deque

import numpy as np
import pytest
import torch
from conftest import REPOSITORY

from rlcontroller.config import ConfigError, build_experiment, load_experiment
from rlcontroller.control.controllers import LQGController
from rlcontroller.control.lqg import design_lqg_ground_model
from rlcontroller.control.mpc_controllers import SemiActiveMPC
from rlcontroller.control.policy_file import read_policy
from rlcontroller.learning.algorithms import build_model, make_vec_env
from rlcontroller.learning.imitation import DAgger, imitation_loss
from rlcontroller.learning.training import train
from rlcontroller.physics.motions.loads import generate_suite
from rlcontroller.physics.plant import Plant
from rlcontroller.simulation.rollout import batch_rollout

STUDY = REPOSITORY / "studies" / "mpc" / "five_story_every_story_dagger.yaml"


def small(**kwargs):
    """The study's experiment on 3-4 s motions, MPC over 5 steps, a small network."""
    experiment = load_experiment(STUDY)
    algorithm = experiment.algorithm.model_dump() | {"eval_every": 2000, "checkpoint_every": 2000}
    algorithm["policy"] = algorithm["policy"] | {"actor_arch": [32]}
    algorithm["kwargs"] = {"horizon": 5, "n_motions": 4, "epochs": 20, "batch_size": 64} | kwargs
    excitation = experiment.excitation.model_dump() | {
        "generator": {"kind": "kanai_tajimi", "duration": [3.0, 4.0], "pga": [4.0, 8.0]},
        "validation_generator": {"kind": "kanai_tajimi", "duration": [3.0, 4.0], "pga": [4.0, 8.0]},
        "validation_motions": 2,
    }
    return experiment.model_validate(
        experiment.model_dump() | {"algorithm": algorithm, "excitation": excitation}
    )


def test_the_loss_is_the_envs_action_error():
    """The env's action is clip(clip(residual) + prior): the loss is its squared error, zero where the env's
    action and MPC's are at the same limit."""
    expert = torch.tensor([[0.5, 1.0, -1.0, 1.0]])
    prior = torch.tensor([[0.2, 0.9, -0.5, 0.0]])
    # 0.5; beyond 1 with MPC at 1; beyond -1 with MPC at -1; 0.4
    exact = torch.tensor([[0.3, 0.6, -0.8, 0.4]])
    assert float(imitation_loss(exact, prior, expert)) == pytest.approx(0.6**2 / 4)  # the last is off by 0.6
    assert float(imitation_loss(exact + torch.tensor([[0.0, 0.0, 0.0, 0.6]]), prior, expert)) == 0.0
    assert float(imitation_loss(torch.tensor([[0.3, -1.0, 1.0, 1.0]]), prior, expert)) == pytest.approx(
        (1.1**2 + 1.5**2) / 4
    )
    # a residual of 3 reaches 1 + prior = 0.5 only, where MPC is at 1: its error, and its excess over 1
    beyond = imitation_loss(torch.tensor([[3.0]]), torch.tensor([[-0.5]]), torch.tensor([[1.0]]))
    assert float(beyond) == pytest.approx(0.5**2 + 2.0**2)
    # no prior: any action beyond the limit MPC is at costs nothing
    assert (
        float(imitation_loss(torch.tensor([[4.0, -2.0]]), torch.zeros(1, 2), torch.tensor([[1.0, -1.0]])))
        == 0.0
    )


@pytest.mark.slow
def test_iterations_bring_the_policy_to_mpc_on_states_it_visits():
    """After cloning and two DAgger iterations, the policy's action error against MPC on fresh generated
    motions, at the states the policy itself reaches, is a small fraction of clipped LQG's."""
    torch.manual_seed(0)
    experiment = small()
    plant = Plant(experiment)
    model = build_model(experiment, make_vec_env(plant, 0), 0, "cpu", tensorboard=None)
    model.ep_info_buffer = deque(maxlen=100)
    for iteration in range(3):
        model.collect(expert_acts=iteration == 0)
        model.fit()
    motions = generate_suite(experiment.excitation.generator, 3, 99, plant.building)
    errors = {"policy": [], "prior": []}
    lqg = LQGController(design_lqg_ground_model(plant.design), plant.design)

    class Judge:
        name = "judge"

        def reset(self):
            model.expert.reset()
            lqg.reset()

        def act(self, observation):
            expert = model.expert.act(observation)
            action = model.act(observation)
            errors["policy"].append(np.mean((action - expert) ** 2))
            errors["prior"].append(np.mean((lqg.act(observation) - expert) ** 2))
            return action

    batch_rollout(plant, motions, [Judge()], seeds=[5, 6, 7])
    assert np.mean(errors["prior"]) > 1e-3  # MPC is not the prior here: the limits bind
    assert np.mean(errors["policy"]) < 0.2 * np.mean(errors["prior"])


@pytest.mark.slow
def test_on_dampers_the_policy_learns_mpcs_commands(tmp_path):
    """With MR dampers the expert is `SemiActiveMPC` (its commands switch each damper on or off); after
    cloning and two iterations the policy's commands on fresh motions agree with MPC's switching on more steps
    than the better constant command does (labels out of step with their observations would not)."""
    torch.manual_seed(0)
    study = load_experiment(REPOSITORY / "studies" / "mpc" / "five_story_mr_dagger.yaml")
    experiment = small().model_copy(
        update={
            key: getattr(study, key) for key in ("devices", "actuators", "sensors", "reward", "supervisor")
        }
    )
    experiment = experiment.model_validate(experiment.model_dump())
    plant = Plant(experiment)
    model = build_model(experiment, make_vec_env(plant, 0), 0, "cpu", tensorboard=None)
    assert isinstance(model.expert, SemiActiveMPC)
    model.ep_info_buffer = deque(maxlen=100)
    for iteration in range(3):
        model.collect(expert_acts=iteration == 0)
        model.fit()
    pairs = []

    class Judge:
        name = "judge"

        def reset(self):
            model.expert.reset()

        def act(self, observation):
            action = model.act(observation)
            pairs.append((model.expert.act(observation), action))
            return action

    batch_rollout(
        plant,
        generate_suite(experiment.excitation.generator, 3, 99, plant.building),
        [Judge()],
        seeds=[5, 6, 7],
    )
    expert, learned = (np.concatenate(side) for side in zip(*pairs, strict=True))
    on = np.mean(expert > 0.0)
    assert 0.1 < on < 0.9  # MPC switches the dampers
    assert np.mean(np.sign(learned) == expert) > max(on, 1.0 - on) + 0.05


@pytest.mark.slow
def test_a_stopped_run_resumes_to_the_same_policy_as_an_uninterrupted_one(tmp_path):
    """A run stopped after one iteration and resumed ends with the uninterrupted run's data set and network
    (the data set, the optimiser and the generator are saved); the saved policy data act as the learner."""
    experiment = small()
    experiment = experiment.model_copy(
        update={"algorithm": experiment.algorithm.model_copy(update={"total_steps": 1500})}
    )
    whole = train(experiment=experiment, run_dir=tmp_path / "whole")
    stopped = train(experiment=experiment, run_dir=tmp_path / "stop", time_limit_s=0.0)
    assert stopped.time_limit_reached and stopped.steps < whole.steps
    assert train(resume=tmp_path / "stop").steps == whole.steps
    models = [DAgger.load(tmp_path / run / "final_model.zip", device="cpu") for run in ("whole", "stop")]
    np.testing.assert_array_equal(models[0].samples["expert"], models[1].samples["expert"])
    for first, second in zip(models[0].policy.parameters(), models[1].policy.parameters(), strict=True):
        torch.testing.assert_close(first, second, rtol=0, atol=0)
    plant = Plant(experiment)
    policy = read_policy(tmp_path / "whole", "final", plant)
    models[0].prior = policy.prior
    observations = np.random.default_rng(1).normal(0.0, 0.3, (8, plant.layout.size))
    np.testing.assert_allclose(policy.act(observations), models[0].act(observations), atol=1e-5)


@pytest.mark.parametrize(
    ("algorithm", "message"),
    [
        (
            {"name": "DAgger", "normalize_observations": True, "kwargs": {}},
            "algorithm.normalize_observations: not for DAgger",
        ),
        (
            {"name": "DAgger", "kwargs": {"horizon": 0}},
            "algorithm.kwargs.horizon: expected an integer in [1, 200]",
        ),
    ],
)
def test_what_dagger_refuses_is_refused_at_loading(algorithm, message):
    with pytest.raises(ConfigError) as error:
        build_experiment({"algorithm": algorithm})
    assert str(error.value).startswith(f"<config>: {message}") and "\n" not in str(error.value)


def test_dagger_under_wind_takes_mpc_on_the_wind_model():
    """Under wind DAgger's expert plans on the wind model's map, from LQG + wind model's estimate."""
    from rlcontroller.control.mpc_controllers import mpc_controller
    from rlcontroller.physics.plant import Plant

    wind = {"kind": "wind", "dt": 0.02, "duration": [60.0, 60.0], "speed": [20.0, 20.0]}
    experiment = build_experiment(
        {"algorithm": {"name": "DAgger", "kwargs": {}}, "excitation": {"generator": wind}}
    )
    plant = Plant(experiment)
    expert = mpc_controller(plant.design)
    assert (
        plant.wind is not None
        and expert.problem.linear.shape[1] == plant.design.sampled().wind_model.phi.shape[0]
    )
