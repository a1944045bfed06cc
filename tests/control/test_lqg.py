import numpy as np
import pytest
import scipy.linalg

from rlcontroller.config import Experiment, KanaiTajimiConfig, MeasurementConfig, SensorConfig
from rlcontroller.control.controllers import LQGController, LQGPrior, Uncontrolled
from rlcontroller.control.lqg import design_lqg, design_lqg_ground_model
from rlcontroller.control.lqr import lqr_gain, preview_feedforward, preview_kernel, quadratic_cost
from rlcontroller.control.optimal import optimal_response
from rlcontroller.control.policy_controller import PolicyController
from rlcontroller.learning.env import BuildingEnv, rollout
from rlcontroller.physics.dynamics import step_map
from rlcontroller.physics.metrics import j_metrics
from rlcontroller.physics.motions.excitation import Load, read_at2, scale_to_pga
from rlcontroller.physics.motions.generators import GroundModel, kanai_tajimi
from rlcontroller.physics.plant import Plant
from rlcontroller.physics.response import Response
from rlcontroller.physics.structure import build

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
    design = design_lqg(Plant(Experiment()), known_ground=known_ground)
    assert np.max(np.abs(design.closed_loop_eigenvalues())) < 1.0
    kalman = design.filter
    estimator = kalman.phi - kalman.gain @ kalman.sensor_c @ kalman.phi
    assert np.max(np.abs(np.linalg.eigvals(estimator))) < 1.0


def test_gain_matches_an_independent_riccati_solution():
    experiment = Experiment()
    env = BuildingEnv(experiment)
    step = env.plant.sampled(1).step
    cost = quadratic_cost(env.plant, experiment.reward, step)
    gain, _ = lqr_gain(step, cost, env.force_limits)
    a, b = step.phi, step.force_gain * env.force_limits
    q, r, n = cost.state.T @ cost.state, cost.action.T @ cost.action, cost.state.T @ cost.action
    p = scipy.linalg.solve_discrete_are(a, b, q, r, s=n)
    np.testing.assert_allclose(
        gain, np.linalg.solve(r + b.T @ p @ b, b.T @ p @ a + n.T), rtol=1e-6, atol=1e-9
    )


def test_the_lqr_cost_is_exactly_the_reward():
    experiment = Experiment()
    env = BuildingEnv(experiment)
    motion = Load("m", 0.02, np.random.default_rng(0).normal(0, 2.0, 60))
    env.reset(seed=0, options={"motion": motion})
    step = env.plant.sampled(1).step
    cost = quadratic_cost(env.plant, experiment.reward, step)
    ground_terms = step.ground_terms(motion.acceleration)
    rng = np.random.default_rng(1)
    for k in range(30):
        state = env.state
        action = rng.uniform(-1, 1, 3)
        _, reward, _, _, _ = env.step(action)
        residual = cost.state @ state + cost.action @ action + cost.ground @ ground_terms[k]
        assert -reward == pytest.approx(float(residual @ residual), rel=1e-9)


def test_kalman_estimate_converges_on_a_noise_free_free_vibration():
    kalman = design_lqg(Plant(NOISE_FREE)).filter
    state = np.concatenate([np.linspace(0.02, 0.06, 5), np.zeros(5)])
    errors, estimate = [], np.zeros(kalman.size)
    for _ in range(300):
        state = kalman.phi @ state
        estimate = kalman.update(
            estimate, kalman.sensor_c @ state, held_action=np.zeros(3), ground=0.0, previous_ground=0.0
        )
        errors.append(np.linalg.norm(estimate - state) / np.linalg.norm(state))
    assert errors[-1] < 1e-3 * errors[0] and errors[-1] < 1e-4


def test_lqg_reduces_drift_on_a_record_without_saturating(records):
    # small: forces stay below 100 kN
    motion = scale_to_pga(read_at2(records / "RSN1086_NORTHR_SYL090.AT2"), 0.5)
    env = BuildingEnv(Experiment())
    bare, _ = rollout(env, motion, Uncontrolled(3))
    controlled, _ = rollout(env, motion, LQGController(design_lqg(Plant(Experiment())), env.plant))
    assert np.max(np.abs(controlled.force)) < 0.99e5
    metrics = j_metrics(controlled, bare)
    assert np.mean(metrics["J1"]) < 0.7 and np.all(metrics["J1"] < 1.0)


