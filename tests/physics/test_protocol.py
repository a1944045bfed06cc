"""The plant protocol: a plant from outside -- here the linear building stepped by an independent solver
(scipy's solve_ivp) instead of the exact discrete map -- implements `SimulatedPlant` and runs through the
env, the batch and the evaluation with nothing else changed, and gives the built-in plant's responses."""

from dataclasses import replace

import numpy as np
import pytest
from conftest import SAME_PHYSICS
from scipy.integrate import solve_ivp

from rlcontroller.config import Experiment
from rlcontroller.control.controllers import LQGController
from rlcontroller.control.lqg import design_lqg
from rlcontroller.evaluation.evaluation import compare
from rlcontroller.learning.env import BuildingEnv, rollout
from rlcontroller.physics.motions.excitation import FLOOR_FORCES, GROUND_ACCELERATION, Load
from rlcontroller.physics.motions.records import synthetic_suite
from rlcontroller.physics.plant import Plant
from rlcontroller.physics.protocol import Integrator, SimulatedPlant
from rlcontroller.simulation.rollout import batch_rollout


class SolveIvpStep:
    """The shear building's equations of motion over one control step, integrated by solve_ivp (RK45,
    tight tolerances): the force held, the ground linear between its samples."""

    def __init__(self, plant: Plant) -> None:
        building = plant.building
        self.n = building.n_dofs
        self.mass_inverse = np.linalg.inv(building.mass)
        self.damping, self.stiffness = building.damping, building.stiffness
        self.floor_gain = building.actuator_matrix * building.force_limits

    def step(self, state, action, ground, control_dt):
        n, force = self.n, self.floor_gain @ action
        times = np.linspace(0.0, control_dt, ground.size)

        def derivative(t, z):
            x, v = z[:n], z[n:]
            a_g = np.interp(t, times, ground)
            return np.concatenate(
                [v, self.mass_inverse @ (force - self.damping @ v - self.stiffness @ x) - a_g]
            )

        solution = solve_ivp(derivative, (0.0, control_dt), state, rtol=1e-10, atol=1e-13, method="DOP853")
        return solution.y[:, -1]


class OutsidePlant(Plant):
    """The experiment's plant with its step replaced by `SolveIvpStep`: what a model from outside does."""

    def __init__(self, experiment: Experiment) -> None:
        super().__init__(experiment)
        self.integrator = SolveIvpStep(self)


@pytest.fixture(scope="module")
def plants():
    experiment = Experiment()
    return Plant(experiment), OutsidePlant(experiment)


@pytest.fixture(scope="module")
def short_motions():
    return [replace(m, acceleration=m.acceleration[:301]) for m in synthetic_suite(2)]  # 6 s at 0.02 s


def test_the_plants_rlc_builds_and_the_outside_one_implement_the_protocol(plants):
    built, outside = plants
    assert isinstance(built, SimulatedPlant) and isinstance(outside, SimulatedPlant)
    assert isinstance(outside.integrator, Integrator)
    assert built.cannot_take(GROUND_ACCELERATION) is None and outside.cannot_take(GROUND_ACCELERATION) is None
    assert built.cannot_take(FLOOR_FORCES) is None
    assert outside.cannot_take(FLOOR_FORCES) == (
        "floor loads (wind) on a building with yielding stories or semi-active dampers are not modelled"
    )


@pytest.mark.slow
def test_an_outside_plant_gives_the_built_in_responses_through_env_and_batch(plants, short_motions):
    built, outside = plants
    lqg = LQGController(design_lqg(built.design), built.design)  # designed on the design model, as always
    reference = batch_rollout(built, short_motions, [lqg])[0]
    batched = batch_rollout(outside, short_motions, [lqg])[0]
    env_run = rollout(BuildingEnv(outside), short_motions[0], lqg, seed=0)
    for (expected, reward), (got, got_reward) in zip(reference, batched, strict=True):
        for quantity in ("drift", "absolute_acceleration", "story_shear", "force"):
            peak = np.abs(expected.quantity(quantity)).max()
            np.testing.assert_allclose(
                got.quantity(quantity), expected.quantity(quantity), atol=SAME_PHYSICS * peak
            )
        assert got_reward == pytest.approx(reward, rel=SAME_PHYSICS)
    np.testing.assert_allclose(
        env_run[0].drift, batched[0][0].drift, atol=1e-9 * np.abs(batched[0][0].drift).max()
    )


@pytest.mark.slow
def test_an_outside_plant_is_evaluated_like_any_other(plants, short_motions):
    built, outside = plants
    expected = compare(built, short_motions, "two motions").metrics
    got = compare(outside, short_motions, "two motions").metrics
    shared = sorted(set(got["controller"]) & set(expected["controller"]))
    assert {"uncontrolled", "LQG", "LQG + ground model"} <= set(shared)  # no clairvoyant optimum: no step map
    key = ["controller", "record", "metric", "index"]
    merged = got.merge(expected, on=key, suffixes=("_outside", "_built"))
    merged = merged[merged["controller"].isin(shared)]
    assert len(merged) > 100
    np.testing.assert_allclose(merged["value_outside"], merged["value_built"], rtol=SAME_PHYSICS)


def test_a_load_has_one_of_two_kinds():
    ground = Load("g", 0.01, np.array([0.0, 1.0, 0.0]))
    wind = Load("w", 0.01, np.zeros(3), floor_forces=np.ones((3, 5)))
    assert (ground.kind, wind.kind) == (GROUND_ACCELERATION, FLOOR_FORCES)
