import warnings

import gymnasium as gym
import numpy as np
import pytest
from conftest import REPOSITORY, SAME_PHYSICS
from gymnasium.utils.env_checker import check_env

from rlcontroller import ENV_ID
from rlcontroller.config import Experiment, MeasurementConfig, RewardTerm, SensorConfig
from rlcontroller.learning.env import BuildingEnv
from rlcontroller.physics.dynamics import simulate
from rlcontroller.physics.motions.excitation import Load, read_at2
from rlcontroller.physics.motions.records import synthetic_suite

NOISE_FREE = Experiment(
    sensors=SensorConfig(
        measurements=[MeasurementConfig(quantity="absolute_acceleration", scale=5.0)], ground_noise_std=0.0
    )
)


def rollout(env, seed, policy_seed=0):
    observation, _ = env.reset(seed=seed)
    rng = np.random.default_rng(policy_seed)
    observations, rewards = [observation], []
    truncated = False
    while not truncated:
        observation, reward, terminated, truncated, _ = env.step(rng.uniform(-1, 1, 3).astype(np.float32))
        assert not terminated
        observations.append(observation)
        rewards.append(reward)
    return np.array(observations), np.array(rewards)


def test_passes_the_gymnasium_env_checker():
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*infinity.*")
        check_env(BuildingEnv(), skip_render_check=True)


def test_gymnasium_make_builds_the_paper_case_or_a_config():
    env = gym.make(ENV_ID)
    assert env.observation_space.shape == (5 * 5 + 5 + 3,)
    assert env.action_space.shape == (3,)
    env = gym.make(ENV_ID, config=REPOSITORY / "configs" / "five_story.yaml")
    assert env.unwrapped.building.n_floors == 5


def test_same_seed_gives_identical_episodes():
    noisy = Experiment(
        sensors=SensorConfig(
            measurements=[MeasurementConfig(quantity="absolute_acceleration", scale=5.0, noise_std=0.1)]
        )
    )
    first = rollout(BuildingEnv(noisy), seed=11)
    second = rollout(BuildingEnv(noisy), seed=11)
    other = rollout(BuildingEnv(noisy), seed=12)
    np.testing.assert_array_equal(first[0], second[0])
    np.testing.assert_array_equal(first[1], second[1])
    assert first[0].shape != other[0].shape or not np.array_equal(first[0], other[0])


def test_steps_match_the_whole_record_simulation(records):
    motion = read_at2(records / "RSN1084_NORTHR_SCS052.AT2")  # dt 0.005 s: four sub-steps per control step
    env = BuildingEnv()
    env.reset(seed=0, options={"motion": motion})
    rng = np.random.default_rng(3)
    actions = rng.uniform(-1.2, 1.2, (env._n_steps, 3))
    drifts, accelerations, shears = [], [], []
    for action in actions:
        _, _, _, truncated, info = env.step(action)
        drifts.append(info["drift"])
        accelerations.append(info["absolute_acceleration"])
        shears.append(info["base_shear"])
    assert truncated
    forces = np.clip(actions, -1, 1) * 1e5
    from rlcontroller.physics.motions.excitation import on_control_grid

    grid = on_control_grid(motion, 0.02)
    samples, substeps = grid.ground, grid.substeps
    reference = simulate(env.building, env.plant.sampled(substeps).step, samples, forces=forces)
    np.testing.assert_allclose(drifts, reference.drift[1:], rtol=SAME_PHYSICS, atol=1e-12)
    np.testing.assert_allclose(
        accelerations, reference.absolute_acceleration[1:], rtol=SAME_PHYSICS, atol=1e-9
    )
    np.testing.assert_allclose(shears, reference.base_shear[1:], rtol=SAME_PHYSICS, atol=1e-6)


def test_reward_is_the_weighted_sum_of_scaled_squares():
    experiment = Experiment()
    env = BuildingEnv(experiment)
    env.reset(seed=4)
    for _ in range(20):
        _, reward, _, _, info = env.step(np.array([0.3, -0.8, 2.0]))
    terms = {term.quantity: term for term in experiment.reward.terms}
    drift = terms["drift"].weight * np.sum((info["drift"] / terms["drift"].scale) ** 2)
    shear = terms["base_shear"].weight * (info["base_shear"] / terms["base_shear"].scale) ** 2
    force = terms["force"].weight * np.sum((info["force"] / terms["force"].scale) ** 2)
    assert info["reward_drift"] == pytest.approx(drift)
    assert info["reward_base_shear"] == pytest.approx(shear)
    assert info["reward_force"] == pytest.approx(force)
    assert reward == pytest.approx(-(drift + shear + force))
    np.testing.assert_allclose(info["force"], [0.3e5, -0.8e5, 1e5])  # clipped to the limit


