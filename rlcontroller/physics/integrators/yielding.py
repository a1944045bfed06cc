"""Yielding stories (Bouc-Wen, `hysteresis.BoucWen`) and the fishbone frame (`fishbone.Fishbone`) over one
control step: classical RK4 on the ground's linear interpolation, the fishbone's floor rotations in
equilibrium."""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def z_rate(
    z: float, drift_rate: float, yield_drift: float, exponent: float, beta: float, gamma: float
) -> float:
    """dz/dt of one Bouc-Wen story. With beta + gamma = 1 the exact z never leaves [-1, 1]; |z|^n is read as
    at most 1, so an RK4 stage that overshoots the bound on a sharp loop (large n) stops there instead of
    being thrown back by |z|^n >> 1 (what made such loops diverge)."""
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
    state,
    floor_force,
    ground,
    control_dt,
    substeps,
    mass_inverse,
    damping,
    linear,
    hysteretic,
    yield_drift,
    exponent,
    beta,
    gamma,
    collapse,
):
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
    state,
    floor_force,
    ground,
    per_step,
    control_dt,
    substeps,
    mass_inverse,
    damping,
    linear,
    hysteretic,
    yield_drift,
    exponent,
    beta,
    gamma,
    collapse,
):
    """The states at every control step (K + 1, size) under `ground` (K * per_step + 1 samples), the floor
    forces held throughout: a whole record in one call (calibration's many runs)."""
    steps = (ground.size - 1) // per_step
    states = np.empty((steps + 1, state.size))
    states[0] = state
    for k in range(steps):
        states[k + 1] = bouc_wen_step(
            states[k],
            floor_force,
            ground[k * per_step : (k + 1) * per_step + 1],
            control_dt,
            substeps,
            mass_inverse,
            damping,
            linear,
            hysteretic,
            yield_drift,
            exponent,
            beta,
            gamma,
            collapse,
        )
    return states


@numba.njit(cache=True)
def _fishbone_derivative(
    s,
    floor_force,
    ground,
    mass_inverse,
    damping,
    linear,
    coupling,
    rotation,
    hinge,
    yield_rotation,
    expo,
    beta,
):
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
            phi[j + 1] = (
                1.0 - min(abs(z[j]) ** expo[j], 1.0) * (beta[j] * sign + 1.0 - beta[j])
            ) / yield_rotation[j]
        theta_rate = np.linalg.solve(np.eye(n + 1) + hinge * phi[np.newaxis, :], elastic)
    for j in range(n):
        rate[2 * n + j] = z_rate(z[j], theta_rate[j + 1], yield_rotation[j], expo[j], beta[j], 1.0 - beta[j])
    rate[:n] = v
    rate[n : 2 * n] = mass_inverse * (floor_force - damping @ v - linear @ s[:n] - coupling @ z) - ground
    return rate


@numba.njit(cache=True)
def fishbone_step(
    state,
    floor_force,
    ground,
    control_dt,
    substeps,
    collapse,
    mass_inverse,
    damping,
    linear,
    coupling,
    rotation,
    hinge,
    yield_rotation,
    exponent,
    beta,
):
    """RK4 over one control step of the fishbone (`physics.fishbone`), the floor forces held: `substeps` steps
    per interval between the ground samples; once a story has collapsed the building stays where it lies, at
    rest."""
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
    ground,
    per_step,
    control_dt,
    substeps,
    collapse,
    mass_inverse,
    damping,
    linear,
    coupling,
    rotation,
    hinge,
    yield_rotation,
    exponent,
    beta,
):
    """The fishbone's uncontrolled states [x; v; z] at every control step (K + 1, 3 n) from rest, stories
    collapsing past `collapse` (m); nan from where a run diverges (a floor past 50 m)."""
    n = mass_inverse.size
    steps = (ground.size - 1) // per_step
    out = np.full((steps + 1, 3 * n), np.nan)
    out[0] = 0.0
    idle = np.zeros(n)
    for k in range(steps):
        s = fishbone_step(
            out[k],
            idle,
            ground[k * per_step : (k + 1) * per_step + 1],
            control_dt,
            substeps,
            collapse,
            mass_inverse,
            damping,
            linear,
            coupling,
            rotation,
            hinge,
            yield_rotation,
            exponent,
            beta,
        )
        if not np.all(np.isfinite(s)) or np.max(np.abs(s[:n])) > 50.0:
            break
        out[k + 1] = s
    return out
