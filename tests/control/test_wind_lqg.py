"""LQG + wind model: its process noise is the continuous model's, its filter tracks the floor forces,
it is the prior a zero residual reproduces, and under wind it beats an LQG that models the ground."""

import numpy as np
import pytest
import scipy.linalg

from rlcontroller.assets import CONFIGS
from rlcontroller.config import Experiment, load_experiment
from rlcontroller.control.controllers import LQGController, LQGPrior
from rlcontroller.control.lqg import design_lqg, design_lqg_wind_model
from rlcontroller.control.policy_controller import PolicyController
from rlcontroller.evaluation.evaluation import evaluate, mean_metric
from rlcontroller.learning.env import BuildingEnv, rollout
from rlcontroller.physics.dynamics import discrete_noise, simulate
from rlcontroller.physics.motions.excitation import on_control_grid
from rlcontroller.physics.motions.loads import generate_suite
from rlcontroller.physics.plant import Plant


@pytest.fixture(scope="module")
def wind_experiment() -> Experiment:
    return load_experiment(CONFIGS / "experiments" / "five_story_wind.yaml")


def test_the_discrete_process_noise_is_van_loans_integral():
    """P - phi P phi' against Van Loan's block exponential on a system that is not stiff."""
    rng = np.random.default_rng(0)
    a = rng.normal(size=(4, 4)) - 3.0 * np.eye(4)
    root = rng.normal(size=(4, 4))
    intensity, dt = root @ root.T, 0.1
    block = np.block([[-a, intensity], [np.zeros((4, 4)), a.T]])
    exponential = scipy.linalg.expm(block * dt)
    van_loan = exponential[4:, 4:].T @ exponential[:4, 4:]
    np.testing.assert_allclose(
        discrete_noise(a, intensity, scipy.linalg.expm(a * dt)), van_loan, rtol=1e-9, atol=1e-12
    )


def velocity_error(plant: Plant, design, motion) -> float:
    """Relative RMS error of the filter's floor velocities, noise-free accelerometers, no control."""
    forces = on_control_grid(motion, plant.control_dt).floor_forces
    response = simulate(
        plant.building, plant.sampled(1).structure, np.zeros(forces.shape[0]), floor_forces=forces
    )
    n = plant.building.n_dofs
    states = np.hstack([response.displacement, response.velocity])
    readings = states @ plant.sensors.c.T + forces @ plant.sensors.load.T
    estimate, velocities = np.zeros(design.filter.size), []
    for reading in readings:
        estimate = design.filter.update(
            estimate,
            reading,
            held_action=np.zeros(plant.building.n_actuators),
            ground=0.0,
            previous_ground=0.0,
        )
        velocities.append(estimate[n : 2 * n])
    error = np.array(velocities)[200:] - states[200:, n:]
    return float(np.linalg.norm(error) / np.linalg.norm(states[200:, n:]))


def test_the_wind_filter_tracks_the_building_under_wind(wind_experiment):
    """Floor forces in the model, the filter knows why the floors accelerate: its velocity estimate is
    a few percent off, where the filter that takes the disturbance for ground shaking is far off."""
    plant = Plant(wind_experiment)
    motion = generate_suite(wind_experiment.excitation.generator, 1, 3, plant.building)[0]
    wind = velocity_error(plant, design_lqg_wind_model(plant), motion)
    assert wind < 0.1
    assert wind < 0.3 * velocity_error(plant, design_lqg(plant), motion)


def earthquake_velocity_error(plant: Plant, design, motion, ground_noise: float) -> float:
    """Relative RMS error of the filter's floor velocities under a ground motion, noise-free floor
    accelerometers, a ground reading with `ground_noise` (m/s^2), no control."""
    grid = on_control_grid(motion, plant.control_dt)
    response = simulate(plant.building, plant.sampled(1).structure, grid.ground)
    n = plant.building.n_dofs
    states = np.hstack([response.displacement, response.velocity])
    readings = states @ plant.sensors.c.T
    ground = grid.ground + np.random.default_rng(1).normal(0.0, ground_noise, grid.ground.shape)
    estimate, velocities, zero = np.zeros(design.filter.size), [], np.zeros(plant.building.n_actuators)
    for k, reading in enumerate(readings):
        estimate = design.filter.update(
            estimate, reading, held_action=zero, ground=ground[k], previous_ground=ground[max(k - 1, 0)]
        )
        velocities.append(estimate[n : 2 * n])
    error = np.array(velocities)[100:] - states[100:, n:]
    return float(np.linalg.norm(error) / np.linalg.norm(states[100:, n:]))