def test_observation_holds_the_history_newest_first():
    motion = Load("ramp", 0.02, np.linspace(0.0, 3.0, 101))
    env = BuildingEnv(NOISE_FREE)
    first, _ = env.reset(seed=0, options={"motion": motion})
    assert np.all(first == 0)  # at rest and the ramp starts at zero
    observations, infos = [], []
    for _ in range(6):
        observation, _, _, _, info = env.step(np.array([0.5, 0.0, -0.5]))
        observations.append(observation)
        infos.append(info)
    latest, previous = observations[-1], observations[-2]
    np.testing.assert_allclose(latest[6:30], previous[:24])  # blocks of 5 floors + ground shift by one
    np.testing.assert_allclose(latest[:5], infos[-1]["absolute_acceleration"] / 5.0, rtol=1e-6)
    np.testing.assert_allclose(latest[6:11], infos[-2]["absolute_acceleration"] / 5.0, rtol=1e-6)
    assert latest[5] == pytest.approx(motion.acceleration[6] / 5.0, rel=1e-6)
    assert latest[11] == pytest.approx(motion.acceleration[5] / 5.0, rel=1e-6)
    np.testing.assert_allclose(latest[30:], [0.5, 0.0, -0.5])
    assert latest.dtype == np.float32


def test_a_selected_sensor_layout_and_force_reward():
    experiment = Experiment(
        sensors=SensorConfig(
            ground_noise_std=0.0,
            history=2,
            measurements=[
                MeasurementConfig(quantity="drift", floors=[1, 5], scale=0.01),
                MeasurementConfig(quantity="force", scale=1e5),
            ],
        ),
        reward=Experiment().reward.model_copy(
            update={"terms": [RewardTerm(quantity="velocity", weight=2.0, scale=0.5)]}
        ),
    )
    env = BuildingEnv(experiment)
    observation, _ = env.reset(seed=0)
    assert observation.shape == (2 * (2 + 3) + 2 + 3,)
    observation, _, _, _, info = env.step(np.array([1.0, 0.0, -1.0]))
    np.testing.assert_allclose(observation[:2], info["drift"][[0, 4]] / 0.01, rtol=1e-5)
    np.testing.assert_allclose(observation[2:5], [1.0, 0.0, -1.0], rtol=1e-6)
    assert observation[5] == pytest.approx(env.motion.acceleration[1] / 5.0, rel=1e-6)
    assert "reward_velocity" in info


def test_step_after_the_end_is_refused():
    env = BuildingEnv()
    env.reset(options={"motion": Load("short", 0.02, np.zeros(3))})
    env.step(np.zeros(3))
    assert env.step(np.zeros(3))[3]
    with pytest.raises(RuntimeError, match="reset"):
        env.step(np.zeros(3))


def test_higher_power_and_force_change_terms():
    terms = [
        {"quantity": "drift", "weight": 2.0, "scale": 0.01, "power": 4},
        {"quantity": "force_change", "weight": 0.5, "scale": 2e4},
        {"quantity": "force", "weight": 1.0, "scale": 1e5},
    ]
    env = BuildingEnv(Experiment(reward={"terms": terms}))
    env.reset(seed=1)
    previous = np.zeros(3)
    for action in ([0.2, -0.4, 1.0], [0.5, 0.1, -0.3], [0.5, 0.1, -0.3]):
        _, reward, _, _, info = env.step(np.array(action))
        drift = 2.0 * np.sum((info["drift"] / 0.01) ** 4)
        change = 0.5 * np.sum(((np.array(action) - previous) * 1e5 / 2e4) ** 2)
        force = np.sum((info["force"] / 1e5) ** 2)
        assert info["reward_drift_p4"] == pytest.approx(drift)
        assert info["reward_force_change"] == pytest.approx(change)
        assert reward == pytest.approx(-(drift + change + force))
        previous = np.array(action)
    assert info["reward_force_change"] == 0.0


