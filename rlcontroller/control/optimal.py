"""The optimal reference: full-state LQR with the ground motion known `preview` steps ahead.

With the whole record known this is the clairvoyant optimum no causal controller can pass on the
quadratic cost; with preview 0 it is full-state LQR that knows nothing of the ground.
"""

from __future__ import annotations

import numpy as np

from rlcontroller.config import RewardConfig
from rlcontroller.control.lqr import lqr_gain, preview_feedforward, quadratic_cost
from rlcontroller.physics.motions.excitation import Load, on_control_grid
from rlcontroller.physics.plant import Plant
from rlcontroller.physics.response import Response


def optimal_response(
    plant: Plant, motion: Load, reward: RewardConfig | None = None, preview: int | None = None
) -> Response:
    """Full-state LQR plus the optimal feed-forward on the next `preview` control steps of the
    ground motion (None: the whole record), forces clipped to the limits.

    With preview=None this is the clairvoyant reference: no causal controller can do better on
    the quadratic cost. preview=0 is full-state LQR that knows nothing of the ground; preview=p
    knows the ground up to p control steps ahead, the sequence between the two.
    """
    return optimal_responses(plant, [motion], reward, preview)[0]


def optimal_responses(
    plant: Plant, motions: list[Load], reward: RewardConfig | None = None, preview: int | None = None
) -> list[Response]:
    """`optimal_response` of every motion, simulated together (motions of one sampling, padded)."""
    building = plant.building
    grids = [on_control_grid(motion, plant.control_dt) for motion in motions]
    results: list[Response | None] = [None] * len(motions)
    for substeps in sorted({grid.substeps for grid in grids}):
        members = [i for i, grid in enumerate(grids) if grid.substeps == substeps]
        sampled = plant.sampled(substeps)
        step = sampled.step
        cost = quadratic_cost(plant, reward or plant.experiment.reward, step)
        feedback, _ = lqr_gain(step, cost, building.force_limits)
        action_gain = step.force_gain * building.force_limits
        terms = [step.ground_terms(grids[i].ground) for i in members]
        n_steps = max(t.shape[0] for t in terms)
        ground_terms = np.zeros((len(members), n_steps, step.phi.shape[0]))
        for row, t in enumerate(terms):
            ground_terms[row, : t.shape[0]] = t
        length = n_steps if preview is None else min(preview, n_steps)
        feedforward = preview_feedforward(cost, step, building.force_limits, ground_terms, length=length)
        states = np.zeros((n_steps + 1, len(members), step.phi.shape[0]))
        actions = np.zeros((n_steps, len(members), building.n_actuators))
        # step first
        by_step = [np.ascontiguousarray(a.transpose(1, 0, 2)) for a in (feedforward, ground_terms)]
        gain, transition, input_gain = -feedback.T, step.phi.T, action_gain.T  # formed once, not every step
        for k, (step_feedforward, step_ground) in enumerate(zip(*by_step, strict=True)):
            (states[k] @ gain - step_feedforward).clip(-1.0, 1.0, out=actions[k])
            states[k + 1] = states[k] @ transition + actions[k] @ input_gain + step_ground
        for row, (i, t) in enumerate(zip(members, terms, strict=True)):
            k = t.shape[0]
            held = np.vstack([np.zeros((1, building.n_actuators)), actions[:k, row] * building.force_limits])
            time = np.arange(k + 1) * step.control_dt
            results[i] = sampled.response(states[: k + 1, row], held, time, ground=grids[i].ground_at_steps)
    return results
