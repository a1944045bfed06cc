"""The plant: built once from an experiment, shared by the env and every design."""

import numpy as np
import pytest
from conftest import SAME_PHYSICS

from rlcontroller.config import Experiment, MeasurementConfig, SensorConfig
from rlcontroller.learning.env import BuildingEnv
from rlcontroller.physics.dynamics import output_matrices
from rlcontroller.physics.motions.excitation import Load
from rlcontroller.physics.plant import Plant


@pytest.mark.parametrize(
    ("sensors", "size", "estimate"),
    [
        ({}, 33, 0),
        ({"state_estimate": True}, 43, 10),
        ({"state_estimate": True, "ground_model": True}, 45, 12),
    ],
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


def test_a_plant_is_sampled_once_per_substep_count_and_shared():
    """`Plant.sampled(r)` is built once per r and every map of it once; the env steps with the plant's."""
    plant = Plant(Experiment())
    assert plant.sampled(4) is plant.sampled(4) and plant.sampled(1) is not plant.sampled(4)
    assert (
        plant.sampled(4).step is plant.sampled(4).step and plant.sampled(1).step is not plant.sampled(4).step
    )
    assert plant.sampled().ground_model is plant.sampled().ground_model
    env = BuildingEnv(plant)
    env.reset(seed=0, options={"motion": Load("quiet", 0.005, np.zeros(41))})  # four samples per control step
    assert env.plant is plant and env.sampled is plant.sampled(4)


def plant_with(**part) -> Plant:
    return Plant(Experiment(plant=part))


def test_a_plant_part_of_defaults_is_the_design_model_bit_for_bit():
    from rlcontroller.physics.motions.records import synthetic_suite

    motion = synthetic_suite(count=1)[0]
    nominal, same = BuildingEnv(Experiment()), BuildingEnv(plant_with())
    a, _ = nominal.reset(seed=4, options={"motion": motion})
    b, _ = same.reset(seed=4, options={"motion": motion})
    action = np.array([0.3, -0.2, 0.5])
    for _ in range(300):
        a, reward_a, *_ = nominal.step(action)
        b, reward_b, *_ = same.step(action)
        assert np.array_equal(a, b) and reward_a == reward_b
    assert Experiment().plant is None and Plant(Experiment()).design is not None


def test_stiffness_and_mass_factors_scale_the_periods_as_sqrt_m_over_k():
    periods = Plant(Experiment()).building.periods()
    np.testing.assert_allclose(
        plant_with(stiffness=0.7).building.periods(), periods / np.sqrt(0.7), rtol=1e-12
    )
    np.testing.assert_allclose(plant_with(mass=1.15).building.periods(), periods * np.sqrt(1.15), rtol=1e-12)
    per_story = plant_with(stiffness=[0.5, 1, 1, 1, 1], damage=[{"story": 2, "stiffness": -0.4}]).building
    design = Plant(Experiment()).building
    np.testing.assert_allclose(
        np.diag(per_story.stiffness) - np.diag(design.stiffness),
        [-2.5e6 - 1.6e6, -1.6e6, 0, 0, 0],
        rtol=1e-12,
    )


def test_the_damping_factor_scales_the_rayleigh_ratios():
    ratios = plant_with(damping=0.5).building.modal_damping_ratios()
    assert ratios[0] == pytest.approx(0.005, rel=1e-9) and ratios[4] == pytest.approx(0.025, rel=1e-9)


def test_the_design_model_is_the_experiment_without_its_plant_part():
    plant = plant_with(stiffness=0.7, actuators={"delay_steps": 2}, sensors={"dead_floors": [3]})
    design = plant.design
    assert design.experiment.plant is None and design.n_state == 10 and plant.n_state == 10 + 2 * 3 + 3
    np.testing.assert_array_equal(design.building.stiffness, Plant(Experiment()).building.stiffness)
    assert plant.sensors.c[2].any() == False and design.sensors.c[2].any()  # noqa: E712


def delivered_forces(plant: Plant, commands: np.ndarray) -> np.ndarray:
    """The env's delivered force after each command, on a quiet ground."""
    env = BuildingEnv(plant)
    env.reset(seed=0, options={"motion": Load("quiet", 0.02, np.full(commands.shape[0] + 2, 1e-9))})
    forces = []
    for command in commands:
        env.step(command)
        forces.append(env.held_force)
    return np.array(forces)


def test_an_actuator_lag_follows_the_analytic_step_response():
    tau, commands = 0.05, np.tile([0.5, -1.0, 0.2], (30, 1))
    forces = delivered_forces(plant_with(actuators={"time_constant": tau}), commands)
    time = 0.02 * np.arange(1, 31)[:, None]
    expected = commands * Plant(Experiment()).force_limits * (1.0 - np.exp(-time / tau))
    np.testing.assert_allclose(forces, expected, rtol=1e-9, atol=1e-6)


@pytest.mark.parametrize("lag", [0.0, 0.03])
def test_a_delay_shifts_the_delivered_force_and_the_response_exactly(lag):
    from rlcontroller.physics.motions.records import synthetic_suite

    rng = np.random.default_rng(2)
    commands = rng.uniform(-1, 1, (200, 3))
    delayed = plant_with(actuators={"delay_steps": 3, "time_constant": lag})
    prompt = plant_with(actuators={"time_constant": lag})
    shifted = np.vstack([np.zeros((3, 3)), commands[:-3]])
    np.testing.assert_allclose(
        delivered_forces(delayed, commands), delivered_forces(prompt, shifted), atol=1e-6
    )
    motion = synthetic_suite(count=1)[0]
    runs = []
    for plant, sequence in ((delayed, commands), (prompt, shifted)):
        env = BuildingEnv(plant)
        env.reset(seed=0, options={"motion": motion})
        runs.append([env.step(a)[4]["drift"] for a in sequence])
    np.testing.assert_allclose(runs[0], runs[1], rtol=SAME_PHYSICS, atol=1e-12)


def test_sensor_faults_dead_floor_bias_and_noise():
    plant = plant_with(
        sensors={"dead_floors": [3], "bias": [{"floor": 1, "value": 0.5}], "noise_factor": 4.0}
    )
    env = BuildingEnv(plant)
    quiet = Load("quiet", 0.02, np.full(2001, 1e-9))
    observation, _ = env.reset(seed=1, options={"motion": quiet})
    readings = [observation[:5]]
    for _ in range(2000):
        readings.append(env.step(np.zeros(3))[0][:5])
    readings = np.array(readings, dtype=float) * 5.0  # back to m/s^2
    assert np.all(readings[:, 2] == 0.0)
    assert readings[:, 0].mean() == pytest.approx(0.5, abs=0.02)
    assert readings[:, 1].std() == pytest.approx(4.0 * 0.05, rel=0.05)
