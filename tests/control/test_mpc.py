"""MPC: with loose limits its first move is LQR's; with binding limits it never leaves them and its plan
costs no more than clipped LQR's; a stroke limit is kept where it can be, and its excess paid where not; a
step the solver does not finish takes the last plan's next action, or LQR's clipped one, and is counted."""

import numpy as np
import pytest

from rlcontroller.assets import CONFIGS
from rlcontroller.config import Experiment, load_experiment
from rlcontroller.control.lqg import design_lqg_ground_model, design_lqg_wind_model
from rlcontroller.control.lqr import lqr_gain, quadratic_cost
from rlcontroller.control.mpc import TOLERANCE, mpc_design, stroke_rows
from rlcontroller.control.mpc_controllers import MPCController, SemiActiveMPC
from rlcontroller.physics.plant import Plant

PLANT = Plant(Experiment())
RNG = np.random.default_rng(7)


@pytest.fixture(scope="module")
def controller():
    return MPCController(PLANT, 20)


def solve(controller, estimate):
    return controller.planner.plan(0, estimate)


def test_with_loose_limits_the_first_move_is_lqrs(controller):
    """Estimates small enough that LQR stays inside the limits over the horizon: MPC's first move equals
    -K z to the solver's tolerance."""
    feedback = design_lqg_ground_model(PLANT).feedback
    for _ in range(5):
        estimate = 1e-4 * RNG.standard_normal(feedback.shape[1])
        np.testing.assert_allclose(solve(controller, estimate)[:3], -feedback @ estimate, atol=10 * TOLERANCE)


def test_under_wind_it_plans_on_the_wind_model_and_its_first_move_is_lqg_wind_models_lqr():
    """Under wind the estimate is LQG + wind model's (the floor forces among its states) and, with loose
    limits, the first move is that LQR's -K z; with large estimates the plan stays within the limits."""
    plant = Plant(load_experiment(CONFIGS / "experiments" / "five_story_wind.yaml")).design
    wind = MPCController(plant, 20)
    feedback = design_lqg_wind_model(plant).feedback
    assert feedback.shape[1] == plant.sampled().wind_model.phi.shape[0] == wind.problem.linear.shape[1]
    for scale, loose in ((1e-4, True), (1.0, False)):
        estimate = scale * RNG.standard_normal(feedback.shape[1])
        plan = solve(wind, estimate)
        if loose:
            np.testing.assert_allclose(plan[:5], -feedback @ estimate, atol=10 * TOLERANCE)
        else:
            assert np.all(np.abs(plan) <= 1.0 + 10 * TOLERANCE) and np.max(np.abs(-feedback @ estimate)) > 1.0


def test_with_binding_limits_the_plan_keeps_them_and_costs_no_more_than_clipped_lqr(controller):
    """Large estimates: every planned action within [-1, 1] (to the solver's tolerance, before any clip), and
    the plan's cost (the QP's objective) at most that of clipped LQR rolled out over the same horizon."""
    step = PLANT.sampled().ground_model
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
    controller.planner._solver(1)
    for solver in controller.planner._solvers:
        solver.update_settings(max_iter=1)
    actions = controller.act(observation)
    assert controller.fallbacks == 2
    np.testing.assert_array_equal(
        actions, (controller.estimator._state @ controller.estimator.output).clip(-1.0, 1.0)
    )


def test_the_problem_is_built_from_the_riccati_solution_it_ends_with():
    """N = 1: the QP's Hessian is 2 (H_u' H_u + B' P B), the LQR curvature of the last step."""
    step = PLANT.sampled().ground_model
    cost = quadratic_cost(PLANT, PLANT.experiment.reward, step)
    _, riccati = lqr_gain(step, cost, PLANT.force_limits)
    action_gain = step.force_gain * PLANT.force_limits
    problem = mpc_design(PLANT, 1).problem()
    expected = 2 * (cost.action.T @ cost.action + action_gain.T @ riccati @ action_gain)
    np.testing.assert_allclose(problem.hessian, expected, rtol=1e-10)


@pytest.mark.slow
def test_compare_lqg_gains_an_mpc_row(tmp_path):
    """On the synthetic suite MPC ties LQG + ground model's J1 (its filter, its cost) within 5 %."""
    from rlcontroller import api

    evaluation = api.compare_lqg(config=CONFIGS / "five_story.yaml", out=tmp_path / "out", mpc=20).evaluation
    summary = evaluation.summary()
    assert "MPC (N = 20)" in summary.index
    assert summary.loc["MPC (N = 20)", "J1"] == pytest.approx(
        summary.loc["LQG + ground model", "J1"], rel=0.05
    )


@pytest.mark.slow
def test_under_strong_wind_mpc_is_ahead_of_lqg_wind_model_which_clips(tmp_path):
    """The five-story building's wind loads (35 m/s ones drive LQG + wind model into its 100 kN limits on 2-3
    % of the steps): MPC on the wind model, planning around the limits, has the lower drift and floor
    acceleration (measured: J1 + J2 0.582 against 0.614)."""
    from rlcontroller import api

    evaluation = api.compare_lqg(
        config=CONFIGS / "experiments" / "five_story_wind.yaml",
        judging=api.Judging(records=CONFIGS / "loads" / "wind.yaml"),
        out=tmp_path / "out",
        mpc=20,
    ).evaluation
    summary = evaluation.summary()
    mpc, lqg = (
        summary.loc[name, "J1"] + summary.loc[name, "J2"] for name in ("MPC (N = 20)", "LQG + wind model")
    )
    assert mpc < 0.97 * lqg


