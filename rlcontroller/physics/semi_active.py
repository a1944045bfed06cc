"""Semi-active dampers between floors and their integrator over one control step.

A damper on story j (drift d = x_j - x_{j-1}, drift velocity d') pushes floor j with -F and floor
j - 1 with +F, where F is its force on the story (positive when it resists a positive drift
velocity). The action a in [-1, 1] of each damper is its command for the whole control step:

- ideal variable damper: F = c d', c = c_min + (c_max - c_min) (a + 1) / 2 (N*s/m): it can only
  dissipate (F d' >= 0 for any command).
- magnetorheological damper: Spencer, Dyke, Sain and Carlson (1997, J. Eng. Mech. 123(3), 230-238),
  the phenomenological model with voltage-dependent parameters, with d as the damper's stroke:

      F = c1 y' + k1 d,   y' = [alpha z + c0 d' + k0 (d - y)] / (c0 + c1),
      z' = -gamma |d' - y'| z |z| - beta (d' - y') z^2 + A (d' - y')        (n = 2),
      alpha, c0, c1 = (..._a + ..._b u),   u' = -eta (u - v),   v = V_max (a + 1) / 2.

  The prototype's parameters (the paper's Table 1 as widely reproduced, converted to SI: N, m, s,
  V; not re-read from the paper here) are `SPENCER_1997`; a damper of another capacity multiplies
  every force parameter (c0, c1, k0, k1, alpha) by capacity / (alpha(V_max) z_max), z_max =
  sqrt(A / (beta + gamma)) being the value z saturates at, so that its yield-like force
  alpha(V_max) z_max is `capacity`. The accumulator's
  preload k1 x0 is left out: it only shifts the building's static equilibrium.

The plant's state is [x; x'; per damper (y, z, u, F)]: the floors' (and mass devices')
displacements and velocities, then each damper's internal displacement y (m), evolutionary
variable z (m), filtered voltage u (V; for a variable damper its c) and its force F at the end of
the step (N), a register through which every output stays linear in the state. Over a control
step the building advances by its exact linear map over `substep` (s) sub-steps, each damper's force
held over each sub-step; z takes an implicit Euler step (it is stiff: its rate reaches 10^3-10^4
1/s), y an explicit one, u its exact exponential. `tests/physics/test_semi_active.py` compares the
result with scipy's Radau on the same equations.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba
import numpy as np

from rlcontroller.physics.dynamics import StateSpace, exact_substep, state_space
from rlcontroller.physics.structure import Building

VARIABLE_DAMPER, MR_DAMPER = 0, 1
INTERNAL = 4  # y, z, u, F per damper
SUBSTEP_S = 0.001  # the longest sub-step (s)

# Spencer et al. (1997), Table 1 (prototype MR damper, N-cm-s units converted to SI).
SPENCER_1997 = {
    "c0a": 21.0e2,  # N s/m
    "c0b": 3.50e2,  # N s/(m V)
    "k0": 46.9e2,  # N/m
    "c1a": 283.0e2,  # N s/m
    "c1b": 2.95e2,  # N s/(m V)
    "k1": 5.00e2,  # N/m
    "alpha_a": 140.0e2,  # N/m
    "alpha_b": 695.0e2,  # N/(m V)
    "gamma": 363.0e4,  # 1/m^2
    "beta": 363.0e4,  # 1/m^2
    "A": 301.0,
}
PARAMETERS = ("c0a", "c0b", "k0", "c1a", "c1b", "k1", "alpha_a", "alpha_b", "gamma", "beta", "A")
FORCE_PARAMETERS = ("c0a", "c0b", "k0", "c1a", "c1b", "k1", "alpha_a", "alpha_b")


def mr_parameters(capacity: float, max_voltage: float) -> dict[str, float]:
    """Spencer's parameters with every force parameter scaled so that alpha(V_max) z_max = capacity (N)."""
    base = SPENCER_1997
    z_max = np.sqrt(base["A"] / (base["beta"] + base["gamma"]))
    scale = capacity / ((base["alpha_a"] + base["alpha_b"] * max_voltage) * z_max)
    return {key: value * scale if key in FORCE_PARAMETERS else value for key, value in base.items()}