def test_optimal_reference_beats_lqg_and_the_bare_building_on_the_cost(records):
    experiment = Experiment()
    motion = scale_to_pga(read_at2(records / "RSN1086_NORTHR_SYL090.AT2"), 0.5)
    env = BuildingEnv(NOISE_FREE)
    optimal = optimal_response(Plant(experiment), motion)
    assert np.max(np.abs(optimal.force)) < 1e5
    lqg, _ = rollout(env, motion, LQGController(design_lqg(Plant(NOISE_FREE), known_ground=True), env.plant))
    bare, _ = rollout(env, motion, Uncontrolled(3))
    assert episode_cost(optimal, experiment) < episode_cost(lqg, experiment) < episode_cost(bare, experiment)


def test_forces_respect_the_limits(records):
    motion = read_at2(records / "RSN1106_KOBE_KJM000.AT2")  # strong: LQG saturates
    env = BuildingEnv(Experiment())
    controlled, _ = rollout(env, motion, LQGController(design_lqg(Plant(Experiment())), env.plant))
    assert np.max(np.abs(controlled.force)) == pytest.approx(1e5)
    assert np.max(np.abs(optimal_response(Plant(Experiment()), motion).force)) <= 1e5 + 1e-6


def test_a_reward_that_leaves_forces_free_is_refused():
    # rank 1 < 3
    experiment = Experiment(reward={"terms": [{"quantity": "base_shear", "weight": 1.0, "scale": 1e5}]})
    with pytest.raises(ValueError, match="R is singular"):
        design_lqg(Plant(experiment))


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
    np.testing.assert_allclose(design_lqg(Plant(extended)).feedback, design_lqg(Plant(base)).feedback)


class ZeroActor:
    """A network whose action is zero for any observation."""

    def __call__(self, observation):
        return np.zeros(np.shape(observation)[:-1] + (3,))


@pytest.mark.parametrize("ground_model", [False, True])
def test_a_zero_residual_on_the_lqg_prior_is_the_matching_lqg(ground_model):
    sensors = {"state_estimate": True, "ground_model": ground_model}
    experiment = Experiment(sensors=sensors, algorithm={"residual_lqg": True})
    env = BuildingEnv(experiment)
    motion = read_at2_or_synthetic()
    residual, _ = rollout(
        env, motion, PolicyController(ZeroActor(), prior=LQGPrior.design(Plant(experiment)))
    )
    design = (
        design_lqg_ground_model(Plant(experiment))
        if ground_model
        else design_lqg(Plant(experiment), known_ground=True)
    )
    lqg, _ = rollout(env, motion, LQGController(design, env.plant))
    np.testing.assert_allclose(residual.force, lqg.force, rtol=1e-3, atol=1.0)
    assert np.abs(lqg.force).max() > 1e4


def read_at2_or_synthetic() -> Load:
    from rlcontroller.physics.motions.records import synthetic_suite

    return synthetic_suite(count=1)[0]


def test_residual_needs_the_state_estimate():
    from rlcontroller.config import ConfigError, build_experiment

    with pytest.raises(ConfigError, match="residual_lqg: needs sensors.state_estimate"):
        build_experiment({"algorithm": {"residual_lqg": True}})
    with pytest.raises(ConfigError, match="ground_model: needs sensors.state_estimate"):
        build_experiment({"sensors": {"ground_model": True}})


def weak_motion(steps: int, seed: int = 3) -> Load:
    """Small enough that no force reaches its limit, so the optimal control is the unclipped one."""
    return Load("weak", 0.02, 0.05 * np.random.default_rng(seed).standard_normal(steps + 1))


def test_clairvoyant_actions_solve_the_finite_least_squares_problem():
    """Independent check of the preview kernel: with the whole record known, the optimal actions
    minimise sum_k |H_z z_k + H_u a_k + F C_r g_k|^2 + z_n' P z_n (the stationary tail), a linear
    least-squares problem in the stacked actions solved here by brute force."""
    experiment, motion = Experiment(), weak_motion(60)
    building = build(experiment.building, experiment.actuators)
    step = step_map(building, experiment.simulation)
    cost = quadratic_cost(Plant(experiment), experiment.reward, step)
    _, riccati = lqr_gain(step, cost, building.force_limits)
    action_gain = step.force_gain * building.force_limits
    ground = step.ground_terms(motion.acceleration)
    n, m, size = ground.shape[0], building.n_actuators, step.phi.shape[0]
    tail = np.linalg.cholesky(riccati).T  # z' P z = |tail z|^2

    def residuals(actions: np.ndarray) -> np.ndarray:
        state, rows = np.zeros(size), []
        for k in range(n):
            rows.append(cost.state @ state + cost.action @ actions[k] + cost.ground @ ground[k])
            state = step.phi @ state + action_gain @ actions[k] + ground[k]
        return np.concatenate(rows + [tail @ state])

    offset = residuals(np.zeros((n, m)))
    columns = [residuals(np.eye(n * m)[i].reshape(n, m)) - offset for i in range(n * m)]
    best = np.linalg.lstsq(np.array(columns).T, -offset, rcond=None)[0].reshape(n, m)
    optimal = optimal_response(Plant(experiment), motion)
    assert np.max(np.abs(optimal.force)) < 0.5e5
    np.testing.assert_allclose(optimal.force[1:], best * building.force_limits, rtol=1e-6, atol=1e-6 * 1e5)