AMD = Plant(load_experiment(CONFIGS / "experiments" / "five_story_amd.yaml"))


def predicted_strokes(problem, plant, estimate, plan):
    """The plan's strokes / limits at z_1..z_N, through the design model's step map."""
    step = plant.sampled().ground_model
    rows = stroke_rows(plant, estimate.size)
    actions = plan[: problem.horizon * problem.actions].reshape(problem.horizon, problem.actions)
    state, strokes = estimate, []
    for action in actions:
        state = step.phi @ state + step.force_gain * plant.force_limits @ action
        strokes.append(rows @ state)
    return np.array(strokes)


@pytest.mark.parametrize(
    ("stroke", "velocity", "within_reach"),
    [(0.5, 5.0, True), (0.6, 4.5, True), (0.5, 6.0, False), (0.8, 5.0, False)],
)
def test_a_plan_keeps_the_stroke_limit_where_it_can_and_pays_for_what_it_cannot(
    stroke, velocity, within_reach
):
    """The roof driver (10 kN, 1 m), its mass `stroke` (m) out and moving outward at `velocity` (m/s), the
    building at rest: clipped LQR overshoots the limit; MPC's plan keeps every predicted stroke within it with
    zero slack where it can (`within_reach`: the price is an exact penalty), and elsewhere its slack is
    exactly what its strokes exceed the limit by; its actions stay within the force limit."""
    design = AMD.design
    controller = MPCController(design, 20)
    problem = controller.problem
    feedback = design_lqg_ground_model(design).feedback
    step = design.sampled().ground_model
    rows = stroke_rows(design, feedback.shape[1])
    n_floors, n_dofs = design.building.n_floors, design.building.n_dofs
    estimate = np.zeros(feedback.shape[1])
    estimate[n_floors], estimate[n_dofs + n_floors] = stroke, velocity
    state, lqr_peak = estimate, 0.0
    for _ in range(problem.horizon):
        state = step.phi @ state + step.force_gain * design.force_limits @ np.clip(-feedback @ state, -1, 1)
        lqr_peak = max(lqr_peak, float(np.max(np.abs(rows @ state))))
    assert lqr_peak > 1.0
    plan = controller.planner.plan(0, estimate)
    actions, slack = plan[: problem.horizon], plan[problem.horizon :]
    assert np.all(np.abs(actions) <= 1.0 + 10 * TOLERANCE)
    strokes = np.abs(predicted_strokes(problem, design, estimate, plan)).ravel()
    np.testing.assert_allclose(slack, np.maximum(strokes - 1.0, 0.0), atol=1e-4)
    assert (np.max(slack) < 1e-4) == within_reach


def test_a_step_the_solver_does_not_finish_takes_the_last_plans_next_action():
    controller = MPCController(PLANT, 20)
    observations = 0.5 * RNG.standard_normal((3, 1, PLANT.layout.size))
    controller.act(observations[0])
    planned = controller.planner._plans[0][0]
    controller.planner._solver(0).update_settings(max_iter=1)
    np.testing.assert_array_equal(controller.act(observations[1])[0], planned[1])
    assert controller.fallbacks == 1
    controller.reset()  # a new record: new solvers, no plan to fall back on
    assert controller.planner._solvers == [] and controller.planner._plans == {}


MR = Plant(load_experiment(CONFIGS / "experiments" / "five_story_mr.yaml"))


def test_a_damper_plan_only_asks_for_forces_that_oppose_the_dampers_velocity():
    """MR dampers on stories 1, 3, 5: from estimates where LQR's demand would push a damper along its velocity
    (what no damper can do), MPC's planned forces all oppose their steps' predicted velocities (the product of
    force and velocity, the damper's power, is never positive) and stay within the capacity."""
    controller = SemiActiveMPC(MR.design, 20)
    problem = controller.problem
    feedback = controller.estimator.design.feedback
    pushing = 0
    for _ in range(10):
        estimate = 0.02 * RNG.standard_normal(feedback.shape[1])
        velocity = controller.velocity_free[: problem.actions] @ estimate
        pushing += int(np.any(-feedback @ estimate * velocity > 1e-9))
        controller.planner.reset()
        plan = controller.planner.plan(0, estimate, controller.action_bounds(0, estimate))
        actions = plan[: problem.horizon * problem.actions]
        velocities = controller.velocity_free @ estimate + controller.velocity_forced @ np.zeros_like(actions)
        assert np.all(actions * velocities <= 10 * TOLERANCE)
        assert np.all(np.abs(actions) <= 1.0 + 10 * TOLERANCE)
    assert pushing  # LQR's demand is not passive in some of them


def test_a_variable_dampers_reach_grows_with_its_velocity():
    """An ideal variable damper (c up to 2e6 N*s/m, capacity 1e5 N): its bound is c_max |v| / capacity, at
    most 1."""
    experiment = load_experiment(CONFIGS / "experiments" / "five_story_mr.yaml")
    devices = [
        {"type": "variable_damper", "story": 1, "damping_min": 1e4, "damping_max": 2e6, "capacity": 1e5},
    ]
    plant = Plant(experiment.model_validate(experiment.model_dump() | {"devices": devices}))
    controller = SemiActiveMPC(plant.design, 5)
    estimate = 0.01 * RNG.standard_normal(controller.velocity_free.shape[1])
    velocity = controller.velocity_free @ estimate
    lower, upper = controller.action_bounds(0, estimate)
    np.testing.assert_allclose(upper - lower, np.minimum(1.0, 20.0 * np.abs(velocity)))
    assert np.all((velocity > 0) <= (upper == 0.0)) and np.all((velocity <= 0) <= (lower == 0.0))
