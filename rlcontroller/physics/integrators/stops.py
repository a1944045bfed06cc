"""A mass device's stroke against its end-stops (`end_stops.EndStops`) over one control step."""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def stop_force(stroke: float, rate: float, limit: float, stiffness: float, damping: float) -> float:
    """The end-stop's force on its mass (N; `end_stops`): -k sign(s) p - c s' while p = |s| - limit > 0."""
    penetration = abs(stroke) - limit
    if penetration <= 0.0:
        return 0.0
    return -(stiffness * penetration if stroke > 0.0 else -stiffness * penetration) - damping * rate


@numba.njit(cache=True)
def held_stop_force(stroke, rate, end_stroke, end_rate, limit, stiffness, damping):
    """The stop's force to hold over a sub-step from (stroke, rate) to the predicted (end_stroke, end_rate):
    the trapezoid of the contact law over the part of the sub-step in contact, a contact's start or end
    located by linear interpolation (there the spring's force is zero and the dashpot's -c s' jumps)."""
    start, end = abs(stroke) - limit, abs(end_stroke) - limit
    if start <= 0.0 and end <= 0.0:
        return 0.0
    force = stop_force(stroke, rate, limit, stiffness, damping)
    end_force = stop_force(end_stroke, end_rate, limit, stiffness, damping)
    if start > 0.0 and end > 0.0:
        return 0.5 * (force + end_force)
    crossing = start / (start - end)  # the fraction of the sub-step at which the face is crossed
    face = -damping * (rate + crossing * (end_rate - rate))
    if start <= 0.0:  # the contact starts
        return (1.0 - crossing) * 0.5 * (face + end_force)
    return crossing * 0.5 * (force + face)  # it ends


@numba.njit(cache=True)
def _strokes_at(j, free, forces, first, response):
    """The strokes and rates at sub-step j: the linear plant's, plus what the stops' forces held over the
    earlier sub-steps `first`..j-1 added (loops: these products are too small for BLAS calls to pay)."""
    y = free[j].copy()
    rows, d = response.shape[1], response.shape[2]
    for i in range(first, j):
        lag = response[j - i - 1]
        for k in range(d):
            f = forces[i, k]
            if f != 0.0:
                for r in range(rows):
                    y[r] += lag[r, k] * f
    return y


@numba.njit(cache=True)
def stop_step(state, loads, linear, strokes, response, end, limits, stiffness, damping):
    """One control step of a building whose mass devices meet end-stops (`end_stops`, by superposition on
    the linear step; `loads` the commands (N), the ground samples and the floor forces' if any): the new state
    [x; per device (force at the end, peak |force|, contacts begun)]. The force held over each sub-step is the
    contact law's mean over it, its end predicted with the start's force held (`held_stop_force`): an impact's
    rebound is right to a fraction of a per cent."""
    n_x, d = linear.shape[0], limits.size
    total = response.shape[0]
    inputs = np.empty(n_x + loads.size)
    inputs[:n_x], inputs[n_x:] = state[:n_x], loads
    free = np.zeros((total + 1, 2 * d))
    for j in range(total + 1):
        for r in range(2 * d):
            row, value = strokes[j, r], 0.0
            for c in range(inputs.size):
                value += row[c] * inputs[c]
            free[j, r] = value
    forces = np.zeros((total, d))
    new = np.zeros(n_x + 3 * d)
    first = total  # the first sub-step with a force: before it, the strokes are the linear plant's
    previous = free[0, :d].copy()
    for j in range(total + 1):
        y = _strokes_at(j, free, forces, first, response)
        start = np.zeros(d)
        for k in range(d):
            start[k] = stop_force(y[k], y[d + k], limits[k], stiffness[k], damping[k])
            if j > 0:
                new[n_x + d + k] = max(new[n_x + d + k], abs(start[k]))
                if abs(y[k]) > limits[k] and abs(previous[k]) <= limits[k]:
                    new[n_x + 2 * d + k] += 1.0
        previous = y[:d].copy()
        if j == total:
            new[n_x : n_x + d] = start
            break
        forces[j] = start  # predict the sub-step's end with the start's force held
        predicted = _strokes_at(j + 1, free, forces, min(first, j), response)
        pushed = False
        for k in range(d):
            forces[j, k] = held_stop_force(
                y[k], y[d + k], predicted[k], predicted[d + k], limits[k], stiffness[k], damping[k]
            )
            pushed = pushed or forces[j, k] != 0.0
        if pushed and first == total:
            first = j
    new[:n_x] = linear @ inputs
    for i in range(first, total):
        for k in range(d):
            f = forces[i, k]
            if f != 0.0:
                for r in range(n_x):
                    new[r] += end[i, r, k] * f
    return new


@numba.njit(cache=True)
def stop_step_many(states, loads, linear, strokes, response, end, limits, stiffness, damping):
    """`stop_step` for many buildings of one plant (states (N, S), loads (N, inputs after x))."""
    new = np.empty((states.shape[0], linear.shape[0] + 3 * limits.size))
    for member in range(states.shape[0]):
        new[member] = stop_step(
            states[member], loads[member], linear, strokes, response, end, limits, stiffness, damping
        )
    return new