def test_state_estimate_in_the_observation_tracks_the_true_state():
    sensors = SensorConfig(state_estimate=True)
    env = BuildingEnv(Experiment(sensors=sensors))
    observation, _ = env.reset(seed=3)
    assert observation.shape == (5 * 6 + 10 + 3,)
    errors, sizes = [], []
    for _ in range(400):
        observation, _, _, truncated, _ = env.step(np.array([0.3, -0.2, 0.1]))
        estimate = observation[30:40].astype(float) * np.repeat([0.02, 0.2], 5)
        errors.append(np.abs(estimate[:5] - env.state[:5]).max())
        sizes.append(np.abs(env.state[:5]).max())
        if truncated:
            break
    assert np.mean(errors[50:]) < 0.1 * np.mean(sizes[50:])
    np.testing.assert_allclose(observation[-3:], [0.3, -0.2, 0.1], rtol=1e-6)


def test_ground_model_estimate_predicts_the_ground_reading():
    """With `ground_model` the estimate ends with the Kanai-Tajimi filter states; their output
    tracks the measured ground acceleration."""
    from rlcontroller.physics.motions.generators import GroundModel

    env = BuildingEnv(Experiment(sensors=SensorConfig(state_estimate=True, ground_model=True)))
    observation, _ = env.reset(seed=3)
    assert observation.shape == (5 * 6 + 12 + 3,)
    model, predicted, measured = GroundModel(), [], []
    for _ in range(300):
        observation, _, _, truncated, _ = env.step(np.zeros(3))
        filter_states = observation[40:42].astype(float) * model.state_scale(env.layout.ground_scale)
        predicted.append(model.output @ filter_states)
        measured.append(observation[env.layout.ground] * env.layout.ground_scale)
        if truncated:
            break
    assert np.corrcoef(predicted, measured)[0, 1] > 0.95


RANDOMIZED = {
    "plant_randomization": {
        "stiffness": {"low": 0.7, "high": 1.3},
        "mass": {"low": 0.9, "high": 1.1},
        "time_constant": {"low": 0.005, "high": 0.05, "log": True},
        "delay_steps": [0, 2],
    }
}


@pytest.mark.slow
def test_randomised_plants_are_drawn_per_episode_from_the_seed_within_the_ranges():
    from rlcontroller.config import build_experiment
    from rlcontroller.physics.motions.records import synthetic_suite

    env = BuildingEnv(build_experiment(RANDOMIZED), randomize=True)
    motion = synthetic_suite(count=1)[0]
    draws = []
    for seed in range(200):
        env.reset(seed=seed, options={"motion": motion})
        config = env.plant.config
        draws.append(
            (config.stiffness, config.mass, config.actuators.time_constant, config.actuators.delay_steps)
        )
    stiffness, mass, lag, delay = (np.array(values) for values in zip(*draws, strict=True))
    assert stiffness.min() >= 0.7 and stiffness.max() <= 1.3 and mass.min() >= 0.9 and mass.max() <= 1.1
    assert set(delay) == {0, 1, 2} and lag.min() >= 0.005 and lag.max() <= 0.05
    assert abs(np.median(np.log(lag)) - np.log(np.sqrt(0.005 * 0.05))) < 0.2  # log-uniform: geometric median
    assert abs(np.mean(stiffness) - 1.0) < 0.03
    env.reset(seed=7, options={"motion": motion})  # the same seed draws the same plant again
    again = env.plant.config
    assert draws[7] == (
        again.stiffness,
        again.mass,
        again.actuators.time_constant,
        again.actuators.delay_steps,
    )


def test_without_randomize_the_env_runs_the_configured_plant():
    """Evaluation never draws: the env of `rlc evaluate` is built without randomize."""
    from rlcontroller.config import build_experiment

    env = BuildingEnv(build_experiment(RANDOMIZED))
    for seed in range(3):
        env.reset(seed=seed)
        assert env.plant.config is None and env.plant.n_state == 10


def test_the_last_actions_are_kept_newest_first():
    env = BuildingEnv(Experiment.model_validate({"sensors": {"action_history": 3}}))
    layout = env.layout
    assert layout.actions.stop - layout.actions.start == 9 and layout.size == layout.actions.stop
    observation, _ = env.reset(seed=0, options={"motion": synthetic_suite(count=1)[0]})
    assert not observation[layout.actions].any()
    actions = [np.full(3, 0.1), np.full(3, -0.2), np.full(3, 0.3)]
    for action in actions:
        observation, *_ = env.step(action)
    np.testing.assert_allclose(observation[layout.actions], np.concatenate(actions[::-1]), rtol=1e-6)
    np.testing.assert_allclose(observation[layout.action], actions[-1], rtol=1e-6)


