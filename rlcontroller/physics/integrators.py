"""The compiled (numba) integrators of the non-linear plants over one control step: yielding stories
(`hysteresis.BoucWen`, classical RK4), the fishbone frame (`fishbone.Fishbone`, RK4 with its massless floor rotations
in equilibrium) and semi-active dampers (`semi_active.SemiActiveDampers`: the
building's exact linear map over sub-steps, implicit Euler on the MR damper's z). The equations are
in those modules' docstrings. This module is imported on first use: numba's own import (~0.2 s) is
never paid by a linear plant.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def z_rate(z: float, drift_rate: float, yield_drift: float, exponent: float, beta: float, gamma: float) -> float:
    """dz/dt of one Bouc-Wen story. With beta + gamma = 1 the exact z never leaves [-1, 1]; |z|^n is read as at
    most 1, so an RK4 stage that overshoots the bound on a sharp loop (large n) stops there instead of being
    thrown back by |z|^n >> 1 (what made such loops diverge)."""
    sign = 1.0 if drift_rate * z > 0.0 else (-1.0 if drift_rate * z < 0.0 else 0.0)
    return drift_rate / yield_drift * (1.0 - min(abs(z) ** exponent, 1.0) * (beta * sign + gamma))


@numba.njit(cache=True)
def _derivative(
    state, floor_force, ground, mass_inverse, damping, linear, hysteretic, yield_drift, exponent, beta, gamma
):
    n = mass_inverse.size
    rate = np.empty(3 * n)
    spring_force = np.empty(n)  # the yielding springs' hysteretic parts, (1 - a) k d_y z
    for i in range(n):
        below_v = state[n + i - 1] if i > 0 else 0.0
        drift_rate = state[n + i] - below_v
        spring_force[i] = hysteretic[i] * state[2 * n + i]
        rate[2 * n + i] = z_rate(state[2 * n + i], drift_rate, yield_drift[i], exponent[i], beta[i], gamma[i])
    for i in range(n):
        restoring = spring_force[i] - (spring_force[i + 1] if i + 1 < n else 0.0)  # D' h z
        damping_force = 0.0
        for j in range(n):
            damping_force += damping[i, j] * state[n + j]
            restoring += linear[i, j] * state[j]  # K_e x
        rate[i] = state[n + i]
        rate[n + i] = mass_inverse[i] * (floor_force[i] - damping_force - restoring) - ground
    return rate


@numba.njit(cache=True)
def collapsed(state, collapse):
    """Whether a story's drift |x_i - x_(i-1)| has reached its collapse drift (m)."""
    below = 0.0
    for i in range(collapse.size):
        if abs(state[i] - below) >= collapse[i]:
            return True
        below = state[i]
    return False


@numba.njit(cache=True)
def bouc_wen_step(
    state, floor_force, ground, control_dt, substeps, mass_inverse, damping, linear, hysteretic, yield_drift, exponent,
    beta, gamma, collapse,
):  # fmt: skip
    """RK4 over one control step: `substeps` steps per interval between the ground samples. Once a story has
    collapsed (`collapse`, m per story; inf: never) the building stays where it lies, at rest."""
    intervals = ground.size - 1
    h = control_dt / (intervals * substeps)
    s = state.copy()
    n = collapse.size
    if collapsed(s, collapse):
        s[n : 2 * n] = 0.0
        return s
    args = (mass_inverse, damping, linear, hysteretic, yield_drift, exponent, beta, gamma)
    for interval in range(intervals):
        start, slope = ground[interval], (ground[interval + 1] - ground[interval]) / (h * substeps)
        for j in range(substeps):
            a0 = start + slope * h * j
            k1 = _derivative(s, floor_force, a0, *args)
            k2 = _derivative(s + 0.5 * h * k1, floor_force, a0 + 0.5 * h * slope, *args)
            k3 = _derivative(s + 0.5 * h * k2, floor_force, a0 + 0.5 * h * slope, *args)
            k4 = _derivative(s + h * k3, floor_force, a0 + h * slope, *args)
            s = s + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
            if collapsed(s, collapse):
                s[n : 2 * n] = 0.0
                return s
    return s


@numba.njit(cache=True)
def bouc_wen_history(
    state, floor_force, ground, per_step, control_dt, substeps, mass_inverse, damping, linear, hysteretic, yield_drift,
    exponent, beta, gamma, collapse,
):  # fmt: skip
    """The states at every control step (K + 1, size) under `ground` (K * per_step + 1 samples), the floor
    forces held throughout: a whole record in one call (calibration's many runs)."""
    steps = (ground.size - 1) // per_step
    states = np.empty((steps + 1, state.size))
    states[0] = state
    for k in range(steps):
        states[k + 1] = bouc_wen_step(
            states[k], floor_force, ground[k * per_step : (k + 1) * per_step + 1], control_dt, substeps, mass_inverse,
            damping, linear, hysteretic, yield_drift, exponent, beta, gamma, collapse,
        )  # fmt: skip
    return states