@dataclass(frozen=True)
class SemiActiveDampers:
    """The dampers of a building and its linear sub-step maps: what the integrator needs (SI)."""

    building: Building
    first_command: int  # the action's index of the first damper (after the active devices)
    kinds: np.ndarray  # (d,) VARIABLE_DAMPER | MR_DAMPER
    stories: np.ndarray  # (d,) 1-based
    parameters: np.ndarray  # (d, 13): PARAMETERS, V_max, eta of an MR damper; c_min, c_max (rest 0) of a variable one
    _maps: dict = field(default_factory=dict, compare=False, repr=False)

    @classmethod
    def of(cls, building: Building) -> SemiActiveDampers:
        rows = []
        for damper in building.dampers:
            config = damper.config
            if damper.kind == "variable_damper":
                rows.append([config.damping_min, config.damping_max] + [0.0] * 11)
            else:
                values = mr_parameters(config.capacity, config.max_voltage)
                rows.append([values[key] for key in PARAMETERS] + [config.max_voltage, config.eta])
        return cls(
            building=building,
            first_command=building.n_actuators - len(building.dampers),
            kinds=np.array([VARIABLE_DAMPER if d.kind == "variable_damper" else MR_DAMPER for d in building.dampers]),
            stories=np.array([d.story for d in building.dampers]),
            parameters=np.array(rows, dtype=float),
        )

    @property
    def size(self) -> int:
        """Internal states of all dampers."""
        return INTERNAL * self.kinds.size

    def _substep_maps(self, intervals: int, control_dt: float) -> tuple[np.ndarray, ...]:
        """The building's exact map over one sub-step for forces on its degrees of freedom (cached)."""
        if intervals not in self._maps:
            per_interval = int(np.ceil(control_dt / intervals / SUBSTEP_S - 1e-9))
            system = state_space(self.building)
            n = self.building.n_dofs
            on_dofs = StateSpace(
                a=system.a,
                b_force=np.vstack([np.zeros((n, n)), np.linalg.inv(self.building.mass)]),
                b_ground=system.b_ground,
            )
            sub = exact_substep(on_dofs, control_dt / (intervals * per_interval))
            maps = (sub.phi, sub.force_gain, sub.ground_start, sub.ground_end)
            self._maps[intervals] = (per_interval, *(np.ascontiguousarray(m) for m in maps))
        return self._maps[intervals]

    def step(self, state: np.ndarray, action: np.ndarray, ground: np.ndarray, control_dt: float) -> np.ndarray:
        """The state after one control step: the action held (the active devices' forces / force
        limits, the dampers' commands in [-1, 1]), `ground` the r + 1 ground samples (m/s^2) spanning
        the step."""
        return self.step_many(state[None], action[None], ground[None], control_dt)[0]

    def step_many(self, states: np.ndarray, actions: np.ndarray, grounds: np.ndarray, control_dt: float) -> np.ndarray:
        """`step` for many buildings of this plant at once (states (N, S), actions (N, m), grounds
        (N, r + 1)), in one compiled call."""
        per_interval, phi, force_gain, ground_start, ground_end = self._substep_maps(grounds.shape[1] - 1, control_dt)
        first, building = self.first_command, self.building
        active = actions[:, :first] @ (building.actuator_matrix[:, :first] * building.force_limits[:first]).T
        h = control_dt / ((grounds.shape[1] - 1) * per_interval)
        return damper_step_many(
            states, active, np.ascontiguousarray(actions[:, first:]), grounds, per_interval, h, phi, force_gain,
            ground_start, ground_end, self.stories, self.kinds, self.parameters,
        )  # fmt: skip


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
