"""The Riccati solutions: exact modal truncation of quasi-static modes, near-optimal lifted gains, every
solution checked against its equation, and designs for every shipped building (the 76-story included)."""

import numpy as np
import pytest
import scipy.linalg

from rlcontroller.assets import CONFIGS
from rlcontroller.config import load_experiment
from rlcontroller.control import riccati
from rlcontroller.control.lqg import design_lqg, design_lqg_ground_model, design_lqg_wind_model
from rlcontroller.control.riccati import (
    DesignError,
    kalman_gain_on_kept_modes,
    lqr,
    lqr_on_kept_modes,
    modal_truncation,
    solve_dare,
)
from rlcontroller.physics.plant import Plant


def system_with_a_quasi_static_mode(fast: float) -> tuple[np.ndarray, np.ndarray]:
    """A lightly damped oscillator and a mode that keeps `fast` of itself per step, in mixed coordinates."""
    rng = np.random.default_rng(3)
    angle, radius = 0.3, 0.97
    modal = scipy.linalg.block_diag(
        [[radius * np.cos(angle), radius * np.sin(angle)], [-radius * np.sin(angle), radius * np.cos(angle)]],
        [[0.5]],
        [[fast]],
    )
    mixing = rng.normal(size=(4, 4)) + 3.0 * np.eye(4)
    return mixing @ modal @ np.linalg.inv(mixing), rng.normal(size=(4, 1))


def test_the_truncation_keeps_an_invariant_subspace_exactly():
    phi, _ = system_with_a_quasi_static_mode(1e-9)
    truncation = modal_truncation(phi)
    basis, projector = truncation.basis, truncation.projector
    assert basis.shape == (4, 3)
    np.testing.assert_allclose(projector @ basis, np.eye(3), atol=1e-12)
    reduced = projector @ phi @ basis
    # the kept modes evolve alone
    np.testing.assert_allclose(projector @ phi, reduced @ projector, atol=1e-12)
    np.testing.assert_allclose(np.sort(np.abs(np.linalg.eigvals(reduced))), [0.5, 0.97, 0.97], rtol=1e-10)
    assert modal_truncation(scipy.linalg.block_diag(phi[:2, :2], [[0.9]])) is None  # nothing to drop


def test_the_lifted_lqr_costs_what_the_full_one_costs():
    """Where the full equation is still solvable (a mode keeping 1e-8 of itself), the gain designed on the
    kept modes and lifted back costs the same to 1e-9, for a cost on the state after the step as the
    reward's (cost_k = |H x_k+1|^2 + rho |u_k|^2, x_k+1 = phi x_k + b u_k): the action's quasi-static
    response is in R, and the quasi-static mode of x_k reaches x_k+1 only as 1e-8 of itself."""
    phi, b = system_with_a_quasi_static_mode(1e-8)
    h = np.random.default_rng(4).normal(size=(3, 4))
    q, r, n = phi.T @ h.T @ h @ phi, b.T @ h.T @ h @ b + 0.1, phi.T @ h.T @ h @ b
    full = solve_dare(phi, b, q, r, s=n)
    full_gain = np.linalg.solve(b.T @ full @ b + r, b.T @ full @ phi + n.T)
    full_again, _ = lqr(phi, b, q, r, n=n)
    # the full equation solves: the full design
    np.testing.assert_allclose(full_again, full_gain, rtol=1e-10, atol=0.0)
    lifted_gain, _ = lqr_on_kept_modes(phi, b, q, r, n=n, truncation=modal_truncation(phi))

    def cost(gain):  # trace of the closed loop's cost-to-go from unit initial states
        closed = phi - b @ gain
        stage = closed.T @ h.T @ h @ closed + 0.1 * gain.T @ gain
        return np.trace(scipy.linalg.solve_discrete_lyapunov(closed.T, stage))

    assert cost(lifted_gain) == pytest.approx(cost(full_gain), rel=1e-9)
    assert max(abs(np.linalg.eigvals(phi - b @ lifted_gain))) < 1


def test_the_lifted_kalman_gain_leaves_a_stable_error():
    phi, _ = system_with_a_quasi_static_mode(1e-12)
    c = np.array([[1.0, 0.0, 0.5, 0.2]])
    gain = kalman_gain_on_kept_modes(
        phi, c, 1e-2 * np.eye(4), np.array([[1e-4]]), truncation=modal_truncation(phi)
    )
    assert max(abs(np.linalg.eigvals((np.eye(4) - gain @ c) @ phi))) < 1


def test_a_solution_that_misses_its_equation_is_an_error(monkeypatch):
    phi, b = system_with_a_quasi_static_mode(0.1)
    solver = scipy.linalg.solve_discrete_are
    monkeypatch.setattr(riccati.scipy.linalg, "solve_discrete_are", lambda *a, **k: 1.001 * solver(*a, **k))
    with pytest.raises(DesignError, match="misses its equation by"):
        solve_dare(phi, b, np.eye(4), np.eye(1), what="LQR")


def test_an_unstabilisable_model_is_an_error_in_one_line():
    with pytest.raises(DesignError, match="no stabilising solution") as error:
        solve_dare(np.array([[2.0]]), np.array([[0.0]]), np.eye(1), np.eye(1), what="LQR")
    assert "\n" not in str(error.value)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["five_story_every_story", "five_story_amd", "seventy_six_story_atmd"])
def test_every_shipped_building_gets_its_lqg_designs(name):
    """The 76-story benchmark's damping leaves modes that die within a 0.1 s step: its Kalman designs failed
    in scipy's Schur reordering before the truncation. Every variant designs and closes a stable loop."""
    plant = Plant(load_experiment(CONFIGS / "experiments" / f"{name}.yaml")).design
    designs = [design_lqg(plant), design_lqg(plant, known_ground=True)]
    designs.append(design_lqg_wind_model(plant) if plant.wind is not None else design_lqg_ground_model(plant))
    if name.startswith("seventy_six"):  # modes that die within its 0.1 s step, which the Kalman design drops
        assert modal_truncation(designs[-1].filter.phi) is not None
    for design in designs:
        kalman = design.filter
        assert max(abs(design.closed_loop_eigenvalues())) < 1
        error = (np.eye(kalman.size) - kalman.gain @ kalman.sensor_c) @ kalman.phi
        assert max(abs(np.linalg.eigvals(error))) < 1


def test_an_actuator_delay_stays_in_the_design():
    """A delay's buffer has zero eigenvalues, yet the action reaches the building only through it: the
    full equation solves, so the design is the full one (dropping the buffer made the LQG re-designed on a
    one-step-delay plant worse than the nominal one, J1 0.469 against 0.406 on the records)."""
    from rlcontroller.config import Experiment
    from rlcontroller.control.lqr import lqr_gain, quadratic_cost

    experiment = Experiment.model_validate({"plant": {"actuators": {"delay_steps": 1}}})
    plant = Plant(experiment).elastic
    step = plant.sampled(1).step
    assert np.min(np.abs(np.linalg.eigvals(step.phi))) < 1e-12  # the buffer
    cost = quadratic_cost(plant, experiment.reward, step)
    gain, _ = lqr_gain(step, cost, plant.building.force_limits)
    b = step.force_gain * plant.building.force_limits
    q, r, n = cost.state.T @ cost.state, cost.action.T @ cost.action, cost.state.T @ cost.action
    riccati = scipy.linalg.solve_discrete_are(step.phi, b, q, r, s=n)
    np.testing.assert_allclose(
        gain, np.linalg.solve(b.T @ riccati @ b + r, b.T @ riccati @ step.phi + n.T), rtol=1e-9
    )
