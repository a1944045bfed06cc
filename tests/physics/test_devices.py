"""Mass devices: Warburton's tuning is the optimum it claims, a vanishing tuned mass leaves the
building as it was, and the assembled plant agrees with an independent integration of the
equations of motion written device by device."""

import numpy as np
import pytest
import scipy.integrate
import scipy.linalg
import scipy.optimize

from rlcontroller.config import Experiment
from rlcontroller.devices.tuned_mass import warburton_optimum
from rlcontroller.physics.dynamics import simulate
from rlcontroller.physics.motions.excitation import on_control_grid
from rlcontroller.physics.motions.records import load_records
from rlcontroller.physics.plant import Plant


def primary_with_absorber(mass_ratio: float, frequency_ratio: float, damping_ratio: float):
    """Undamped primary (m = 1, omega = 1) with an absorber, under base acceleration: A, B and the
    primary's displacement row."""
    k = mass_ratio * frequency_ratio**2
    c = 2.0 * damping_ratio * mass_ratio * frequency_ratio
    mass = np.diag([1.0, mass_ratio])
    stiffness = np.array([[1.0 + k, -k], [-k, k]])
    damping = np.array([[c, -c], [-c, c]])
    a = np.block(
        [[np.zeros((2, 2)), np.eye(2)], [-np.linalg.solve(mass, stiffness), -np.linalg.solve(mass, damping)]]
    )
    return a, np.array([0.0, 0.0, -1.0, -1.0]), np.array([1.0, 0.0, 0.0, 0.0])


def mean_square(parameters, mass_ratio):
    """The primary's stationary displacement variance under unit white-noise base acceleration."""
    a, b, c = primary_with_absorber(mass_ratio, *parameters)
    if np.max(np.linalg.eigvals(a).real) >= 0.0:
        return np.inf
    return float(c @ scipy.linalg.solve_continuous_lyapunov(a, -np.outer(b, b)) @ c)


def peak_response(parameters, mass_ratio):
    """The peak over frequency of |X_primary / a_g| (harmonic base acceleration)."""
    a, b, c = primary_with_absorber(mass_ratio, *parameters)
    frequencies = np.linspace(0.6, 1.4, 1601)
    return max(abs(c @ np.linalg.solve(1j * w * np.eye(4) - a, b)) for w in frequencies)


@pytest.mark.parametrize("mass_ratio", [0.01, 0.02, 0.05])
def test_warburtons_random_tuning_minimises_the_mean_square_displacement(mass_ratio):
    tuned = warburton_optimum(mass_ratio, "random")
    assert tuned[0] == pytest.approx(np.sqrt(1 - mass_ratio / 2) / (1 + mass_ratio), rel=1e-15)
    best = scipy.optimize.minimize(
        mean_square,
        [1.0, 0.1],
        args=(mass_ratio,),
        method="Nelder-Mead",
        options={"xatol": 1e-9, "fatol": 1e-14},
    )
    np.testing.assert_allclose(tuned, best.x, rtol=1e-5)


@pytest.mark.slow
@pytest.mark.parametrize("mass_ratio", [0.01, 0.02, 0.05])
def test_warburtons_harmonic_tuning_minimises_the_peak_response(mass_ratio):
    tuned = warburton_optimum(mass_ratio, "harmonic")
    at_tuning = peak_response(tuned, mass_ratio)
    frequency, damping = tuned
    grid = [
        (frequency * (1 + df), damping * (1 + dz))
        for df in (-0.02, -0.01, 0.01, 0.02)
        for dz in (-0.3, 0.0, 0.3)
    ]
    grid += [(frequency, damping * 0.7), (frequency, damping * 1.3)]
    assert all(peak_response(other, mass_ratio) > at_tuning for other in grid)
    best = scipy.optimize.minimize(peak_response, tuned, args=(mass_ratio,), method="Nelder-Mead")
    assert at_tuning <= 1.001 * best.fun  # Den Hartog-type closed form: within 0.1 % of the true optimum


def experiment_with(devices, actuators=None) -> Experiment:
    raw = Experiment().model_dump()
    raw["devices"] = devices
    if actuators is not None:
        raw["actuators"] = actuators
    return Experiment.model_validate(raw)


def test_a_vanishing_tuned_mass_leaves_the_building_as_it_was(records):
    motion = load_records(records)[0][0]
    grid = on_control_grid(motion, 0.02)
    samples, substeps = grid.ground, grid.substeps
    bare = Plant(Experiment())
    tiny = Plant(experiment_with([{"type": "tuned_mass", "floor": 5, "mass_ratio": 1e-9}]))
    assert tiny.building.n_dofs == 6 and tiny.building.n_floors == 5
    expected = simulate(bare.building, bare.sampled(substeps).step, samples)
    got = simulate(tiny.building, tiny.sampled(substeps).step, samples)
    for quantity in ("drift", "absolute_acceleration", "story_shear"):
        scale = np.max(np.abs(expected.quantity(quantity)))
        np.testing.assert_allclose(got.quantity(quantity), expected.quantity(quantity), atol=1e-6 * scale)


