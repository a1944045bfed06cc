"""The fishbone frame: its column line against beam theory, its elastic response against the linear building,
and its massless rotations against an independent solver that gives them a small inertia."""

from dataclasses import replace

import numpy as np
import pytest
import scipy.integrate

from rlcontroller.physics.fishbone import ColumnLine, Fishbone
from rlcontroller.physics.integrators.yielding import z_rate

H, EI = 3.5, 2.0e8  # m, N m^2


def line(masses=(1e5, 1e5), beams=3.0e8, base=1e22) -> ColumnLine:
    n = len(masses)
    return ColumnLine(np.asarray(masses, float), np.full(n, H), np.full(n, EI), np.full(n, beams), base)


def test_one_story_column_is_a_cantilever_without_beams_and_guided_with_rigid_ones():
    weightless = (1e-9,)  # no P-Delta
    assert line(weightless, beams=0.0).lateral()[0, 0] == pytest.approx(3 * EI / H**3, rel=1e-9)
    assert line(weightless, beams=1e18).lateral()[0, 0] == pytest.approx(12 * EI / H**3, rel=1e-6)
    heavy = line((2e5,), beams=0.0).lateral()[0, 0]  # the leaning column's P-Delta: -W / h
    assert heavy == pytest.approx(3 * EI / H**3 - 2e5 * 9.80665 / H, rel=1e-9)


def test_two_story_cantilever_flexibility_is_beam_theory():
    flexibility = np.linalg.inv(line((1e-9, 1e-9), beams=0.0).lateral())
    # deflection at a under a unit load at b >= a: a^2 (3 b - a) / (6 EI)
    expected = np.array([[1 / 3, 5 / 6], [5 / 6, 8 / 3]]) * H**3 / EI
    np.testing.assert_allclose(flexibility, expected, rtol=1e-9)


def ground_motion(duration=4.0, dt=0.01, amplitude=4.0, frequency=2.5):
    t = np.arange(0.0, duration + dt / 2, dt)
    return t, amplitude * np.sin(2 * np.pi * frequency * t) * np.minimum(t, 1.0)


def frame(yield_rotation, ratio=0.05, exponent=2.0) -> tuple[ColumnLine, Fishbone]:
    column_line = line()
    damping = 0.01 * 2 * np.sqrt(1e5 * 5e7) / 1e5 * np.diag(column_line.masses)  # about 1 % in the first mode
    n = column_line.n
    fishbone = Fishbone.of(
        column_line,
        damping,
        yield_rotation=np.full(n, yield_rotation),
        post_yield_ratio=np.full(n, ratio),
        exponent=np.full(n, exponent),
        beta=np.full(n, 0.5),
    )
    return column_line, fishbone


def test_beams_that_never_yield_give_the_linear_building():
    column_line, fishbone = frame(yield_rotation=1e3)  # |z| stays below 1e-5: the hinges are elastic
    t, ground = ground_motion()
    states = fishbone.history(ground, 1, 0.01)
    m, k, c = np.diag(column_line.masses), column_line.lateral(), fishbone.damping

    def rate(time, s):
        return np.concatenate(
            [s[2:], np.linalg.solve(m, -c @ s[2:] - k @ s[:2]) - np.interp(time, t, ground)]
        )

    exact = scipy.integrate.solve_ivp(rate, (0, t[-1]), np.zeros(4), t_eval=t, rtol=1e-10, atol=1e-12).y.T
    np.testing.assert_allclose(states[:, :2], exact[:, :2], atol=1e-6 * np.abs(exact[:, :2]).max())


