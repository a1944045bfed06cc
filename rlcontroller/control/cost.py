"""The cost every controller is judged by, as output rows: the reward terms of an experiment on the
plant's linear outputs. LQR minimises it (`lqr.quadratic_cost`), the simulator pays it out as the
reward (`simulation.outputs`)."""

from __future__ import annotations

import numpy as np

from rlcontroller.config import RewardTerm
from rlcontroller.physics.plant import Plant


def reward_matrices(
    plant: Plant, terms: list[RewardTerm]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[slice]]:
    """(C, D, weight^(1/power)/scale per row, one slice of rows per term) for terms on linear outputs,
    so that a term's value is the sum over its rows of |factor * (C x + D u)|^power."""
    building = plant.building
    rows_c, rows_d, factors, slices = [], [], [], []
    start = 0
    for term in terms:
        c, d = plant.outputs(term.quantity)
        rows_c.append(c)
        rows_d.append(d)
        factors.append(np.full(c.shape[0], term.weight ** (1.0 / term.power) / term.scale))
        slices.append(slice(start, start + c.shape[0]))
        start += c.shape[0]
    if not terms:
        return np.zeros((0, plant.n_state)), np.zeros((0, building.n_actuators)), np.zeros(0), []
    return np.vstack(rows_c), np.vstack(rows_d), np.concatenate(factors), slices
