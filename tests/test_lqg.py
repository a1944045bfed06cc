import numpy as np
import pytest
import scipy.linalg

from rlcontroller.config import Experiment, MeasurementConfig, SensorConfig
from rlcontroller.controllers import Uncontrolled, rollout
from rlcontroller.dynamics import Response
from rlcontroller.env import BuildingEnv
from rlcontroller.excitation import GroundMotion, read_at2, scale_to_pga
from rlcontroller.lqg import LQGController, design_lqg, lqr_gain, optimal_response, quadratic_cost
from rlcontroller.metrics import j_metrics

NOISE_FREE = Experiment(
    sensors=SensorConfig(
        measurements=[MeasurementConfig(quantity="absolute_acceleration", scale=5.0)], ground_noise_std=0.0
    )
)


def episode_cost(result: Response, experiment: Experiment) -> float:
    """The quadratic cost (minus the reward) summed over the record, from the response."""
    total = 0.0
    for term in experiment.reward.terms:
        values = result.quantity(term.quantity)[1:]
        total += term.weight * np.sum((values / term.scale) ** 2)
    return float(total)


@pytest.mark.parametrize("known_ground", [False, True])
def test_closed_loop_is_stable(known_ground):
    design = design_lqg(Experiment(), known_ground=known_ground)
    assert np.max(np.abs(design.closed_loop_eigenvalues())) < 1.0
    kalman = design.filter
    estimator = kalman.phi - kalman.gain @ kalman.sensor_c @ kalman.phi
    assert np.max(np.abs(np.linalg.eigvals(estimator))) < 1.0


def test_gain_matches_an_independent_riccati_solution():
    experiment = Experiment()
    env = BuildingEnv(experiment)
    step = env.step_map(1)
    cost = quadratic_cost(env.building, experiment.reward, step)
    gain, _ = lqr_gain(step, cost, env.force_limits)
    a, b = step.phi, step.force_gain * env.force_limits
    q, r, n = cost.state.T @ cost.state, cost.action.T @ cost.action, cost.state.T @ cost.action
    p = scipy.linalg.solve_discrete_are(a, b, q, r, s=n)
    np.testing.assert_allclose(gain, np.linalg.solve(r + b.T @ p @ b, b.T @ p @ a + n.T), rtol=1e-6, atol=1e-9)


def test_the_lqr_cost_is_exactly_the_reward():
    experiment = Experiment()
    env = BuildingEnv(experiment)
    motion = GroundMotion("m", 0.02, np.random.default_rng(0).normal(0, 2.0, 60))
    env.reset(seed=0, options={"motion": motion})
    step = env.step_map(1)
    cost = quadratic_cost(env.building, experiment.reward, step)
    ground_terms = step.ground_terms(motion.acceleration)
    rng = np.random.default_rng(1)
    for k in range(30):
        state = env.state
        action = rng.uniform(-1, 1, 3)
        _, reward, _, _, _ = env.step(action)
        residual = cost.state @ state + cost.action @ action + cost.ground @ ground_terms[k]
        assert -reward == pytest.approx(float(residual @ residual), rel=1e-9)


def test_kalman_estimate_converges_on_a_noise_free_free_vibration():
    kalman = design_lqg(NOISE_FREE).filter
    state = np.concatenate([np.linspace(0.02, 0.06, 5), np.zeros(5)])
    errors = []
    for _ in range(300):
        state = kalman.phi @ state
        estimate = kalman.update(kalman.sensor_c @ state, np.zeros(3), 0.0)
        errors.append(np.linalg.norm(estimate - state) / np.linalg.norm(state))
    assert errors[-1] < 1e-3 * errors[0] and errors[-1] < 1e-4


def test_lqg_reduces_drift_on_a_record_without_saturating(records):
    motion = scale_to_pga(read_at2(records / "RSN1086_NORTHR_SYL090.AT2"), 0.5)  # small: forces stay below 100 kN
    env = BuildingEnv(Experiment())
    bare, _ = rollout(env, motion, Uncontrolled(3))
    controlled, _ = rollout(env, motion, LQGController(design_lqg(Experiment()), env))
    assert np.max(np.abs(controlled.force)) < 0.99e5
    metrics = j_metrics(controlled, bare)
    assert np.mean(metrics["J1"]) < 0.7 and np.all(metrics["J1"] < 1.0)


def test_optimal_reference_beats_lqg_and_the_bare_building_on_the_cost(records):
    experiment = Experiment()
    motion = scale_to_pga(read_at2(records / "RSN1086_NORTHR_SYL090.AT2"), 0.5)
    env = BuildingEnv(NOISE_FREE)
    optimal = optimal_response(experiment, motion)
    assert np.max(np.abs(optimal.force)) < 1e5
    lqg, _ = rollout(env, motion, LQGController(design_lqg(NOISE_FREE, known_ground=True), env))
    bare, _ = rollout(env, motion, Uncontrolled(3))
    assert episode_cost(optimal, experiment) < episode_cost(lqg, experiment) < episode_cost(bare, experiment)


def test_forces_respect_the_limits(records):
    motion = read_at2(records / "RSN1106_KOBE_KJM000.AT2")  # strong: LQG saturates
    env = BuildingEnv(Experiment())
    controlled, _ = rollout(env, motion, LQGController(design_lqg(Experiment()), env))
    assert np.max(np.abs(controlled.force)) == pytest.approx(1e5)
    assert np.max(np.abs(optimal_response(Experiment(), motion).force)) <= 1e5 + 1e-6


def test_a_reward_that_leaves_forces_free_is_refused():
    experiment = Experiment(reward={"terms": [{"quantity": "base_shear", "weight": 1.0, "scale": 1e5}]})  # rank 1 < 3
    with pytest.raises(ValueError, match="R is singular"):
        design_lqg(experiment)


def test_lqg_keeps_only_the_quadratic_terms_of_linear_quantities():
    base = Experiment()
    extended = Experiment(
        reward={
            "terms": [t.model_dump() for t in base.reward.terms]
            + [
                {"quantity": "drift", "weight": 5.0, "scale": 0.02, "power": 6},
                {"quantity": "force_change", "weight": 1.0, "scale": 1e4},
            ]
        }
    )
    np.testing.assert_allclose(design_lqg(extended).feedback, design_lqg(base).feedback)


def test_a_zero_residual_on_the_lqg_prior_is_lqg_with_ground():
    from rlcontroller.controllers import PolicyController
    from rlcontroller.lqg import LQGPrior

    class ZeroPolicy:
        def predict(self, observation, deterministic=True):
            return np.zeros(3), None

    experiment = Experiment(sensors={"state_estimate": True}, algorithm={"residual_lqg": True})
    env = BuildingEnv(experiment)
    motion = read_at2_or_synthetic()
    residual, _ = rollout(env, motion, PolicyController(ZeroPolicy(), env.force_limits, prior=LQGPrior(experiment)))
    lqg, _ = rollout(env, motion, LQGController(design_lqg(experiment, known_ground=True), env))
    np.testing.assert_allclose(residual.force, lqg.force, rtol=1e-3, atol=1.0)


def read_at2_or_synthetic() -> GroundMotion:
    from rlcontroller.evaluation import synthetic_suite

    return synthetic_suite(count=1)[0]


def test_residual_needs_the_state_estimate():
    from rlcontroller.config import ConfigError, build_experiment

    with pytest.raises(ConfigError, match="residual_lqg: needs sensors.state_estimate"):
        build_experiment({"algorithm": {"residual_lqg": True}})
