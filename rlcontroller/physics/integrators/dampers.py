"""Semi-active dampers (`semi_active.SemiActiveDampers`) over one control step: the building's exact linear
map over sub-steps, implicit Euler on the MR damper's evolutionary variable z."""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def damper_step_many(
    states,
    active,
    actions,
    grounds,
    per_interval,
    h,
    phi,
    force_gain,
    ground_start,
    ground_end,
    stories,
    kinds,
    parameters,
):
    new = np.empty_like(states)
    for member in range(states.shape[0]):
        new[member] = damper_step(
            states[member],
            active[member],
            actions[member],
            grounds[member],
            per_interval,
            h,
            phi,
            force_gain,
            ground_start,
            ground_end,
            stories,
            kinds,
            parameters,
        )
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
    state,
    active_force,
    actions,
    ground,
    per_interval,
    h,
    phi,
    force_gain,
    ground_start,
    ground_end,
    stories,
    kinds,
    parameters,
):
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
