"""The optimal reference: full-state LQR with the ground motion known `preview` steps ahead.

With the whole record known this is the clairvoyant optimum no causal controller can pass on the
quadratic cost; with preview 0 it is full-state LQR that knows nothing of the ground.
"""

from __future__ import annotations

import numpy as np

from rlcontroller.config import RewardConfig
from rlcontroller.control.lqr import lqr_gain, preview_kernel, quadratic_cost
from rlcontroller.physics.dynamics import Response, response
from rlcontroller.physics.excitation import GroundMotion, for_control_step
from rlcontroller.physics.plant import Plant


def optimal_response(
    plant: Plant, motion: GroundMotion, reward: RewardConfig | None = None, preview: int | None = None
) -> Response:
    """Full-state LQR plus the optimal feed-forward on the next `preview` control steps of the
    ground motion (None: the whole record), forces clipped to the limits.

    With preview=None this is the clairvoyant reference: no causal controller can do better on
    the quadratic cost. preview=0 is full-state LQR that knows nothing of the ground; preview=p
    knows the ground up to p control steps ahead, the sequence between the two.
    """
    building = plant.building
    samples, substeps = for_control_step(motion, plant.control_dt)
    step = plant.step_map(substeps)
    cost = quadratic_cost(plant, reward or plant.experiment.reward, step)
    feedback, _ = lqr_gain(step, cost, building.force_limits)
    action_gain = step.force_gain * building.force_limits
    ground_terms = step.ground_terms(samples)
    n_steps = ground_terms.shape[0]
    length = n_steps if preview is None else min(preview, n_steps)
    feedforward = np.zeros((n_steps, building.n_actuators))
    for lag, kernel in enumerate(preview_kernel(cost, step, building.force_limits, length)):
        feedforward[: n_steps - lag] += ground_terms[lag:] @ kernel.T
    states = np.zeros((n_steps + 1, step.phi.shape[0]))
    actions = np.zeros((n_steps, building.n_actuators))
    for k in range(n_steps):
        actions[k] = np.clip(-feedback @ states[k] - feedforward[k], -1.0, 1.0)
        states[k + 1] = step.phi @ states[k] + action_gain @ actions[k] + ground_terms[k]
    held = np.vstack([np.zeros((1, building.n_actuators)), actions * building.force_limits])
    time = np.arange(n_steps + 1) * step.control_dt
    return response(building, states, held, time, samples[::substeps][: n_steps + 1])