def test_more_preview_never_costs_more_and_zero_preview_is_full_state_lqr():
    experiment, motion = Experiment(), weak_motion(400)
    costs = [
        episode_cost(optimal_response(Plant(experiment), motion, preview=p), experiment)
        for p in (0, 1, 5, 25, None)
    ]
    assert costs == sorted(costs, reverse=True) and len(set(costs)) == len(costs)
    assert optimal_response(Plant(experiment), motion, preview=10_000).force == pytest.approx(
        optimal_response(Plant(experiment), motion).force
    )
    building = build(experiment.building, experiment.actuators)
    step = step_map(building, experiment.simulation)
    feedback, _ = lqr_gain(
        step, quadratic_cost(Plant(experiment), experiment.reward, step), building.force_limits
    )
    blind = optimal_response(Plant(experiment), motion, preview=0)
    actions = -np.hstack([blind.displacement, blind.velocity]) @ feedback.T
    np.testing.assert_allclose(blind.force[1:], actions[:-1] * building.force_limits, atol=1e-6)


def test_ground_model_keeps_the_building_gain_and_is_stable():
    """The ground filter's states are uncontrollable and not driven by the building, so the optimal
    feedback on the building state is plain LQR's; the ground model only adds a feed-forward."""
    experiment = Experiment()
    design = design_lqg_ground_model(Plant(experiment))
    np.testing.assert_allclose(
        design.feedback[:, :10], design_lqg(Plant(experiment)).feedback, rtol=1e-6, atol=1e-9
    )
    assert np.abs(design.feedback[:, 10:]).max() > 1e-3
    assert np.max(np.abs(design.closed_loop_eigenvalues())) < 1.0
    kalman = design.filter
    assert np.max(np.abs(np.linalg.eigvals(kalman.phi - kalman.gain @ kalman.sensor_c @ kalman.phi))) < 1.0


@pytest.mark.slow
def test_ground_model_lqg_wins_on_the_motions_it_models():
    """On stationary Kanai-Tajimi ground motion with the model's own parameters, weak enough that no
    force saturates, the LQG that predicts the ground has the better reward of the three LQGs."""
    model = GroundModel()
    fixed = (model.frequency, model.frequency), (model.damping, model.damping)
    generator = KanaiTajimiConfig(
        duration=(120.0, 120.0),
        ground_frequency=fixed[0],
        ground_damping=fixed[1],
        pga=(0.3, 0.3),
        rise_time=(0.1, 0.1),
        strong_duration=(200.0, 200.0),
    )
    motion = kanai_tajimi(generator, np.random.default_rng(5))
    env = BuildingEnv(NOISE_FREE)
    designs = {
        "plain": design_lqg(Plant(NOISE_FREE)),
        "ground": design_lqg(Plant(NOISE_FREE), known_ground=True),
        "model": design_lqg_ground_model(Plant(NOISE_FREE)),
    }
    rewards = {}
    for name, design in designs.items():
        result, rewards[name] = rollout(env, motion, LQGController(design, env.plant))
        assert np.max(np.abs(result.force)) < 0.9e5
    assert rewards["model"] > rewards["ground"] > rewards["plain"]


@pytest.mark.parametrize("length", [1, 2, 7, 40, 60])
def test_the_backward_feedforward_equals_the_kernel_sum(length):
    """sum_{j < length} W_j g_{k+j} from the explicit kernels, for a batch of two ground histories."""
    plant = Plant(Experiment())
    step = plant.sampled(1).step
    cost = quadratic_cost(plant, plant.experiment.reward, step)
    terms = np.random.default_rng(4).standard_normal((2, 60, step.phi.shape[0])) * 1e-3
    kernels = preview_kernel(cost, step, plant.force_limits, length)
    expected = np.zeros((2, 60, 3))
    for lag, kernel in enumerate(kernels):
        expected[:, : 60 - lag] += terms[:, lag:] @ kernel.T
    actual = preview_feedforward(cost, step, plant.force_limits, terms, length=length)
    np.testing.assert_allclose(actual, expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max())
