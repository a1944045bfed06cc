"""LQR on the reward's cost: the Riccati solution is the closed loop's cost-to-go (summed along a
simulated free response), and no other gain does better from the same state."""

import numpy as np
import pytest
from conftest import REPOSITORY

from rlcontroller.config import Experiment, load_experiment
from rlcontroller.control.lqr import lqr_gain, quadratic_cost
from rlcontroller.physics.plant import Plant


def cost_to_go(step, cost, gain, limits, start: np.ndarray, steps: int = 20_000) -> float:
    """The summed cost |H_z z + H_u a|^2 of the closed loop a = -K z from `start`, no ground motion."""
    z, total = start.copy(), 0.0
    for _ in range(steps):
        action = -gain @ z
        stage = cost.state @ z + cost.action @ action
        total += float(stage @ stage)
        z = step.phi @ z + (step.force_gain * limits) @ action
    return total


@pytest.mark.slow
def test_the_riccati_solution_is_the_summed_cost_of_the_closed_loop_and_the_least():
    for experiment in (
        Experiment(),
        load_experiment(REPOSITORY / "configs" / "experiments" / "five_story_every_story.yaml"),
    ):
        plant = Plant(experiment)
        step, limits = plant.sampled(1).step, plant.force_limits
        cost = quadratic_cost(plant, experiment.reward, step)
        gain, riccati = lqr_gain(step, cost, limits)
        start = np.random.default_rng(4).standard_normal(step.phi.shape[0]) * 0.01
        optimal = cost_to_go(step, cost, gain, limits, start)
        np.testing.assert_allclose(optimal, start @ riccati @ start, rtol=1e-6)
        assert np.max(np.abs(np.linalg.eigvals(step.phi - step.force_gain * limits @ gain))) < 1.0
        for scale in (0.8, 1.25):  # a detuned gain costs more from the same state
            assert cost_to_go(step, cost, scale * gain, limits, start) > optimal