def test_massless_rotations_agree_with_rotations_given_a_small_inertia():
    """The integrator solves theta' = -(I + G Phi)^-1 A v at each stage; an independent model gives the
    rotations an inertia J (their frequencies 50 times the first mode's) and integrates them as states with
    scipy."""
    column_line, fishbone = frame(yield_rotation=0.002, ratio=0.05, exponent=2.0)
    n, ratio, yield_rotation, beta = 2, 0.05, 0.002, 0.5
    t, ground = ground_motion()
    states = replace(fishbone, substeps=8).history(ground, 1, 0.01)
    xx, xt, tt = column_line.matrices(ratio)
    hinge = np.concatenate([[0.0], (1 - ratio) * column_line.beams * yield_rotation])
    first = np.sqrt(
        np.linalg.eigvals(np.linalg.solve(np.diag(column_line.masses), column_line.lateral())).real.min()
    )
    inertia = (
        np.diag(tt + np.diag(np.concatenate([[0.0], (1 - ratio) * column_line.beams]))) / (50 * first) ** 2
    )
    masses, damping = column_line.masses, fishbone.damping

    def rate(time, s):
        x, theta, v = s[:n], s[n : 2 * n + 1], s[2 * n + 1 : 3 * n + 1]
        omega, z = s[3 * n + 1 : 4 * n + 2], s[4 * n + 2 :]
        moments = xt.T @ x + tt @ theta + hinge * np.concatenate([[0.0], z])
        acceleration = (-damping @ v - xx @ x - xt @ theta) / masses - np.interp(time, t, ground)
        z_dot = [z_rate(z[j], omega[j + 1], yield_rotation, 2.0, beta, 1 - beta) for j in range(n)]
        return np.concatenate([v, omega, acceleration, -moments / inertia, z_dot])

    independent = scipy.integrate.solve_ivp(
        rate, (0, t[-1]), np.zeros(5 * n + 2), t_eval=t, method="Radau", rtol=1e-8, atol=1e-11
    ).y.T
    drift, expected = np.diff(states[:, :n], prepend=0.0), np.diff(independent[:, :n], prepend=0.0)
    assert np.abs(independent[:, 4 * n + 2 :]).max() > 0.9  # the hinges yielded
    np.testing.assert_allclose(drift, expected, atol=0.01 * np.abs(expected).max())
    np.testing.assert_allclose(states[:, 2 * n :], independent[:, 4 * n + 2 :], atol=0.02)


def fishbone_plant(yield_rotation=0.004, ratio=0.05, collapse_drift=None, column=4e7, beams=6e7):
    """The default experiment's five-story building simulated as a fishbone frame (3 m stories)."""
    from rlcontroller.config import Experiment, HysteresisConfig, PlantConfig
    from rlcontroller.physics.plant import Plant

    experiment = Experiment()
    building = experiment.building.model_copy(update={"story_heights": [3.0] * 5})
    hysteresis = HysteresisConfig(
        model="fishbone",
        yield_drift=0.01,
        yield_rotation=yield_rotation,
        column_stiffness=[column] * 5,
        beam_stiffness=[beams] * 5,
        base_stiffness=1e12,
        post_yield_ratio=ratio,
        collapse_drift=collapse_drift,
    )
    update = {"building": building, "plant": PlantConfig(hysteresis=hysteresis)}
    return Plant(experiment.model_copy(update=update))


def test_the_fishbone_is_refused_without_its_values_and_its_values_without_it():
    from rlcontroller.config import HysteresisConfig

    with pytest.raises(ValueError, match="model fishbone needs yield_rotation, column_stiffness"):
        HysteresisConfig(model="fishbone", yield_drift=0.01)
    with pytest.raises(ValueError, match="base_stiffness: only for model fishbone"):
        HysteresisConfig(yield_drift=0.01, base_stiffness=1e9)


def test_a_frame_that_cannot_stand_or_a_collapse_past_the_story_is_refused_at_load():
    """Column EI of 1 N m^2 (and weak beams): the floors' weight (P-Delta) beats the column line; a collapse
    drift of 5 m on 3 m stories: a story cannot lean that far. Each one line, before any run."""
    from rlcontroller.config import ConfigError

    with pytest.raises(ConfigError, match="hysteresis: the frame cannot stand under its own weight"):
        fishbone_plant(column=1.0, beams=1.0)
    with pytest.raises(
        ConfigError, match=r"hysteresis: collapse_drift: 5 m in story 1, beyond its height 3 m"
    ):
        fishbone_plant(collapse_drift=5.0)
    assert fishbone_plant(collapse_drift=0.5).yielding is not None  # a frame that stands: as before


