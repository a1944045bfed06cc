import numpy as np
import pytest
import scipy.signal
from conftest import sdof

from rlcontroller.config import SimulationConfig
from rlcontroller.physics.dynamics import (
    exact_substep,
    newmark_substep,
    output_matrices,
    simulate,
    state_space,
    step_map,
)
from rlcontroller.physics.motions.excitation import Load, on_control_grid, read_at2

MASS, STIFFNESS = 2.0e4, 8.0e5  # kg, N/m -> omega = 6.32 rad/s


def iterate(phi: np.ndarray, z0: np.ndarray, steps: int) -> np.ndarray:
    states = [z0]
    for _ in range(steps):
        states.append(phi @ states[-1])
    return np.array(states)


def rayleigh_motion(seed: int = 3, dt: float = 0.01, seconds: float = 20.0) -> np.ndarray:
    """A smooth, broadband ground motion (m/s^2) for comparisons."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, dt)
    frequencies = rng.uniform(0.3, 8.0, 12)
    phases = rng.uniform(0, 2 * np.pi, 12)
    return np.sum(np.sin(2 * np.pi * frequencies[:, None] * t + phases[:, None]), axis=0) * np.exp(-0.1 * t)


@pytest.mark.parametrize("method", ["exact", "newmark"])
def test_sdof_free_vibration_matches_the_analytic_solution(method):
    zeta = 0.05
    omega = np.sqrt(STIFFNESS / MASS)
    building = sdof(MASS, STIFFNESS, 2 * zeta * omega * MASS)
    dt = 0.001
    substep = exact_substep(state_space(building), dt) if method == "exact" else newmark_substep(building, dt)
    states = iterate(substep.phi, np.array([0.05, 0.0]), 5000)
    t = np.arange(5001) * dt
    omega_d = omega * np.sqrt(1 - zeta**2)
    analytic = (
        0.05
        * np.exp(-zeta * omega * t)
        * (np.cos(omega_d * t) + zeta * omega / omega_d * np.sin(omega_d * t))
    )
    tolerance = 1e-12 if method == "exact" else 1e-5  # m; Newmark's period error is (omega dt)^2 / 12
    np.testing.assert_allclose(states[:, 0], analytic, atol=tolerance)


@pytest.mark.parametrize("method", ["exact", "newmark"])
def test_sdof_harmonic_ground_motion_matches_the_analytic_solution(method):
    zeta, amplitude, forcing = 0.02, 2.0, 4.0  # -, m/s^2, rad/s
    omega = np.sqrt(STIFFNESS / MASS)
    building = sdof(MASS, STIFFNESS, 2 * zeta * omega * MASS)
    ground_dt, control_dt = 0.0005, 0.01  # 20 sub-steps per control step
    t = np.arange(0.0, 15.0 + ground_dt / 2, ground_dt)
    ground = amplitude * np.sin(forcing * t)
    step = step_map(building, SimulationConfig(control_dt=control_dt, method=method), substeps=20)
    result = simulate(building, step, ground)
    # x'' + 2 zeta omega x' + omega^2 x = -A sin(W t), from rest.
    magnitude = amplitude / np.hypot(omega**2 - forcing**2, 2 * zeta * omega * forcing)
    phase = np.arctan2(2 * zeta * omega * forcing, omega**2 - forcing**2)
    omega_d = omega * np.sqrt(1 - zeta**2)
    c1 = magnitude * np.sin(-phase)
    c2 = (zeta * omega * c1 - (-magnitude * forcing * np.cos(-phase))) / omega_d
    tc = result.time
    analytic = -magnitude * np.sin(forcing * tc - phase) + np.exp(-zeta * omega * tc) * (
        c1 * np.cos(omega_d * tc) + c2 * np.sin(omega_d * tc)
    )
    peak = np.max(np.abs(analytic))
    np.testing.assert_allclose(result.displacement[:, 0], analytic, atol=1e-5 * peak)


def test_five_story_record_response_matches_lsim(paper_building):
    dt = 0.01
    ground = rayleigh_motion(dt=dt)
    step = step_map(paper_building, SimulationConfig(control_dt=dt))
    result = simulate(paper_building, step, ground)
    system = state_space(paper_building)
    c, _ = output_matrices(paper_building, "drift")
    t = np.arange(ground.size) * dt
    _, drift, _ = scipy.signal.lsim((system.a, system.b_ground[:, None], c, np.zeros((5, 1))), ground, t)
    np.testing.assert_allclose(result.drift, drift, atol=1e-8 * np.max(np.abs(drift)))


@pytest.mark.parametrize("method", ["exact", "newmark"])
def test_undamped_free_vibration_conserves_energy(paper_building, method):
    from dataclasses import replace

    building = replace(paper_building, damping=np.zeros((5, 5)))
    dt = 0.02
    substep = exact_substep(state_space(building), dt) if method == "exact" else newmark_substep(building, dt)
    z0 = np.concatenate([np.linspace(0.01, 0.05, 5), np.zeros(5)])
    states = iterate(substep.phi, z0, 5000)
    x, v = states[:, :5], states[:, 5:]
    energy = 0.5 * np.einsum("ti,ij,tj->t", v, building.mass, v) + 0.5 * np.einsum(
        "ti,ij,tj->t", x, building.stiffness, x
    )
    np.testing.assert_allclose(energy, energy[0], rtol=1e-9)


def test_newmark_error_falls_four_times_when_dt_halves(paper_building):
    ground_fine = rayleigh_motion(dt=0.005)
    errors = []
    for dt in (0.02, 0.01, 0.005):
        ground = ground_fine[:: round(dt / 0.005)]
        substeps = round(0.02 / dt)
        runs = [
            simulate(
                paper_building,
                step_map(paper_building, SimulationConfig(control_dt=0.02, method=m), substeps),
                ground,
            )
            for m in ("exact", "newmark")
        ]
        errors.append(np.max(np.abs(runs[1].drift - runs[0].drift)))
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all((ratios > 3.5) & (ratios < 4.5)), ratios


def runge_kutta_reference(building, ground: np.ndarray, ground_dt: float, refinement: int) -> np.ndarray:
    """Classical RK4 on the continuous system, ground linear between samples; drift at the samples."""
    system = state_space(building)
    c, _ = output_matrices(building, "drift")
    h = ground_dt / refinement
    z = np.zeros(system.a.shape[0])
    drifts = [c @ z]

    def rate(state, acceleration):
        return system.a @ state + system.b_ground * acceleration

    for k in range(ground.size - 1):
        start, slope = ground[k], (ground[k + 1] - ground[k]) / ground_dt
        for j in range(refinement):
            t = j * h
            k1 = rate(z, start + slope * t)
            k2 = rate(z + h / 2 * k1, start + slope * (t + h / 2))
            k3 = rate(z + h / 2 * k2, start + slope * (t + h / 2))
            k4 = rate(z + h * k3, start + slope * (t + h))
            z = z + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        drifts.append(c @ z)
    return np.array(drifts)


@pytest.mark.slow
def test_exact_discretisation_matches_a_40_times_finer_reference(paper_building):
    dt = 0.02
    ground = rayleigh_motion(dt=dt, seconds=8.0)
    coarse = simulate(paper_building, step_map(paper_building, SimulationConfig(control_dt=dt)), ground)
    reference = runge_kutta_reference(paper_building, ground, dt, refinement=40)
    np.testing.assert_allclose(coarse.drift, reference, atol=1e-5 * np.max(np.abs(reference)))


def test_newmark_agrees_with_exact_to_a_few_percent(paper_building, records):
    motion = read_at2(records / "RSN1086_NORTHR_SYL090.AT2")
    peaks = {}
    for method in ("exact", "newmark"):
        for dt in (0.02, 0.01):
            grid = on_control_grid(motion, dt)
            samples, substeps = grid.ground, grid.substeps
            result = simulate(
                paper_building,
                step_map(paper_building, SimulationConfig(control_dt=dt, method=method), substeps),
                samples,
            )
            peaks[method, dt] = np.max(np.abs(result.drift), axis=0)
    difference_02 = np.max(np.abs(peaks["newmark", 0.02] / peaks["exact", 0.02] - 1))
    difference_01 = np.max(np.abs(peaks["newmark", 0.01] / peaks["exact", 0.01] - 1))
    assert difference_02 < 0.05 and difference_01 < 0.015 and difference_01 < difference_02 / 2


def test_substeps_never_decimate_a_fine_record(paper_building):
    ground_dt = 0.005
    ground = rayleigh_motion(dt=ground_dt)
    grid = on_control_grid(Load("fine", ground_dt, ground), 0.02)
    samples, substeps = grid.ground, grid.substeps
    assert substeps == 4 and samples.size == ground.size
    coarse = simulate(
        paper_building, step_map(paper_building, SimulationConfig(control_dt=0.02), substeps), samples
    )
    fine = simulate(paper_building, step_map(paper_building, SimulationConfig(control_dt=ground_dt)), ground)
    np.testing.assert_allclose(coarse.drift, fine.drift[::4][: coarse.drift.shape[0]], atol=1e-12)


def test_held_force_is_the_same_at_both_ends_of_a_newmark_step(paper_building):
    """Newmark with a held force must converge to the exact zero-order-hold response."""
    rng = np.random.default_rng(0)
    forces = rng.uniform(-1e5, 1e5, (500, 3))
    ground = np.zeros(501)
    exact = simulate(
        paper_building, step_map(paper_building, SimulationConfig(control_dt=0.02)), ground, forces=forces
    )
    newmark = simulate(
        paper_building,
        step_map(paper_building, SimulationConfig(control_dt=0.02, method="newmark"), 16),
        np.zeros(500 * 16 + 1),
        forces=forces,
    )
    np.testing.assert_allclose(newmark.drift, exact.drift, atol=1e-3 * np.max(np.abs(exact.drift)))


def test_base_shear_is_the_sum_of_floor_mass_times_absolute_acceleration(paper_building):
    rng = np.random.default_rng(1)
    ground = rayleigh_motion(dt=0.02)
    forces = rng.uniform(-5e4, 5e4, (ground.size - 1, 3))
    result = simulate(paper_building, step_map(paper_building, SimulationConfig()), ground, forces=forces)
    masses = paper_building.floor_masses
    np.testing.assert_allclose(
        result.base_shear, result.absolute_acceleration @ masses, rtol=1e-10, atol=1e-6
    )
    top_story = masses[4] * result.absolute_acceleration[:, 4]
    np.testing.assert_allclose(result.story_shear[:, 4], top_story, rtol=1e-10, atol=1e-6)


def test_absolute_acceleration_is_relative_plus_ground_acceleration(paper_building):
    dt = 0.001
    ground = rayleigh_motion(dt=dt, seconds=5.0)
    result = simulate(paper_building, step_map(paper_building, SimulationConfig(control_dt=dt)), ground)
    relative = np.gradient(result.velocity, dt, axis=0)[1:-1]  # central differences, O(dt^2)
    absolute = relative + result.ground[1:-1, None]
    np.testing.assert_allclose(
        result.absolute_acceleration[1:-1], absolute, atol=1e-3 * np.max(np.abs(absolute))
    )


def test_constant_actuator_force_gives_the_static_drift(paper_building):
    force = np.array([4e4, -2e4, 3e4])
    steps = 60_000  # 1200 s: the 1 % mode has decayed by e^-52
    result = simulate(
        paper_building,
        step_map(paper_building, SimulationConfig()),
        np.zeros(steps + 1),
        forces=np.tile(force, (steps, 1)),
    )
    static = np.linalg.solve(paper_building.stiffness, paper_building.actuator_matrix @ force)
    static_drift = static - np.concatenate([[0.0], static[:-1]])
    np.testing.assert_allclose(result.drift[-1], static_drift, rtol=1e-6, atol=1e-12)
    # At rest nothing accelerates, so the inertial base shear sum(m a) vanishes.
    assert abs(result.base_shear[-1]) < 1e-6 * np.max(np.abs(force))