@numba.njit(cache=True)
def damper_step_many(
    states, active, actions, grounds, per_interval, h, phi, force_gain, ground_start, ground_end, stories, kinds,
    parameters,
):  # fmt: skip
    new = np.empty_like(states)
    for member in range(states.shape[0]):
        new[member] = damper_step(
            states[member], active[member], actions[member], grounds[member], per_interval, h, phi, force_gain,
            ground_start, ground_end, stories, kinds, parameters,
        )  # fmt: skip
    return new


@numba.njit(cache=True)
def _z_implicit(z0, h, drift, velocity, y, alpha, c0, c1, k0, gamma, beta, a):
    """z after an implicit Euler step of z' = w (A - (gamma sgn(w z) + beta) z^2), w = d' - y'(z)."""
    total = c0 + c1
    z = z0
    for _ in range(8):
        w = (c1 * velocity - alpha * z - k0 * (drift - y)) / total
        sign = 1.0 if w * z > 0.0 else (-1.0 if w * z < 0.0 else 0.0)
        kappa = gamma * sign + beta
        rate = w * (a - kappa * z * z)
        slope = -alpha / total * (a - kappa * z * z) - 2.0 * kappa * z * w
        residual = z - z0 - h * rate
        change = residual / (1.0 - h * slope)
        z -= change
        if abs(change) <= 1e-14 + 1e-12 * abs(z):
            break
    return z


@numba.njit(cache=True)
def damper_step(
    state, active_force, actions, ground, per_interval, h, phi, force_gain, ground_start, ground_end, stories, kinds,
    parameters,
):  # fmt: skip
    """One control step of the building and its dampers (see the module docstring)."""
    size = phi.shape[0]
    n = size // 2
    dampers = stories.size
    s = state.copy()
    new = np.empty(size)
    held_term = force_gain @ active_force  # the active devices' forces, held over the whole step
    damper_gain = np.zeros((size, dampers))  # z per newton of each damper's force F (-F above, +F below)
    for k in range(dampers):
        floor = stories[k] - 1
        for i in range(size):
            damper_gain[i, k] = -force_gain[i, floor] + (force_gain[i, floor - 1] if floor > 0 else 0.0)
    intervals = ground.size - 1
    for interval in range(intervals):
        for j in range(per_interval):
            a0 = ground[interval] + j / per_interval * (ground[interval + 1] - ground[interval])
            a1 = ground[interval] + (j + 1) / per_interval * (ground[interval + 1] - ground[interval])
            for i in range(size):
                total = held_term[i] + ground_start[i] * a0 + ground_end[i] * a1
                for col in range(size):
                    total += phi[i, col] * s[col]
                for k in range(dampers):
                    total += damper_gain[i, k] * s[size + 4 * k + 3]
                new[i] = total
            s[:size] = new
            for k in range(dampers):
                floor = stories[k] - 1
                drift = s[floor] - (s[floor - 1] if floor > 0 else 0.0)
                velocity = s[n + floor] - (s[n + floor - 1] if floor > 0 else 0.0)
                base = 2 * n + 4 * k
                p = parameters[k]
                command = 0.5 * (actions[k] + 1.0)
                if kinds[k] == 0:
                    c = p[0] + (p[1] - p[0]) * command
                    s[base + 2] = c
                    s[base + 3] = c * velocity
                    continue
                k0, k1, gamma, beta, a, v_max, eta = p[2], p[5], p[8], p[9], p[10], p[11], p[12]
                s[base + 2] = v_max * command + (s[base + 2] - v_max * command) * np.exp(-eta * h)
                u = s[base + 2]
                c0, c1, alpha = p[0] + p[1] * u, p[3] + p[4] * u, p[6] + p[7] * u
                y = s[base]
                z_new = _z_implicit(s[base + 1], h, drift, velocity, y, alpha, c0, c1, k0, gamma, beta, a)
                y_rate = (alpha * z_new + c0 * velocity + k0 * (drift - y)) / (c0 + c1)
                s[base] = y + h * y_rate
                s[base + 1] = z_new
                s[base + 3] = c1 * y_rate + k1 * drift
    return s


