"""The fail-safe twin in the observation (`sensors.twin`): its estimate is, step by step, the one the same
filter gives of the building failed safe under the same motion and noise, whatever the actuators received;
its running story peaks are the fail-safe building's within one percent with sensor noise; env and batch
build it alike; the observation stays the controller's whole state (the closed loop keeps its eigenvalues);
a twin the plant cannot have is one line."""

import numpy as np
import pytest
from conftest import assert_env_and_batch_agree

from rlcontroller.config import ConfigError, Experiment, build_experiment
from rlcontroller.control.controllers import LQGController, Uncontrolled
from rlcontroller.control.lqg import design_lqg_ground_model
from rlcontroller.learning.env import BuildingEnv, rollout
from rlcontroller.physics.motions.records import synthetic_suite
from rlcontroller.physics.plant import Plant
from rlcontroller.simulation.linearised import closed_loop_matrix

EVERY_STORY = [{"story": story, "force_limit": 1.0e5} for story in range(1, 6)]


def experiment(twin: bool = True) -> Experiment:
    sensors = {"state_estimate": True, "ground_model": True, "twin": twin}
    return Experiment.model_validate({"actuators": EVERY_STORY, "sensors": sensors})


def lqg(plant: Plant) -> LQGController:
    return LQGController(design_lqg_ground_model(plant.design), plant, "LQG")


def twin_block(env: BuildingEnv, observation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The twin's estimate and running story peaks (SI units) as the observation holds them."""
    values = observation[env.layout.twin].astype(float) * env.layout.twin_scale
    return np.split(values, [env.layout.estimate.stop - env.layout.estimate.start])


def test_the_twin_is_the_estimate_of_the_building_failed_safe_whatever_the_actuators_received():
    motion = synthetic_suite(count=1)[0]
    controlled, bare = BuildingEnv(experiment()), BuildingEnv(experiment(twin=False))
    controller = lqg(controlled.plant)
    observation, info = controlled.reset(seed=3, options={"motion": motion})
    quiet, _ = bare.reset(seed=3, options={"motion": motion})
    controller.reset()
    twins, estimates, peaks, forces = [], [], [], []
    drift = controlled.plant.building.drift_matrix()
    for _ in range(info["steps"]):
        twin, peak = twin_block(controlled, observation)
        twins.append(twin)
        peaks.append(peak)
        estimates.append(quiet[bare.layout.estimate] * bare.layout.estimate_scale)
        observation, *_ = controlled.step(controller.act(observation))
        quiet, *_ = bare.step(np.zeros(5))
        forces.append(controlled.command)
    twins, estimates, peaks = np.array(twins), np.array(estimates), np.array(peaks)
    assert np.abs(forces).max() > 0.5e5  # the controller acted: the twin is not the estimate itself
    scale = np.abs(estimates).max(axis=0)
    # float32 storage
    np.testing.assert_array_less(np.abs(twins - estimates).max(axis=0), 1e-4 * scale + 1e-12)
    running = np.maximum.accumulate(np.abs(estimates[:, :5] @ drift.T), axis=0)
    np.testing.assert_allclose(peaks, running, rtol=1e-4, atol=1e-4 * running.max())


def test_the_twin_s_story_peaks_are_the_fail_safe_building_s_within_one_percent_with_sensor_noise():
    env = BuildingEnv(experiment())
    controller = lqg(env.plant)
    for motion in synthetic_suite(count=3):
        observation, info = env.reset(seed=3, options={"motion": motion})
        controller.reset()
        for _ in range(info["steps"]):
            observation, *_ = env.step(controller.act(observation))
        twin_peak = twin_block(env, observation)[1]
        failed_safe, _ = rollout(BuildingEnv(experiment(twin=False)), motion, Uncontrolled(5), seed=3)
        np.testing.assert_allclose(twin_peak, np.abs(failed_safe.drift).max(axis=0), rtol=0.01)


def test_env_and_batch_build_the_twin_alike():
    assert_env_and_batch_agree(Plant(experiment()), synthetic_suite(count=2), lqg)


def test_the_observation_stays_the_whole_state_of_a_controller_that_ignores_the_twin():
    """The linearised closed loop with the twin block has every eigenvalue it has without (and the twin's own,
    the design model's): the batch reads the twin's difference back from the observation as it does the
    estimate."""
    with_twin, without = Plant(experiment()), Plant(experiment(twin=False))
    plain = np.linalg.eigvals(closed_loop_matrix(without, lqg(without)))
    extended = np.linalg.eigvals(closed_loop_matrix(with_twin, lqg(with_twin)))
    distance = np.abs(plain[:, None] - extended[None, :]).min(axis=1)
    assert distance.max() < 1e-6
    assert np.abs(extended).max() < 1.0


@pytest.mark.parametrize(
    ("document", "message"),
    [
        ({"sensors": {"twin": True}}, "<config>: sensors.twin: needs sensors.state_estimate: true"),
        (
            {
                "sensors": {"state_estimate": True, "twin": True},
                "actuators": [],
                "devices": [{"type": "mr_damper", "story": 1, "capacity": 1.0e5}],
            },
            "<config>: sensors.twin: not with semi-active dampers",
        ),
        (
            {
                "sensors": {"state_estimate": True, "twin": True},
                "actuators": [],
                "devices": [
                    {
                        "type": "active_mass",
                        "floor": 5,
                        "mass_ratio": 0.02,
                        "force_limit": 1.0e4,
                        "stroke_limit": 1.0,
                    }
                ],
            },
            "<config>: sensors.twin: not with a mass device on end-stops",
        ),
    ],
)
def test_a_twin_the_plant_cannot_have_is_one_line(document, message):
    with pytest.raises(ConfigError, match="^" + message) as error:
        build_experiment(document)
    assert "\n" not in str(error.value)