def test_with_the_ground_model_the_wind_filter_also_tracks_the_building_in_an_earthquake(wind_experiment):
    """A building designed against wind also shakes: with `sensors.ground_model` the wind filter also models
    the measured ground (its estimate: floors, velocities, forces, then the ground filter's two states), and
    under generated earthquakes its velocity estimate is a few percent off, where the wind filter alone takes
    the shaking for wind forces; under wind it tracks as the wind filter does."""
    sensors = wind_experiment.sensors.model_copy(update={"ground_model": False})
    both, wind_only = Plant(wind_experiment), Plant(wind_experiment.model_copy(update={"sensors": sensors}))
    assert wind_experiment.sensors.ground_model
    assert both.layout.estimate.stop - both.layout.estimate.start == 2 * 5 + 5 + 2
    # N, then the ground's
    assert both.layout.estimate_scale[10] > 1e2 > both.layout.estimate_scale[-2:].max()
    generator = load_experiment(CONFIGS / "experiments" / "five_story_every_story.yaml").excitation.generator
    for motion in generate_suite(generator, 3, 5, both.building):
        error = earthquake_velocity_error(both, design_lqg_wind_model(both), motion, ground_noise=0.05)
        assert error < 0.1
        assert error < 0.3 * earthquake_velocity_error(
            wind_only, design_lqg_wind_model(wind_only), motion, 0.05
        )
    motion = generate_suite(wind_experiment.excitation.generator, 1, 3, both.building)[0]
    assert velocity_error(both, design_lqg_wind_model(both), motion) < 0.1


def test_a_zero_residual_on_the_wind_prior_is_lqg_with_the_wind_model(wind_experiment):
    plant = Plant(wind_experiment)
    assert plant.layout.estimate.stop - plant.layout.estimate.start == 2 * 5 + 5 + 2  # x, v, forces, ground
    motion = generate_suite(wind_experiment.excitation.generator, 1, 4, plant.building)[0]
    env = BuildingEnv(wind_experiment)

    class ZeroActor:
        def __call__(self, observation):
            return np.zeros(np.shape(observation)[:-1] + (5,))

    residual, _ = rollout(env, motion, PolicyController(ZeroActor(), prior=LQGPrior.design(plant)))
    lqg, _ = rollout(env, motion, LQGController(design_lqg_wind_model(plant), env.plant))
    np.testing.assert_allclose(residual.force, lqg.force, rtol=1e-3, atol=1.0)
    assert np.abs(lqg.force).max() > 1e3


@pytest.mark.slow
def test_under_wind_the_wind_model_beats_the_ground_model_in_comfort(wind_experiment):
    """The same cost, the same sensors: modelling the disturbance as floor forces (not ground
    shaking) gives lower RMS floor accelerations on generated wind."""
    plant = Plant(wind_experiment)
    motions = generate_suite(wind_experiment.excitation.generator, 3, 7, plant.building)
    controllers = [
        LQGController(design_lqg(plant), plant, "LQG"),
        LQGController(design_lqg_wind_model(plant), plant, "LQG + wind model"),
    ]
    evaluation = evaluate(plant, motions, controllers, "wind", include_optimal=False)
    wind = mean_metric(evaluation, "LQG + wind model", "rms_acceleration")
    assert wind < 0.95 * mean_metric(evaluation, "LQG", "rms_acceleration")
    assert wind < 0.8


def test_without_a_wind_generator_there_is_no_wind_model():
    with pytest.raises(ValueError, match="kind wind"):
        design_lqg_wind_model(Plant(Experiment()))


@pytest.mark.slow
def test_compare_lqg_runs_on_the_76_story_benchmark(tmp_path):
    """The command that ended in a Riccati traceback (scipy's Schur reordering on modes that die within one
    0.1 s step): LQG and LQG + wind model design and run; under a short generated wind the passive damper's
    RMS acceleration beats the bare building's, and the drivers the laws command meet their 1 m end-stops,
    counted (a free mass let both laws beat the passive damper; on its stops the 500 t mass slams:
    docs/wind.md)."""
    import pandas as pd
    from typer.testing import CliRunner

    from rlcontroller.cli import app

    wind = tmp_path / "wind.yaml"
    wind.write_text(
        (CONFIGS / "loads" / "wind_76.yaml").read_text().replace("duration: 600.0", "duration: 120.0")
    )
    wind.write_text(wind.read_text().replace("records_per_speed: 3", "records_per_speed: 1"))
    config = str(CONFIGS / "experiments" / "seventy_six_story_atmd.yaml")
    out = tmp_path / "out"
    result = CliRunner().invoke(
        app, ["compare", "lqg", "--config", config, "--records", str(wind), "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    table = pd.read_csv(out / "summary.csv", index_col=0)
    summary = table["rms_acceleration"]
    assert summary["passive devices"] < summary["uncontrolled"] == 1.0
    assert table.loc["LQG + wind model", "contacts"] > 0 and table.loc["LQG", "contacts"] > 0
    assert table.loc["LQG + wind model", "stroke_over_limit"] < 1.2  # on its stops, not through them