@numba.njit(cache=True)
def _fishbone_derivative(
    s, floor_force, ground, mass_inverse, damping, linear, coupling, rotation, hinge, yield_rotation, expo, beta
):  # fmt: skip
    n = mass_inverse.size
    v, z = s[n : 2 * n], s[2 * n :]
    rate = np.empty(3 * n)
    elastic = -(rotation @ v)  # theta' were the hinges not yielding (n + 1: the base's first)
    theta_rate = elastic.copy()
    for _ in range(2):  # Phi from the signs of the last estimate of theta', then the linear solve
        phi = np.zeros(n + 1)
        for j in range(n):
            t = theta_rate[j + 1]
            sign = 1.0 if t * z[j] > 0.0 else (-1.0 if t * z[j] < 0.0 else 0.0)
            phi[j + 1] = (1.0 - min(abs(z[j]) ** expo[j], 1.0) * (beta[j] * sign + 1.0 - beta[j])) / yield_rotation[j]
        theta_rate = np.linalg.solve(np.eye(n + 1) + hinge * phi[np.newaxis, :], elastic)
    for j in range(n):
        rate[2 * n + j] = z_rate(z[j], theta_rate[j + 1], yield_rotation[j], expo[j], beta[j], 1.0 - beta[j])
    rate[:n] = v
    rate[n : 2 * n] = mass_inverse * (floor_force - damping @ v - linear @ s[:n] - coupling @ z) - ground
    return rate


@numba.njit(cache=True)
def fishbone_step(
    state, floor_force, ground, control_dt, substeps, collapse, mass_inverse, damping, linear, coupling, rotation,
    hinge, yield_rotation, exponent, beta,
):  # fmt: skip
    """RK4 over one control step of the fishbone (`physics.fishbone`), the floor forces held: `substeps` steps per
    interval between the ground samples; once a story has collapsed the building stays where it lies, at rest."""
    intervals = ground.size - 1
    h = control_dt / (intervals * substeps)
    s = state.copy()
    n = collapse.size
    if collapsed(s, collapse):
        s[n : 2 * n] = 0.0
        return s
    args = (mass_inverse, damping, linear, coupling, rotation, hinge, yield_rotation, exponent, beta)
    for interval in range(intervals):
        start, slope = ground[interval], (ground[interval + 1] - ground[interval]) / (h * substeps)
        for j in range(substeps):
            a0 = start + slope * h * j
            k1 = _fishbone_derivative(s, floor_force, a0, *args)
            k2 = _fishbone_derivative(s + 0.5 * h * k1, floor_force, a0 + 0.5 * h * slope, *args)
            k3 = _fishbone_derivative(s + 0.5 * h * k2, floor_force, a0 + 0.5 * h * slope, *args)
            k4 = _fishbone_derivative(s + h * k3, floor_force, a0 + h * slope, *args)
            s = s + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
            if collapsed(s, collapse):
                s[n : 2 * n] = 0.0
                return s
    return s


@numba.njit(cache=True)
def fishbone_history(
    ground, per_step, control_dt, substeps, collapse, mass_inverse, damping, linear, coupling, rotation, hinge,
    yield_rotation, exponent, beta,
):  # fmt: skip
    """The fishbone's uncontrolled states [x; v; z] at every control step (K + 1, 3 n) from rest, stories collapsing
    past `collapse` (m); nan from where a run diverges (a floor past 50 m)."""
    n = mass_inverse.size
    steps = (ground.size - 1) // per_step
    out = np.full((steps + 1, 3 * n), np.nan)
    out[0] = 0.0
    idle = np.zeros(n)
    for k in range(steps):
        s = fishbone_step(
            out[k], idle, ground[k * per_step : (k + 1) * per_step + 1], control_dt, substeps, collapse, mass_inverse,
            damping, linear, coupling, rotation, hinge, yield_rotation, exponent, beta,
        )  # fmt: skip
        if not np.all(np.isfinite(s)) or np.max(np.abs(s[:n])) > 50.0:
            break
        out[k + 1] = s
    return out


@numba.njit(cache=True)
def stop_force(stroke: float, rate: float, limit: float, stiffness: float, damping: float) -> float:
    """The end-stop's force on its mass (N; `end_stops`): -k sign(s) p - c s' while p = |s| - limit > 0."""
    penetration = abs(stroke) - limit
    if penetration <= 0.0:
        return 0.0
    return -(stiffness * penetration if stroke > 0.0 else -stiffness * penetration) - damping * rate


@numba.njit(cache=True)
def held_stop_force(stroke, rate, end_stroke, end_rate, limit, stiffness, damping):
    """The stop's force to hold over a sub-step from (stroke, rate) to the predicted (end_stroke, end_rate): the
    trapezoid of the contact law over the part of the sub-step in contact, a contact's start or end located by
    linear interpolation (there the spring's force is zero and the dashpot's -c s' jumps)."""
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
    """The strokes and rates at sub-step j: the linear plant's, plus what the stops' forces held over the earlier
    sub-steps `first`..j-1 added (loops: these products are too small for BLAS calls to pay)."""
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
    """One control step of a building whose mass devices meet end-stops (`end_stops`, by superposition on the
    linear step; `loads` the commands (N), the ground samples and the floor forces' if any): the new state [x; per
    device (force at the end, peak |force|, contacts begun)]. The force held over each sub-step is the contact
    law's mean over it, its end predicted with the start's force held (`held_stop_force`): an impact's rebound is
    right to a fraction of a per cent."""
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