@pytest.mark.parametrize("collapse_drift", [None, 0.018])
def test_the_plant_steps_the_fishbone_as_its_history_runs_it(collapse_drift):
    """Step by step or in one call, the same states; with a collapse drift the frame is still where it lay
    once a story passes it (the motion's peak drift is 0.025 m), in both."""
    plant = fishbone_plant(yield_rotation=0.004, collapse_drift=collapse_drift)
    t, ground = ground_motion(dt=0.02, amplitude=3.0)
    state, states = np.zeros(15), [np.zeros(15)]
    for k in range(t.size - 1):
        state = plant.integrator.step(state, np.zeros(plant.force_limits.size), ground[k : k + 2], 0.02)
        states.append(state)
    history = plant.yielding.history(ground, 1, 0.02)
    np.testing.assert_allclose(np.array(states), history, rtol=1e-12, atol=1e-15)
    drift = np.abs(np.diff(history[:, :5], axis=1, prepend=0.0)).max(axis=1)
    if collapse_drift is None:
        assert np.abs(history[:, 10:]).max() > 0.9 and 0.02 < drift.max() < 0.03  # the hinges yielded
    else:
        fallen = np.argmax(drift >= collapse_drift)
        assert 0 < fallen < t.size - 20 and np.all(history[fallen:] == history[fallen])
        assert np.all(history[fallen, 5:10] == 0.0)


def test_a_held_actuator_force_settles_to_the_column_lines_static_deflection():
    plant = fishbone_plant(ratio=1.0)  # elastic: the hinges keep all of their stiffness
    action = np.zeros(plant.force_limits.size)
    action[0] = 0.5  # half the first actuator's force
    state = np.zeros(15)
    for _ in range(15000):  # 300 s: the free vibration has died out
        state = plant.integrator.step(state, action, np.zeros(2), 0.02)
    building = plant.building
    line = ColumnLine(np.diag(building.mass), np.full(5, 3.0), np.full(5, 4e7), np.full(5, 6e7), 1e12)
    static = np.linalg.solve(line.lateral(), building.actuator_matrix @ (action * plant.force_limits))
    np.testing.assert_allclose(state[:5], static, rtol=1e-4)


def test_the_absolute_acceleration_output_is_the_floors_acceleration():
    plant = fishbone_plant(yield_rotation=0.004)
    c, _ = plant.outputs("absolute_acceleration")
    dt, steps = 0.001, 3000
    t = np.arange(steps + 1) * dt
    ground = 3.0 * np.sin(2 * np.pi * 2.0 * t)
    states = [np.zeros(15)]
    for k in range(steps):
        states.append(
            plant.integrator.step(states[-1], np.zeros(plant.force_limits.size), ground[k : k + 2], dt)
        )
    states = np.array(states)
    # central differences of the floors' velocities
    relative = (states[2:, 5:10] - states[:-2, 5:10]) / (2 * dt)
    absolute = relative + ground[1:-1, None]
    assert np.abs(states[:, 10:]).max() > 0.5  # yielding on the way
    np.testing.assert_allclose(states[1:-1] @ c.T, absolute, atol=2e-3 * np.abs(absolute).max())


def test_the_kernels_take_their_arrays_in_the_order_the_named_tuples_give_them():
    """The numba kernels take their arrays positionally: each model hands them over as a named tuple whose
    fields are the kernels' own parameter names, in order (a reordered field would swap two arrays
    silently)."""
    import inspect

    from rlcontroller.physics.fishbone import FishboneArrays
    from rlcontroller.physics.hysteresis import BoucWenArrays
    from rlcontroller.physics.integrators import yielding as integrators

    for kernel, arrays in (
        (integrators.fishbone_step, FishboneArrays),
        (integrators.fishbone_history, FishboneArrays),
        (integrators.bouc_wen_step, BoucWenArrays),
        (integrators.bouc_wen_history, BoucWenArrays),
    ):
        names = list(inspect.signature(kernel.py_func).parameters)
        assert names[-len(arrays._fields) :] == list(arrays._fields), kernel.__name__
