"""Loads on the floors (wind): a constant force settles at the static displacement K^-1 F, random
forces match an independent integration, and a building with a TMD takes them on its floors only."""

import numpy as np
import pytest
import scipy.integrate

from rlcontroller.config import Experiment
from rlcontroller.physics.dynamics import load_map, simulate
from rlcontroller.physics.plant import Plant


def test_a_constant_floor_load_settles_at_the_static_displacement():
    plant = Plant(Experiment())
    building = plant.building
    steps = 12_000  # 240 s: the first mode's 1 % damping decays by e^-10
    force = np.array([1e4, 2e4, -1e4, 3e4, 5e3])
    forces = np.tile(force, (steps + 1, 1))
    result = simulate(building, plant.sampled(1).step, np.zeros(steps + 1), floor_forces=forces)
    static = np.linalg.solve(building.stiffness, force)
    np.testing.assert_allclose(result.displacement[-1], static, rtol=1e-4)
    np.testing.assert_allclose(result.absolute_acceleration[-1], 0.0, atol=1e-4 * np.abs(force).max() / 1e4)
    shears = np.cumsum(force[::-1])[::-1]  # the story shears that carry the loads above each story
    np.testing.assert_allclose(result.story_shear[-1], -shears, rtol=1e-4)


@pytest.mark.slow
def test_random_floor_loads_match_solve_ivp_with_two_samples_per_step():
    plant = Plant(Experiment())
    building = plant.building
    rng = np.random.default_rng(4)
    dt, steps = 0.01, 300  # two load samples per 0.02 s control step
    forces = rng.normal(0.0, 2e4, size=(2 * steps + 1, 5))
    result = simulate(building, plant.sampled(2).step, np.zeros(2 * steps + 1), floor_forces=forces)
    time = np.arange(2 * steps + 1) * dt

    def rates(t, s):
        f = np.array([np.interp(t, time, column) for column in forces.T])
        x, v = s[:5], s[5:]
        return np.concatenate(
            [v, np.linalg.solve(building.mass, f - building.stiffness @ x - building.damping @ v)]
        )

    solution = scipy.integrate.solve_ivp(
        rates, (0.0, time[-1]), np.zeros(10), t_eval=time[::2], rtol=1e-10, atol=1e-13, max_step=dt / 4
    )
    np.testing.assert_allclose(result.drift, np.diff(solution.y[:5].T, axis=1, prepend=0.0), atol=1e-6 * 1e-2)
    expected = np.linalg.solve(
        building.mass, forces[::2].T - building.stiffness @ solution.y[:5] - building.damping @ solution.y[5:]
    ).T
    np.testing.assert_allclose(result.absolute_acceleration, expected, atol=1e-6 * np.abs(expected).max())


def test_with_a_tuned_mass_the_loads_stay_on_the_floors():
    raw = Experiment().model_dump()
    raw["devices"] = [{"type": "tuned_mass", "floor": 5, "mass_ratio": 0.02}]
    plant = Plant(Experiment.model_validate(raw))
    gain = load_map(plant.building, 0.02, 1).gain
    assert gain.shape == (12, 2, 5)
    force = np.zeros((2, 5))
    force[:, 4] = 1e4  # a roof load reaches the TMD only through its spring: after one step, barely
    moved = np.einsum("ijf,jf->i", gain, force)
    assert abs(moved[5]) < 1e-2 * abs(moved[4])  # loaded directly it would move 15 times more than the roof


def wind_record(plant: Plant, seconds: float = 120.0, seed: int = 0):
    from rlcontroller.physics.motions.excitation import Load
    from rlcontroller.physics.motions.wind import WindField, fluctuating_forces, mean_force

    heights = 3.0 * np.arange(1, 6)
    field = WindField(heights=heights, speed=30.0, reference_height=10.0, roughness=0.3, width=20.0)
    dt = 0.01
    forces = mean_force(field) + fluctuating_forces(field, seconds, dt, np.random.default_rng(seed))
    return Load(f"wind_{seed}", dt, np.zeros(forces.shape[0]), synthetic=True, floor_forces=forces)


@pytest.mark.slow
def test_a_batch_under_wind_gives_each_records_env_rollout():
    """The batch and the Gymnasium env load the floors alike, with LQG reading the accelerometers."""
    from rlcontroller.control.controllers import LQGController, Uncontrolled
    from rlcontroller.control.lqg import design_lqg
    from rlcontroller.learning.env import BuildingEnv, rollout
    from rlcontroller.simulation.rollout import batch_rollout

    plant = Plant(Experiment())
    motions = [wind_record(plant, 60.0, seed) for seed in (1, 2)]
    controllers = [Uncontrolled(3), LQGController(design_lqg(plant), plant)]
    batched = batch_rollout(plant, motions, controllers, seeds=[3, 4])
    env = BuildingEnv(plant)
    for controller, runs in zip(controllers, batched, strict=True):
        for motion, seed, (result, reward) in zip(motions, [3, 4], runs, strict=True):
            alone, alone_reward = rollout(env, motion, controller, seed=seed)
            assert reward == alone_reward or abs(reward - alone_reward) <= 1e-9 * abs(alone_reward)
            for quantity in ("drift", "absolute_acceleration"):
                expected = alone.quantity(quantity)
                np.testing.assert_allclose(
                    result.quantity(quantity), expected, atol=1e-9 * np.abs(expected).max()
                )
    samples = motions[0]
    open_loop = simulate(
        plant.building, plant.sampled(2).step, samples.acceleration, floor_forces=samples.floor_forces
    )
    np.testing.assert_allclose(
        batched[0][0][0].drift, open_loop.drift, atol=1e-9 * np.abs(open_loop.drift).max()
    )
    np.testing.assert_allclose(
        batched[0][0][0].absolute_acceleration, open_loop.absolute_acceleration, atol=1e-9 * 10.0
    )


def test_the_floor_loads_need_a_linear_plant():
    import pytest

    raw = Experiment().model_dump()
    raw["plant"] = {"hysteresis": {"yield_drift": 0.01}}
    with pytest.raises(ValueError, match=r"floor loads \(wind\) on a building with yielding stories"):
        _ = Plant(Experiment.model_validate(raw)).sampled(1).load


def test_a_measured_floor_force_record_loads_the_floors_in_si(tmp_path):
    from rlcontroller.physics.motions.excitation import read_motion

    rows = ["time_s,floor 1 [kN],floor 2 [kN],floor 3 [kN],floor 4 [kN],floor 5 [kN]"]
    rows += [f"{0.01 * k:.2f},{k % 7},{-(k % 5)},0,1.5,{k % 3}" for k in range(50)]
    (tmp_path / "gust.csv").write_text("\n".join(rows) + "\n")
    record = read_motion(tmp_path / "gust.csv")
    assert (
        abs(record.dt - 0.01) < 1e-12
        and record.floor_forces.shape == (50, 5)
        and not record.acceleration.any()
    )
    np.testing.assert_array_equal(record.floor_forces[8], [1e3, -3e3, 0.0, 1.5e3, 2e3])  # kN to N
