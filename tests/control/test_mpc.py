"""MPC: with loose limits its first move is LQR's; with binding limits it never leaves them and its plan
costs no more than clipped LQR's; a step the solver does not finish falls back to LQR's clipped action and
is counted."""

import numpy as np
import pytest

from rlcontroller.config import Experiment
from rlcontroller.control.lqg import design_lqg_ground_model
from rlcontroller.control.lqr import lqr_gain, quadratic_cost
from rlcontroller.control.mpc import TOLERANCE, MPCController, mpc_problem
from rlcontroller.physics.plant import Plant

PLANT = Plant(Experiment())
RNG = np.random.default_rng(7)


@pytest.fixture(scope="module")
def controller():
    return MPCController(PLANT, 20)


def solve(controller, estimate):
    solver = controller._solver(0)
    solver.update(q=controller.problem.linear @ estimate)
    return solver.solve(raise_error=False).x


def test_with_loose_limits_the_first_move_is_lqrs(controller):
    """Estimates small enough that LQR stays inside the limits over the horizon: MPC's first move equals
    -K z to the solver's tolerance."""
    feedback = design_lqg_ground_model(PLANT).feedback
    for _ in range(5):
        estimate = 1e-4 * RNG.standard_normal(feedback.shape[1])
        np.testing.assert_allclose(solve(controller, estimate)[:3], -feedback @ estimate, atol=10 * TOLERANCE)


def test_with_binding_limits_the_plan_keeps_them_and_costs_no_more_than_clipped_lqr(controller):
    """Large estimates: every planned action within [-1, 1] (to the solver's tolerance, before any clip), and
    the plan's cost (the QP's objective) at most that of clipped LQR rolled out over the same horizon."""
    step = PLANT.ground_model_step()
    cost = quadratic_cost(PLANT, PLANT.experiment.reward, step)
    feedback, riccati = lqr_gain(step, cost, PLANT.force_limits)
    action_gain = step.force_gain * PLANT.force_limits
    problem = controller.problem
    for _ in range(5):
        estimate = 0.3 * RNG.standard_normal(feedback.shape[1])
        plan = solve(controller, estimate)
        assert np.all(np.abs(plan) <= 1.0 + 10 * TOLERANCE)
        state, clipped = estimate, []
        for _ in range(problem.horizon):
            clipped.append(np.clip(-feedback @ state, -1.0, 1.0))
            state = step.phi @ state + action_gain @ clipped[-1]
        clipped = np.concatenate(clipped)
        assert np.any(np.abs(clipped) == 1.0)  # the limits bind
        objective = [0.5 * a @ problem.hessian @ a + (problem.linear @ estimate) @ a for a in (plan, clipped)]
        assert objective[0] <= objective[1] + 1e-6 * abs(objective[1])


def test_a_step_the_solver_does_not_finish_falls_back_to_lqr_and_is_counted():
    controller = MPCController(PLANT, 20)
    observation = 0.5 * RNG.standard_normal((2, PLANT.layout.size))
    controller._solver(1)
    for solver in controller._solvers:
        solver.update_settings(max_iter=1)
    actions = controller.act(observation)
    assert controller.fallbacks == 2
    np.testing.assert_array_equal(actions, (controller.lqg._state @ controller.lqg.output).clip(-1.0, 1.0))


def test_the_problem_is_built_from_the_riccati_solution_it_ends_with():
    """N = 1: the QP's Hessian is 2 (H_u' H_u + B' P B), the LQR curvature of the last step."""
    step = PLANT.ground_model_step()
    cost = quadratic_cost(PLANT, PLANT.experiment.reward, step)
    _, riccati = lqr_gain(step, cost, PLANT.force_limits)
    action_gain = step.force_gain * PLANT.force_limits
    problem = mpc_problem(PLANT, 1)
    expected = 2 * (cost.action.T @ cost.action + action_gain.T @ riccati @ action_gain)
    np.testing.assert_allclose(problem.hessian, expected, rtol=1e-10)


@pytest.mark.slow
def test_compare_lqg_gains_an_mpc_row(tmp_path):
    """On the synthetic suite MPC ties LQG + ground model's J1 (its filter, its cost) within 5 %."""
    from rlcontroller import api
    from rlcontroller.assets import CONFIGS

    evaluation = api.compare_lqg(config=CONFIGS / "five_story.yaml", out=tmp_path / "out", mpc=20).evaluation
    summary = evaluation.summary()
    assert "MPC (N = 20)" in summary.index
    assert summary.loc["MPC (N = 20)", "J1"] == pytest.approx(summary.loc["LQG + ground model", "J1"], rel=0.05)
