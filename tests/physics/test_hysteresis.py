"""Yielding stories (Bouc-Wen): against the linear exact map, the textbook loop, an independent
stiff solver, and the integrator's order."""

import numpy as np
import pytest
import scipy.integrate

from rlcontroller.config import Experiment, HysteresisConfig
from rlcontroller.physics.hysteresis import BoucWen
from rlcontroller.physics.integrators.yielding import z_rate
from rlcontroller.physics.motions.records import synthetic_suite
from rlcontroller.physics.plant import Plant
from rlcontroller.physics.structure import build

EXPERIMENT = Experiment()
STIFFNESS = np.asarray(EXPERIMENT.building.stiffnesses)
BUILDING = build(EXPERIMENT.building, EXPERIMENT.actuators)
MOTION = synthetic_suite(count=1)[0]  # 0.02 s samples, PGA 2-6 m/s^2


def run(model: BoucWen, steps: int, force: np.ndarray | None = None) -> np.ndarray:
    """Drift history of the yielding building under MOTION (actuator forces (N) held, 0.02 s control
    steps)."""
    action = np.zeros(3) if force is None else force / BUILDING.force_limits
    state, drifts = np.zeros(15), []
    for k in range(steps):
        state = model.step(state, action, MOTION.acceleration[k : k + 2], 0.02)
        drifts.append(np.diff(np.concatenate([[0.0], state[:5]])))
    return np.array(drifts)


def bouc_wen(**settings) -> BoucWen:
    return BoucWen.of(BUILDING, HysteresisConfig(**settings))


def test_post_yield_ratio_one_is_the_linear_exact_map():
    from rlcontroller.physics.dynamics import step_map

    step = step_map(BUILDING, EXPERIMENT.simulation, 1)
    actuator_force = np.array([2e4, -1e4, 3e4])
    linear, reference = np.zeros(10), []
    for k in range(600):
        linear = (
            step.phi @ linear
            + step.ground_gain @ MOTION.acceleration[k : k + 2]
            + step.force_gain @ actuator_force
        )
        reference.append(np.diff(np.concatenate([[0.0], linear[:5]])))
    drifts = run(bouc_wen(yield_drift=0.001, post_yield_ratio=1.0, substeps=8), 600, actuator_force)
    np.testing.assert_allclose(drifts, np.array(reference), atol=2e-6 * np.abs(reference).max())


