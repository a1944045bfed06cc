"""Runtime assurance: the fail-safe twin is the Kalman estimate the building failed safe would give (by
superposition, whatever the actuators received), it tracks the fail-safe building simulated on the same
motion with sensor noise; the switch holds a destabilising controller near the fail-safe building; env
and batch apply it alike; a bad assurance section is one line."""

import numpy as np
import pytest
from conftest import assert_env_and_batch_agree

from rlcontroller.config import ConfigError, Experiment, build_experiment
from rlcontroller.control.controllers import LQGController, Uncontrolled
from rlcontroller.control.lqg import design_lqg_ground_model
from rlcontroller.learning.env import BuildingEnv, rollout
from rlcontroller.physics.motions.records import synthetic_suite
from rlcontroller.physics.plant import Plant

EVERY_STORY = [{"story": story, "force_limit": 1.0e5} for story in range(1, 6)]
SENSORS = {"state_estimate": True, "ground_model": True}
ASSURED = {"assurance": {"release": 1.0, "engage": 0.9}}


def experiment(supervisor=ASSURED) -> Experiment:
    return Experiment.model_validate({"actuators": EVERY_STORY, "sensors": SENSORS, "supervisor": supervisor})


class Flipped:
    """LQG with its sign reversed: it pumps energy in (a broken or adversarial controller)."""

    def __init__(self, plant: Plant) -> None:
        self.lqg = LQGController(design_lqg_ground_model(plant.design), plant, "LQG")
        self.name = "flipped LQG"

    def reset(self) -> None:
        self.lqg.reset()

    def act(self, observation: np.ndarray) -> np.ndarray:
        return -self.lqg.act(observation)


def peak_drift_ratios(env: BuildingEnv, controller, motion) -> np.ndarray:
    """Per story (m per m of height; m where the building states no heights, as the twin reads them)."""
    response, _ = rollout(env, motion, controller, seed=3)
    heights = env.plant.building.story_heights
    return np.abs(response.drift).max(axis=0) / (1.0 if heights is None else heights)


def test_the_twin_is_the_estimate_of_the_building_failed_safe_whatever_the_actuators_received():
    """Superposition: controlled estimate minus the known response to the applied forces equals, step by
    step, the estimate the same filter gives of the uncontrolled building under the same motion and noise."""
    motion = synthetic_suite(count=1)[0]
    assured, bare = BuildingEnv(experiment()), BuildingEnv(experiment(None))
    assurance = assured.supervisor.assurance
    controller = Flipped(assured.plant)  # so that the switch hands over and back: recovery forces count too
    observation, info = assured.reset(seed=3, options={"motion": motion})
    quiet, _ = bare.reset(seed=3, options={"motion": motion})
    controller.reset()
    twins, estimates, engaged = [], [], []
    for _ in range(info["steps"]):
        twins.append(assurance.twin(observation[None])[1][0])
        estimates.append(quiet[bare.layout.estimate] * bare.layout.estimate_scale)
        observation, *_ = assured.step(controller.act(observation))
        quiet, *_ = bare.step(np.zeros(5))
        engaged.append(assurance.engaged[0])
    twins, estimates = np.array(twins), np.array(estimates)
    assert 0.05 < np.mean(engaged) < 0.95  # both modes were exercised
    peak = np.abs(estimates).max(axis=0)
    # float32 storage
    np.testing.assert_array_less(np.abs(twins - estimates).max(axis=0), 1e-4 * peak + 1e-12)


def test_the_twin_s_story_peaks_are_the_fail_safe_building_s_within_one_percent_with_sensor_noise():
    env = BuildingEnv(experiment())
    assurance = env.supervisor.assurance
    controller = LQGController(design_lqg_ground_model(env.plant.design), env.plant, "LQG")
    for motion in synthetic_suite(count=3):
        observation, info = env.reset(seed=3, options={"motion": motion})
        controller.reset()
        twin_peak = np.zeros(5)
        for _ in range(info["steps"]):
            twin_peak = np.maximum(
                twin_peak, np.abs(assurance.twin(observation[None])[1][0] @ assurance.drift_t)
            )
            observation, *_ = env.step(controller.act(observation))
        true_peak = peak_drift_ratios(BuildingEnv(experiment(None)), Uncontrolled(5), motion)
        np.testing.assert_allclose(twin_peak, true_peak, rtol=0.01)


def test_the_switch_holds_a_destabilising_controller_near_the_building_failed_safe():
    motion = synthetic_suite(count=1)[0]
    failed_safe = peak_drift_ratios(BuildingEnv(experiment(None)), Uncontrolled(5), motion).max()
    free_env, assured_env = BuildingEnv(experiment(None)), BuildingEnv(experiment())
    free = peak_drift_ratios(free_env, Flipped(free_env.plant), motion).max()
    assured = peak_drift_ratios(assured_env, Flipped(assured_env.plant), motion).max()
    assert free > 3.0 * failed_safe  # unguarded, it drives the building far beyond its fail-safe response
    assert assured < 1.25 * failed_safe


def test_env_and_batch_apply_the_switch_alike():
    assert_env_and_batch_agree(Plant(experiment()), synthetic_suite(count=2), Flipped)


@pytest.mark.parametrize(
    ("assurance", "message"),
    [
        ({"release": 0.8, "engage": 0.9}, "<config>: supervisor.assurance: .*engage 0.9 above release 0.8"),
        ({"release": 0.0}, "<config>: supervisor.assurance.release: Input should be greater than 0"),
        ({"margin": 1.0}, "<config>: supervisor.assurance.margin: unknown key"),
    ],
)
def test_a_bad_assurance_section_is_one_line_naming_the_field(assurance, message):
    with pytest.raises(ConfigError, match="^" + message) as error:
        build_experiment({"sensors": SENSORS, "supervisor": {"assurance": assurance}})
    assert "\n" not in str(error.value)


def test_assurance_needs_the_state_estimate():
    with pytest.raises(
        ConfigError, match=r"^<config>: supervisor.assurance: needs sensors.state_estimate: true"
    ):
        build_experiment({"supervisor": {"assurance": {}}})