@pytest.mark.slow
def test_a_reward_per_motion_does_not_depend_on_the_motion_intensity():
    """Noise-free sensors and LQG (linear in the readings): with `reward.per_motion` a motion and the
    same motion x 20 give the same return for homogeneous terms of powers 2 and 4 and a force change;
    without it, 20^2 times more for the quadratic terms."""
    from rlcontroller.control.controllers import LQGController
    from rlcontroller.control.lqg import design_lqg
    from rlcontroller.learning.env import rollout
    from rlcontroller.physics.plant import Plant

    terms = [
        {"quantity": "drift", "weight": 1.0, "scale": 0.01},
        {"quantity": "drift", "weight": 1.0, "scale": 0.02, "power": 4},
        {"quantity": "force_change", "weight": 0.2, "scale": 1.0e5},
    ]
    quiet = {"ground_noise_std": 0.0, "measurements": [{"quantity": "absolute_acceleration", "scale": 5.0}]}
    weak = synthetic_suite(count=1)[0]
    weak = Load("weak", weak.dt, weak.acceleration * (0.001 / np.abs(weak.acceleration).max()))
    strong = Load("strong", weak.dt, 20.0 * weak.acceleration)
    returns = {}
    for per_motion in (True, False):
        experiment = Experiment.model_validate(
            {"sensors": quiet, "reward": {"terms": terms, "per_motion": per_motion}}
        )
        plant = Plant(experiment)
        env = BuildingEnv(plant)
        lqg = LQGController(design_lqg(plant), plant)
        returns[per_motion] = [rollout(env, motion, lqg)[1] for motion in (weak, strong)]
        assert np.abs(rollout(env, strong, lqg)[0].force).max() < 0.99 * plant.force_limits.min()  # linear
    np.testing.assert_allclose(returns[True][1], returns[True][0], rtol=1e-3)  # float32 readings into LQG
    assert returns[False][1] / returns[False][0] > 400  # 20^2 for the quadratic terms, 20^4 for the other


def test_a_randomised_device_frequency_detunes_the_driver_per_episode():
    """The spring of an active mass driver, as drawn per episode, is the tuned one times the
    drawn frequency factor squared; the design model keeps the tuned spring."""
    from rlcontroller.config import build_experiment
    from rlcontroller.physics.plant import Plant

    driver = {
        "type": "active_mass",
        "floor": 5,
        "mass_ratio": 0.02,
        "force_limit": 1.0e4,
        "stroke_limit": 1.0,
    }
    experiment = build_experiment(
        {
            "actuators": [],
            "devices": [driver],
            "plant_randomization": {"device_frequency": {"low": 0.85, "high": 1.15}},
        }
    )
    tuned = Plant(experiment).design.building.devices[0].stiffness
    env = BuildingEnv(experiment, randomize=True)
    motion = synthetic_suite(count=1)[0]
    factors = []
    for seed in range(40):
        env.reset(seed=seed, options={"motion": motion})
        factor = env.plant.config.devices.frequency
        assert env.plant.building.devices[0].stiffness == pytest.approx(tuned * factor**2, rel=1e-12)
        factors.append(factor)
    assert 0.85 <= min(factors) < 0.9 and 1.1 < max(factors) <= 1.15


def test_randomised_yield_drifts_are_the_plants_own_times_one_drawn_factor():
    """A yield-drift range is a factor on the plant's own per-story yield drifts, drawn per episode."""
    from rlcontroller.config import build_experiment

    own = [0.01, 0.012, 0.014, 0.012, 0.01]
    experiment = build_experiment(
        {
            "plant": {"hysteresis": {"yield_drift": own}},
            "plant_randomization": {"yield_drift": {"low": 0.8, "high": 1.25, "log": True}},
        }
    )
    env = BuildingEnv(experiment, randomize=True)
    motion = synthetic_suite(count=1)[0]
    factors = []
    for seed in range(30):
        env.reset(seed=seed, options={"motion": motion})
        drawn = np.asarray(env.plant.yielding.yield_drift) / own
        assert np.ptp(drawn) < 1e-12  # one factor on every story
        factors.append(drawn[0])
    assert 0.8 <= min(factors) < 0.9 and 1.15 < max(factors) <= 1.25