@pytest.mark.slow
def test_mass_devices_match_an_independent_integration_of_their_equations(records):
    """Floors of the paper's building with a tuned mass on floor 3 and an active mass driver on the
    roof, pushed by its three actuators and the driver with random held forces, on a real record:
    the step maps against solve_ivp on equations written per floor and per device."""
    devices = [
        {"type": "tuned_mass", "floor": 3, "mass_ratio": 0.03, "mode": 2},
        {"type": "active_mass", "floor": 5, "mass_ratio": 0.02, "force_limit": 2.0e4, "stroke_limit": 0.5},
    ]
    plant = Plant(experiment_with(devices))
    building = plant.building
    motion = load_records(records)[0][0]
    grid = on_control_grid(motion, plant.control_dt)
    samples, substeps = grid.ground, grid.substeps
    samples = samples[: 400 * substeps + 1]  # the first 8 s
    steps = (samples.size - 1) // substeps
    forces = np.random.default_rng(3).uniform(-1.0, 1.0, (steps, 4)) * building.force_limits
    result = simulate(building, plant.sampled(substeps).step, samples, forces=forces)

    floors = np.asarray(Experiment().building.masses)
    story_k = np.asarray(Experiment().building.stiffnesses)
    floor_damping = Plant(Experiment()).building.damping  # Rayleigh, of the floors alone
    tmd, amd = building.devices
    dt = plant.control_dt / substeps

    def rates(t, state, held):
        x, v = state[:7], state[7:]
        a_g = np.interp(t, np.arange(samples.size) * dt, samples)
        drift = x[:5] - np.concatenate([[0.0], x[:4]])
        story = story_k * drift
        force = np.zeros(7)
        force[:5] -= story - np.concatenate([story[1:], [0.0]])
        force[:5] -= floor_damping @ v[:5]
        for dof, device in ((5, tmd), (6, amd)):
            floor = device.floor - 1
            pull = device.stiffness * (x[dof] - x[floor]) + device.damping * (v[dof] - v[floor])
            force[dof] -= pull
            force[floor] += pull
        for story_number, u in zip((1, 3, 5), held[:3], strict=True):
            force[story_number - 1] += u
            if story_number > 1:
                force[story_number - 2] -= u
        force[6] += held[3]  # the driver pushes its mass and pulls the roof
        force[4] -= held[3]
        masses = np.concatenate([floors, [tmd.mass, amd.mass]])
        return np.concatenate([v, force / masses - a_g])

    state = np.zeros(14)
    drifts, strokes = [np.zeros(5)], [np.zeros(2)]
    for k in range(steps):
        span = (k * plant.control_dt, (k + 1) * plant.control_dt)
        state = scipy.integrate.solve_ivp(rates, span, state, args=(forces[k],), rtol=1e-10, atol=1e-13).y[
            :, -1
        ]
        drifts.append(state[:5] - np.concatenate([[0.0], state[:4]]))
        strokes.append(state[5:7] - state[[2, 4]])
    np.testing.assert_allclose(result.drift, drifts, atol=1e-6 * np.max(np.abs(drifts)))
    np.testing.assert_allclose(result.stroke, strokes, atol=1e-6 * np.max(np.abs(strokes)))
    assert np.max(np.abs(result.stroke[:, 1])) > 5 * np.max(np.abs(result.drift[:, 4]))  # the driver moves


def test_the_tuning_is_the_design_models_so_a_softer_plant_detunes_it():
    devices = [{"type": "tuned_mass", "floor": 5, "mass_ratio": 0.02}]
    design = Plant(experiment_with(devices))
    raw = experiment_with(devices).model_dump()
    raw["plant"] = {"stiffness": 0.8}
    softer = Plant(Experiment.model_validate(raw))
    assert softer.building.devices == design.building.devices  # same mass, spring and dashpot
    omega = np.sqrt(scipy.linalg.eigh(design.bare.building.stiffness, design.bare.building.mass)[0][0])
    tmd = design.building.devices[0]
    assert np.sqrt(tmd.stiffness / tmd.mass) / omega == pytest.approx(warburton_optimum(0.02)[0], rel=1e-12)


def test_a_detuned_plant_changes_only_the_devices_spring_and_dashpot():
    devices = [
        {"type": "active_mass", "floor": 5, "mass_ratio": 0.02, "force_limit": 1e4, "stroke_limit": 1.0}
    ]
    raw = experiment_with(devices, actuators=[]).model_dump()
    nominal = Plant(Experiment.model_validate(raw)).building
    raw["plant"] = {"devices": {"frequency": 0.9, "damping": 2.0}}
    built = Plant(Experiment.model_validate(raw)).building
    (tuned,), (detuned,) = nominal.devices, built.devices
    assert (
        detuned.stiffness == pytest.approx(0.81 * tuned.stiffness) and detuned.damping == 2.0 * tuned.damping
    )
    assert detuned.mass == tuned.mass and np.array_equal(built.actuator_matrix, nominal.actuator_matrix)
    np.testing.assert_array_equal(built.mass, nominal.mass)
