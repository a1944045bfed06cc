"""The plant: built once from an experiment, shared by the env and every design."""

import numpy as np
import pytest

from rlcontroller.config import Experiment, MeasurementConfig, SensorConfig
from rlcontroller.learning.env import BuildingEnv
from rlcontroller.physics.dynamics import output_matrices
from rlcontroller.physics.plant import Plant


@pytest.mark.parametrize(
    ("sensors", "size", "estimate"),
    [({}, 33, 0), ({"state_estimate": True}, 43, 10), ({"state_estimate": True, "ground_model": True}, 45, 12)],
)
def test_the_observation_layout(sensors, size, estimate):
    """H = 5 blocks of 5 floor accelerations + the ground, the estimate, then 3 actions."""
    plant = Plant(Experiment(sensors=sensors))
    layout = plant.layout
    assert layout.size == size and layout.readings == slice(0, 5) and layout.ground == 5
    assert layout.estimate.stop - layout.estimate.start == estimate and layout.action == slice(size - 3, size)
    assert BuildingEnv(plant).observation_space.shape == (size,)


def test_sensor_rows_pick_the_configured_floors():
    sensors = SensorConfig(
        measurements=[
            MeasurementConfig(quantity="drift", floors=[2, 4], scale=0.01, noise_std=1e-4),
            MeasurementConfig(quantity="absolute_acceleration", scale=5.0),
        ]
    )
    plant = Plant(Experiment(sensors=sensors))
    drift_c, _ = output_matrices(plant.building, "drift")
    np.testing.assert_array_equal(plant.sensors.c[:2], drift_c[[1, 3]])
    np.testing.assert_array_equal(plant.sensors.scale, [0.01, 0.01] + [5.0] * 5)
    np.testing.assert_array_equal(plant.sensors.noise_std, [1e-4, 1e-4] + [0.0] * 5)


def test_step_maps_are_built_once_and_shared():
    plant = Plant(Experiment())
    assert plant.step_map(4) is plant.step_map(4) and plant.step_map(1) is not plant.step_map(4)
    env = BuildingEnv(plant)
    assert env.plant is plant and env.step_map(4) is plant.step_map(4)
    assert plant.ground_model_step() is plant.ground_model_step()
