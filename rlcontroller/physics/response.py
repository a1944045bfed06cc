"""A plant's time histories at its control steps (SI units), and the one function that makes them from states.

Every consumer (the batch, the env, evaluation, the FE loop) simulates states; `response` turns states, the
forces held over each step and the floor forces into every quantity the tables and the standard read, through
the plant's output matrices (C, D on the state): outputs at t_k use the force held over the step ending at
t_k.
"""

from __future__ import annotations

import typing
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from rlcontroller.config import Quantity

QUANTITIES: tuple[str, ...] = typing.get_args(Quantity)


@dataclass(frozen=True)
class Response:
    """Time histories at the control-step boundaries t_k = k dt, k = 0..K (SI units).

    `force` row k is the force held over the step ending at t_k (row 0 is zero); the force
    applied over [t_k, t_{k+1}) is row k + 1.
    """

    time: np.ndarray
    ground: np.ndarray
    displacement: np.ndarray
    velocity: np.ndarray
    drift: np.ndarray
    absolute_acceleration: np.ndarray
    story_shear: np.ndarray
    base_shear: np.ndarray
    force: np.ndarray
    hysteretic_force: np.ndarray | None = None  # yielding stories: (1 - a) k d_y z per story (N)
    stroke: np.ndarray | None = None  # mass devices: displacement relative to the floor (m)
    stroke_velocity: np.ndarray | None = None  # mass devices (m/s)
    device_velocity: np.ndarray | None = None  # across each commanded device (m/s): power = force x this
    connections: np.ndarray | None = None  # FE member ends, when recorded (`physics.fe.connections`)
    stop_force: np.ndarray | None = None  # end-stops, per mass device: the largest |force| over each step (N)
    stop_contacts: np.ndarray | None = None  # end-stops, per mass device: the contacts begun in each step

    def quantity(self, name: str) -> np.ndarray:
        return getattr(self, name)


RESPONSE_QUANTITIES = (*(q for q in QUANTITIES if q != "base_shear"), "stroke_velocity", "device_velocity")


def response(
    outputs: Callable[[str], tuple[np.ndarray, np.ndarray]],
    load_outputs: Callable[[str], np.ndarray],
    states: np.ndarray,
    held_forces: np.ndarray,
    *,
    time: np.ndarray,
    ground: np.ndarray,
    floor_forces: np.ndarray | None = None,
    story_force_map: np.ndarray | None = None,
) -> Response:
    """Every time history from states x (K+1, size), the forces (N) held just before each instant (K+1, m)
    and the floor forces (N) at each instant (K+1, floors), if any, through `outputs(quantity)` = (C, D) on
    x and `load_outputs(quantity)` (how floor forces enter it); with `story_force_map` (n, n: the stories'
    shear carried by the hysteretic parts from z, x = [x; v; z]) also the story hysteretic forces (N)."""
    values = {}
    for quantity in RESPONSE_QUANTITIES:
        c, d = outputs(quantity)
        values[quantity] = states @ c.T + held_forces @ d.T
        if floor_forces is not None:
            values[quantity] += floor_forces @ load_outputs(quantity).T
    c, d = outputs("base_shear")
    values["base_shear"] = (states @ c.T + held_forces @ d.T)[:, 0]
    if story_force_map is not None:
        values["hysteretic_force"] = states[:, 2 * len(story_force_map) :] @ story_force_map.T
    return Response(time=time, ground=ground, **values)
