"""The steady-state Kalman filters: the gain against an independent Riccati solve, and an estimate
that converges to the true state. The model-free integration of the readings: its transfer
functions, and velocity and displacement recovered from an acceleration."""

import numpy as np
import pytest
import scipy.linalg
from conftest import REPOSITORY

from rlcontroller.config import Experiment, MeasurementConfig, PlantConfig, SensorConfig, load_experiment
from rlcontroller.config.plant import DeviceFactors
from rlcontroller.control.estimation import (
    design_kalman,
    design_kalman_ground_model,
    integration_filter,
    kalman_gain,
)
from rlcontroller.learning.env import BuildingEnv
from rlcontroller.physics.motions.excitation import Load
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
            measurements=[MeasurementConfig(quantity="absolute_acceleration", scale=5.0)],
            ground_noise_std=0.0,
        )
    )
    plant = Plant(experiment)
    kalman = design_kalman(plant, known_ground=True)
    pulse = np.zeros(1501)
    pulse[10:20] = 2.0
    env = BuildingEnv(plant)
    observation, _ = env.reset(seed=0, options={"motion": Load("pulse", 0.02, pulse)})
    layout, errors, previous = plant.layout, [], 0.0
    estimate = np.zeros(kalman.size)
    for _ in range(1500):
        observation, *_ = env.step(np.zeros(3))
        ground = float(observation[layout.ground]) * layout.ground_scale
        readings = observation[layout.readings] * layout.reading_scale
        estimate = kalman.update(
            estimate,
            readings,
            held_action=observation[layout.action],
            ground=ground,
            previous_ground=previous,
        )
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
    batch = kalman.update(estimates, readings, held_action=actions, ground=ground, previous_ground=previous)
    for i in range(4):
        alone = kalman.update(
            estimates[i], readings[i], held_action=actions[i], ground=ground[i], previous_ground=previous[i]
        )
        np.testing.assert_allclose(batch[i], alone, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("design", ["known ground", "ground model"])
def test_the_update_on_raw_observations_is_the_update_on_si_readings(design):
    plant = Plant(Experiment())
    kalman = (
        design_kalman(plant, known_ground=True)
        if design == "known ground"
        else design_kalman_ground_model(plant)
    )
    layout = plant.layout
    free, observed, previous_ground_gain = kalman.on_observations(layout)
    rng = np.random.default_rng(2)
    observations = rng.standard_normal((4, layout.size)).astype(np.float32)
    estimates, previous = rng.standard_normal((4, kalman.size)), rng.standard_normal(4)
    ground = observations[:, layout.ground].astype(float) * layout.ground_scale
    expected = kalman.update(
        estimates,
        observations[:, layout.readings] * layout.reading_scale,
        held_action=observations[:, layout.action].astype(float),
        ground=ground,
        previous_ground=previous * layout.ground_scale,
    )
    folded = estimates @ free + observations @ observed
    if previous_ground_gain is not None:
        folded += previous[:, None] * previous_ground_gain
    assert (previous_ground_gain is not None) == kalman.known_ground
    np.testing.assert_allclose(folded, expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())


def run_filter(filter_, accelerations: np.ndarray) -> np.ndarray:
    """The filter's states after each sample of one channel (through the ground input)."""
    state, states, none = np.zeros(filter_.size), [], np.zeros(filter_.action_gain.shape[1])
    for value in accelerations:
        state = filter_.update(state, np.zeros(0), held_action=none, ground=value, previous_ground=0.0)
        states.append(state)
    return np.array(states)


def test_the_integration_filter_is_the_backward_euler_image_of_its_transfer_functions():
    """At z = exp(i w dt): H(s), D(s) = s / (s + c)^3, V(s) = s^2 / (s + c)^3 at s = (1 - 1/z) / dt,
    for each of two channels, and no crosstalk."""
    dt, cutoff = 0.02, 0.1
    filter_ = integration_filter(cutoff, dt, channels=2, n_actuators=3)
    c = 2 * np.pi * cutoff
    for frequency in [0.03, 0.7, 3.0, 20.0]:
        z = np.exp(1j * 2 * np.pi * frequency * dt)
        response = np.linalg.solve(np.eye(6) - filter_.phi / z, filter_.gain)  # states per reading
        s = (1 - 1 / z) / dt
        expected = [1 / (s + c), s / (s + c) ** 3, s**2 / (s + c) ** 3]
        for channel in range(2):
            np.testing.assert_allclose(response[channel::2, channel], expected, rtol=1e-10)
            np.testing.assert_allclose(response[1 - channel :: 2, channel], 0.0, atol=1e-15)


@pytest.mark.slow
def test_integrated_accelerations_give_velocity_and_displacement_and_forget_a_bias():
    """a = -W^2 A sin(W t) + bias, well above the cutoff: after the transient, d = A sin(W t) and
    v = A W cos(W t) to 5 % (the three poles at 0.02 Hz lead by 3 atan(0.01), 3 % of the amplitude), whatever
    the constant bias of the sensor."""
    dt, cutoff, amplitude, w = 0.001, 0.02, 0.01, 2 * np.pi * 2.0
    time = np.arange(1, 200_001) * dt
    acceleration = -(w**2) * amplitude * np.sin(w * time) + 0.3
    states = run_filter(integration_filter(cutoff, dt, channels=1, n_actuators=1), acceleration)
    late = time > 150.0
    np.testing.assert_allclose(states[late, 1], amplitude * np.sin(w * time[late]), atol=0.05 * amplitude)
    np.testing.assert_allclose(
        states[late, 2], amplitude * w * np.cos(w * time[late]), atol=0.05 * amplitude * w
    )


@pytest.mark.slow
def test_loop_transfer_recovery_keeps_lqg_stable_with_a_detuned_damper():
    """The 76-story active tuned mass damper's LQG + wind model goes unstable when the damper's frequency is
    10 % off its design; with sensors.input_noise (fictitious noise at the driver's input) it does not."""
    from rlcontroller.control.classical import classical_policy
    from rlcontroller.simulation.linearised import spectral_radius

    config = REPOSITORY / "studies" / "safety_check" / "seventy_six_story_atmd_stroke_weighted.yaml"
    robust = load_experiment(config)
    assert robust.sensors.input_noise == 0.1
    plain = robust.model_copy(update={"sensors": robust.sensors.model_copy(update={"input_noise": 0.0})})
    detuned = PlantConfig(devices=DeviceFactors(frequency=0.9))
    radii = {}
    for name, experiment in (("plain", plain), ("robust", robust)):
        controller = classical_policy(Plant(experiment), "lqg_wind_model")
        radii[name] = spectral_radius(Plant(experiment.model_copy(update={"plant": detuned})), controller)
        assert spectral_radius(Plant(experiment), controller) < 1.0  # both stable on the design model
    assert radii["plain"] > 1.0 > radii["robust"]
