"""The steady-state Kalman filters: the gain against an independent Riccati solve, and an estimate
that converges to the true state."""

import numpy as np
import scipy.linalg

from rlcontroller.config import Experiment, MeasurementConfig, SensorConfig
from rlcontroller.control.estimation import design_kalman, design_kalman_ground_model, kalman_gain
from rlcontroller.learning.env import BuildingEnv
from rlcontroller.physics.excitation import GroundMotion
from rlcontroller.physics.plant import Plant


def test_the_gain_solves_the_filter_riccati_equation():
    """L = P C' (C P C' + R)^-1 with P from scipy's DARE (the dual of the control problem)."""
    rng = np.random.default_rng(0)
    phi = scipy.linalg.expm(0.02 * np.array([[0.0, 1.0], [-40.0, -0.4]]))
    c = rng.standard_normal((1, 2))
    process, measurement = np.diag([1e-4, 1e-3]), np.array([[1e-2]])
    prior = scipy.linalg.solve_discrete_are(phi.T, c.T, process, measurement)
    expected = prior @ c.T @ np.linalg.inv(c @ prior @ c.T + measurement)
    np.testing.assert_allclose(kalman_gain(phi, c, process, measurement), expected, rtol=1e-8)


def test_the_estimate_converges_to_the_true_state_from_noise_free_readings():
    """Free vibration after a ground pulse, readings without noise: the estimation error falls
    by orders of magnitude (the filter is stable and unbiased)."""
    experiment = Experiment(
        sensors=SensorConfig(
            measurements=[MeasurementConfig(quantity="absolute_acceleration", scale=5.0)], ground_noise_std=0.0
        )
    )
    plant = Plant(experiment)
    kalman = design_kalman(plant, known_ground=True)
    pulse = np.zeros(1501)
    pulse[10:20] = 2.0
    env = BuildingEnv(plant)
    observation, _ = env.reset(seed=0, options={"motion": GroundMotion("pulse", 0.02, pulse)})
    layout, errors, previous = plant.layout, [], 0.0
    estimate = np.zeros(kalman.size)
    for _ in range(1500):
        observation, *_ = env.step(np.zeros(3))
        ground = float(observation[layout.ground]) * layout.ground_scale
        readings = observation[layout.readings] * layout.reading_scale
        estimate = kalman.update(estimate, readings, observation[layout.action], ground, previous)
        previous = ground
        errors.append(np.linalg.norm(estimate - env.state) / max(np.linalg.norm(env.state), 1e-12))
    assert np.mean(errors[:20]) > 100 * np.mean(errors[-100:])
    assert np.mean(errors[-100:]) < 1e-3


def test_the_ground_model_filter_estimates_the_ground_it_measures():
    plant = Plant(Experiment())
    kalman = design_kalman_ground_model(plant)
    assert kalman.phi.shape == (12, 12) and kalman.measures_ground
    np.testing.assert_array_equal(kalman.sensor_c[-1, -2:], plant.ground_model.output)
    assert np.all(np.abs(np.linalg.eigvals(kalman.phi - kalman.gain @ kalman.sensor_c @ kalman.phi)) < 1.0)


def test_a_batch_of_estimates_updates_as_each_one_alone():
    plant = Plant(Experiment())
    kalman = design_kalman(plant, known_ground=True)
    rng = np.random.default_rng(1)
    estimates, readings = rng.standard_normal((4, 10)), rng.standard_normal((4, 5))
    actions, ground, previous = rng.uniform(-1, 1, (4, 3)), rng.standard_normal(4), rng.standard_normal(4)
    batch = kalman.update(estimates, readings, actions, ground, previous)
    for i in range(4):
        alone = kalman.update(estimates[i], readings[i], actions[i], ground[i], previous[i])
        np.testing.assert_allclose(batch[i], alone, rtol=1e-12, atol=1e-15)