def loop(amplitude: float, exponent: float, alpha: float, cycles: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Story force (N) against a slow sinusoidal drift (m) of one story, k = 5e6 N/m, d_y = 0.01 m."""
    k, yield_drift, steps = 5.0e6, 0.01, 4000 * cycles
    time = np.linspace(0.0, cycles * 2 * np.pi, steps + 1)
    drift, rate = amplitude * np.sin(time), amplitude * np.cos(time)
    z, forces = 0.0, [0.0]
    h = time[1]
    for i in range(steps):  # RK4 on z with the prescribed drift rate, independent of the integrator
        r0, r1 = rate[i], rate[i + 1]
        rm = amplitude * np.cos(time[i] + 0.5 * h)
        k1 = z_rate(z, r0, yield_drift, exponent, 0.5, 0.5)
        k2 = z_rate(z + 0.5 * h * k1, rm, yield_drift, exponent, 0.5, 0.5)
        k3 = z_rate(z + 0.5 * h * k2, rm, yield_drift, exponent, 0.5, 0.5)
        k4 = z_rate(z + h * k3, r1, yield_drift, exponent, 0.5, 0.5)
        z += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        forces.append(alpha * k * drift[i + 1] + (1 - alpha) * k * yield_drift * z)
    return drift, np.array(forces)


def test_a_quasi_static_cycle_draws_the_textbook_loop():
    k, yield_drift, amplitude = 5.0e6, 0.01, 0.04
    drift, force = loop(amplitude, exponent=20.0, alpha=0.0)
    first = drift[:1001]  # virgin loading up to the peak
    assert np.interp(yield_drift, first, force[:1001]) == pytest.approx(k * yield_drift, rel=0.05)
    assert force.max() == pytest.approx(k * yield_drift, rel=0.01)  # a plateau at the yield force
    last = slice(len(drift) - 4001, len(drift))  # the last, steady cycle
    area = np.trapezoid(force[last], drift[last])  # the loop integral of F dd: energy dissipated
    assert area > 0 and area == pytest.approx(4 * k * yield_drift * (amplitude - yield_drift), rel=0.03)
    _, elastic = loop(amplitude, exponent=2.0, alpha=1.0)
    assert abs(np.trapezoid(elastic[last], drift[last])) < 1e-6 * area  # a linear story dissipates nothing


def derivative(time, state, model: BoucWen, alpha: float):
    """The shear building's equations, story by story in plain numpy, for scipy's Radau."""
    x, v, z = state[:5], state[5:10], state[10:]
    drift = np.diff(np.concatenate([[0.0], x]))
    rate = np.diff(np.concatenate([[0.0], v]))
    force = alpha * STIFFNESS * drift + model.hysteretic_stiffness * z
    restoring = force - np.append(force[1:], 0.0)
    ground = np.interp(time, MOTION.time, MOTION.acceleration)
    acceleration = model.mass_inverse * (-model.damping @ v - restoring) - ground
    z_dot = rate / model.yield_drift * (1 - np.abs(z) ** model.exponent * (0.5 * np.sign(rate * z) + 0.5))
    return np.concatenate([v, acceleration, z_dot])


@pytest.mark.slow
def test_a_record_response_matches_scipy_radau():
    model = bouc_wen(yield_drift=0.005, post_yield_ratio=0.1, exponent=2.0, substeps=8)
    steps = 400  # 8 s of strong motion
    drifts = run(model, steps)
    times = 0.02 * np.arange(1, steps + 1)
    solution = scipy.integrate.solve_ivp(
        derivative,
        (0.0, times[-1]),
        np.zeros(15),
        method="Radau",
        t_eval=times,
        rtol=1e-10,
        atol=1e-12,
        args=(model, 0.1),
        max_step=0.005,
    )
    reference = np.diff(np.vstack([np.zeros(steps), solution.y[:5]]), axis=0).T
    assert np.abs(reference).max() / 0.005 > 2  # it yields: ductility above 2
    np.testing.assert_allclose(drifts, reference, atol=1e-4 * np.abs(reference).max())


def test_the_error_falls_at_the_integrators_order_when_substeps_double():
    """RK4 is fourth order where the right-hand side is smooth: with a = 1 against the exact linear
    map, the error falls 16x per doubling. Yielding stories have a right-hand side that jumps at
    every velocity reversal (beta sgn(d' z)), which costs RK4 its order there: measured about 2.2
    from 2 to 16 sub-steps; the error still falls at every doubling."""
    from rlcontroller.physics.dynamics import step_map

    step = step_map(BUILDING, EXPERIMENT.simulation, 1)
    linear, exact = np.zeros(10), []
    for k in range(300):
        linear = step.phi @ linear + step.ground_gain @ MOTION.acceleration[k : k + 2]
        exact.append(np.diff(np.concatenate([[0.0], linear[:5]])))
    smooth = [
        np.abs(run(bouc_wen(yield_drift=0.01, post_yield_ratio=1.0, substeps=q), 300) - exact).max()
        for q in (1, 2, 4)
    ]
    assert np.all(np.log2(np.array(smooth[:-1]) / np.array(smooth[1:])) > 3.8)
    reference = run(bouc_wen(yield_drift=0.005, exponent=2.0, substeps=96), 300)
    errors = [
        np.abs(run(bouc_wen(yield_drift=0.005, exponent=2.0, substeps=q), 300) - reference).max()
        for q in (2, 4, 8, 16)
    ]
    assert np.all(np.diff(errors) < 0) and np.log2(errors[0] / errors[-1]) / 3 > 2.0


def test_a_sharp_loop_stays_bounded_with_few_substeps():
    """An exponent of 10-20 (an elastic-plastic story) at one or two sub-steps: an RK4 stage past |z| = 1 once
    raised |z|^n far above 1 and threw z back ever further (NaN within the record); with |z|^n read as at most
    1 the run stays finite and near the one with 64 sub-steps."""
    for exponent in (10.0, 20.0):
        reference = run(
            bouc_wen(yield_drift=0.01, post_yield_ratio=0.05, exponent=exponent, substeps=64), 600
        )
        assert np.abs(reference).max() / 0.01 > 10  # deep into yielding
        for substeps, tolerance in ((1, 0.2), (2, 0.04)):
            drifts = run(
                bouc_wen(yield_drift=0.01, post_yield_ratio=0.05, exponent=exponent, substeps=substeps), 600
            )
            assert np.all(np.isfinite(drifts))
            assert np.abs(drifts - reference).max() < tolerance * np.abs(reference).max()


def test_a_yielding_plant_reports_ductility_residual_drift_and_hysteretic_energy():
    from rlcontroller.control.controllers import Uncontrolled
    from rlcontroller.evaluation.evaluation import evaluate

    plant = Plant(Experiment(plant={"hysteresis": {"yield_drift": 0.004, "post_yield_ratio": 0.1}}))
    assert plant.n_state == 15 and plant.elastic.n_state == 10 and plant.elastic.yielding is None
    result = evaluate(plant, [MOTION], [Uncontrolled(3)], "test", include_optimal=True)
    summary = result.summary()
    assert {"ductility", "residual_drift_m", "hysteretic_energy_J"} <= set(summary.columns)
    assert (
        summary.loc["uncontrolled", "ductility"] > 1.0
        and summary.loc["uncontrolled", "hysteretic_energy_J"] > 0
    )
    assert "optimal (clairvoyant)" not in result.controllers  # no linear optimum for a yielding plant
    bare = result.responses["uncontrolled", MOTION.name]
    assert bare.time[-1] == pytest.approx(MOTION.duration + 20.0, abs=0.03)  # the settling tail


@pytest.mark.slow
def test_a_matrix_building_yields_in_its_story_springs_and_keeps_the_rest_linear():
    """A stiffness matrix that is not a shear building's (floors 1 and 3, 2 and 4 coupled, as a frame's
    columns couple floors): each story's spring is story shear over drift under first-mode forces, and yields
    with its own parameters; the rest of K stays linear (and carries nothing in the first mode's shape).
    Assembled story by story here, the first mode by numpy's eig, and solved with scipy's Radau: the plant
    agrees."""
    from rlcontroller.config import MatrixBuildingConfig

    stiffness = BUILDING.stiffness.copy()
    stiffness[np.ix_([0, 2], [0, 2])] += 2.0e7 * np.array([[1.0, -1.0], [-1.0, 1.0]])
    stiffness[np.ix_([1, 3], [1, 3])] += 1.0e7 * np.array([[1.0, -1.0], [-1.0, 1.0]])
    matrices = MatrixBuildingConfig(
        mass_matrix=BUILDING.mass.tolist(),
        stiffness_matrix=stiffness.tolist(),
        damping_matrix=BUILDING.damping.tolist(),
        story_heights=[3.0] * 5,
    )
    settings = {
        "yield_drift": [0.004, 0.005, 0.006, 0.005, 0.004],
        "post_yield_ratio": [0.1, 0.2, 0.05, 0.3, 0.1],
    }
    settings |= {"exponent": [2.0, 3.0, 1.5, 2.0, 4.0], "beta": [0.5, 0.3, 0.7, 0.5, 0.9]}
    settings["gamma"] = [1.0 - b for b in settings["beta"]]
    model = Plant(Experiment(building=matrices, plant={"hysteresis": settings | {"substeps": 8}})).yielding
    values, vectors = np.linalg.eig(np.linalg.solve(BUILDING.mass, stiffness))
    first = np.real(vectors[:, np.argmin(np.real(values))])
    forces = BUILDING.mass @ first
    displacement = np.linalg.solve(stiffness, forces)
    k = np.cumsum(forces[::-1])[::-1] / np.diff(np.concatenate([[0.0], displacement]))
    drift_of = np.eye(5) - np.eye(5, k=-1)
    remainder = stiffness - drift_of.T @ np.diag(k) @ drift_of
    assert (
        np.abs(remainder).max() > 1e6
        and np.linalg.eigvalsh(remainder).min() > -1e-6 * np.abs(remainder).max()
    )
    a, d_y = np.array(settings["post_yield_ratio"]), np.array(settings["yield_drift"])
    n_exp, beta = np.array(settings["exponent"]), np.array(settings["beta"])

    def springs(time, state):
        x, v, z = state[:5], state[5:10], state[10:]
        drift, rate = np.diff(np.concatenate([[0.0], x])), np.diff(np.concatenate([[0.0], v]))
        story = a * k * drift + (1 - a) * k * d_y * z
        force = remainder @ x + story - np.append(story[1:], 0.0)
        ground = np.interp(time, MOTION.time, MOTION.acceleration)
        acceleration = (-BUILDING.damping @ v - force) / np.diag(BUILDING.mass) - ground
        z_dot = rate / d_y * (1 - np.abs(z) ** n_exp * (beta * np.sign(rate * z) + 1 - beta))
        return np.concatenate([v, acceleration, z_dot])

    steps = 300
    state, drifts = np.zeros(15), []
    for step in range(steps):
        state = model.step(state, np.zeros(3), MOTION.acceleration[step : step + 2], 0.02)
        drifts.append(np.diff(np.concatenate([[0.0], state[:5]])))
    times = 0.02 * np.arange(1, steps + 1)
    solution = scipy.integrate.solve_ivp(
        springs,
        (0.0, times[-1]),
        np.zeros(15),
        method="Radau",
        t_eval=times,
        rtol=1e-10,
        atol=1e-12,
        max_step=0.005,
    )
    reference = np.diff(np.vstack([np.zeros(steps), solution.y[:5]]), axis=0).T
    assert np.max(np.abs(reference) / d_y) > 2  # it yields
    np.testing.assert_allclose(np.array(drifts), reference, atol=1e-4 * np.abs(reference).max())
    history = model.history(MOTION.acceleration[: steps + 1], 1, 0.02)  # a whole record in one call: the same
    np.testing.assert_allclose(
        np.diff(history[1:, :5], axis=1, prepend=0.0), np.array(drifts), rtol=0, atol=1e-12
    )


def test_story_springs_of_a_shear_building_are_its_story_stiffnesses():
    from rlcontroller.physics.hysteresis import story_springs

    springs = story_springs(BUILDING.mass, BUILDING.stiffness)
    np.testing.assert_allclose(springs, EXPERIMENT.building.stiffnesses, rtol=1e-10)


def _one_story(**settings) -> tuple[BoucWen, float]:
    """A one-story building of 1e5 kg and 4e6 N/m with Bouc-Wen `settings` and one actuator of 1 MN; its
    spring's stiffness."""
    from rlcontroller.physics.structure import Building

    building = Building(
        mass=np.array([[1.0e5]]),
        stiffness=np.array([[4.0e6]]),
        damping=np.array([[2.0e4]]),
        actuator_matrix=np.array([[1.0]]),
        force_limits=np.array([1.0e6]),
        story_heights=np.array([3.0]),
    )
    return BoucWen.of(building, HysteresisConfig(**settings)), 4.0e6


@pytest.mark.parametrize("fraction, falls", [(0.9, False), (1.1, True)])
def test_a_story_losing_strength_stands_below_its_strength_and_collapses_above_it(fraction, falls):
    """a = -0.2: the story's force peaks at k d_y at yield and falls after, so a force held below k d_y is
    carried and one above it pushes the story to its collapse drift, where it stays at rest."""
    model, k = _one_story(
        yield_drift=0.01, post_yield_ratio=-0.2, exponent=20.0, collapse_drift=0.3, substeps=8
    )
    strength, state, drifts = k * 0.01, np.zeros(3), []
    for step in range(4000):  # the force raised over 40 s (quasi-static: the period is 1 s), then held
        force = fraction * strength * min(1.0, step / 2000)
        state = model.step(state, np.array([force / 1.0e6]), np.zeros(2), 0.02)
        drifts.append(state[0])
    assert (max(drifts) >= 0.3) == falls
    if falls:
        assert drifts[-1] == drifts[-2] and state[1] == 0.0  # as it lies, at rest
    else:  # carried on the rising branch, about 0.9 d_y (the sharp loop is near elastic below yield)
        assert drifts[-1] == pytest.approx(0.009, rel=0.05)


def test_a_negative_post_yield_ratio_needs_a_collapse_drift_beyond_yield():
    with pytest.raises(ValueError, match="needs a collapse_drift"):
        HysteresisConfig(yield_drift=0.01, post_yield_ratio=-0.1)
    with pytest.raises(ValueError, match="must exceed yield_drift"):
        HysteresisConfig(yield_drift=0.01, post_yield_ratio=-0.1, collapse_drift=0.005)
