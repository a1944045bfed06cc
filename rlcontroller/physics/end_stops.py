"""End-stops: the housing that stops a tuned mass or an active mass driver at its stroke limit.

The contact is a linear spring-dashpot (Kelvin-Voigt) stop, the impact element of Anagnostopoulos (1988,
"Pounding of buildings in series during earthquakes", Earthquake Eng. Struct. Dyn. 16, 443-456). A device of
mass m_d whose stroke s = x_d - x_floor (m) passes its limit L meets it with penetration p = |s| - L; while
p > 0 the stop pushes the mass back with

    f = -sign(s) (k p + c p') = -k sign(s) p - c s'   (N, on the mass; its floor gets -f),

k the stop's stiffness (N/m) and c = 2 zeta sqrt(k m_d), zeta = -ln e / sqrt(pi^2 + ln^2 e), so that a mass
meeting a fixed stop at speed v leaves it at e v (e the coefficient of restitution). As in the source, the
dashpot acts for the whole contact, so it may pull the mass for an instant before it leaves the stop; m_d is
the device's own mass (its floor is far heavier). Defaults in `devices.tuned_mass`.

Stepping, by superposition. Between contacts the building and its devices are linear, so over one control step

    x_{k+1} = (the plant's own linear step of x_k, u_k and the ground) + sum_j E_j f_j,

f_j the stops' forces held over sub-step j of h seconds (h at most 1 ms and 1/200 of the stiffest stop's
period), E_j how a force held over sub-step j moves the state at the step's end. The strokes and their rates
at each sub-step are y_j = Y_j [x_k; u_k; ground samples] + sum_{i<j} H_{j-i} f_i, and f_j is the contact law
at y_j. Y, H and E come from the method's own sub-step map at h (exact or Newmark; with an actuator lag the
exact map of the building and its lag; with a delay, the buffered command applied over the step), so the
env, the batch and evaluation all step the same numbers through one compiled kernel
(`integrators.stop_step_many`). Without a contact the step is the linear plant's to rounding.

The plant's state is [x; per stopped device (f at the step's end, the largest |f| over the step, contacts
begun in the step)]: the first is a register through which every output stays linear in the state (the floor
accelerations feel it at once; a story shear, which counts the mass's inertia with its floor's, through the
motion), the others are what the tables report (peak contact force, number of contacts) and feed back into
nothing.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from rlcontroller.config import SimulationConfig
from rlcontroller.physics.dynamics import (
    StateSpace,
    StepMap,
    exact_substep,
    load_map,
    newmark_substep,
    state_space,
)
from rlcontroller.physics.structure import Building

# per stopped device: force at the step's end (N), peak |force| over the step (N), contacts begun

REGISTERS = 3
LONGEST_SUBSTEP_S = 0.001
SUBSTEPS_PER_STOP_PERIOD = 200


@dataclass(frozen=True)
class StopMaps:
    """One load sampling's maps (module docstring), on the inputs v = [x; u; ground window; floor-force
    window, sample by sample, when the load has floor forces]: y_j = strokes[j] @ v (j = 0..J), H_l =
    response[l - 1] (l = 1..J), E_j = end[j] (j = 0..J-1), and the plant's own linear step x_{k+1} = linear @
    v (its load map for the floor forces)."""

    strokes: np.ndarray  # (J + 1, 2 d, inputs): strokes (m), then stroke rates (m/s)
    response: np.ndarray  # (J, 2 d, d)
    end: np.ndarray  # (J, n_x, d)
    linear: np.ndarray  # (n_x, inputs)


@dataclass(frozen=True)
class EndStops:
    """The stopped mass devices of a plant and how it steps with them (SI; module docstring)."""

    building: Building
    simulation: SimulationConfig
    devices: np.ndarray  # (d,) indices of the stopped devices among `building.devices`
    limits: np.ndarray  # (d,) m
    stiffness: np.ndarray  # (d,) N/m
    damping: np.ndarray  # (d,) N*s/m
    n_linear: int  # the plant's linear state x, before the registers
    time_constant: float  # s, the actuators' lag (0: none)
    delay_steps: int
    linear_step: Callable[[int], StepMap]  # r ground samples per step -> the plant's own linear step on x
    _maps: dict = field(default_factory=dict, compare=False, repr=False)

    @classmethod
    def of(
        cls,
        building: Building,
        simulation: SimulationConfig,
        *,
        n_linear: int,
        time_constant: float,
        delay_steps: int,
        linear_step: Callable[[int], StepMap],
    ) -> EndStops | None:
        """The stops of `building`'s mass devices that have a stroke limit; None when none has."""
        stopped = [i for i, device in enumerate(building.devices) if device.stroke_limit is not None]
        if not stopped:
            return None
        devices = [building.devices[i] for i in stopped]
        return cls(
            building=building,
            simulation=simulation,
            devices=np.array(stopped),
            limits=np.array([d.stroke_limit for d in devices]),
            stiffness=np.array([d.stop_stiffness for d in devices]),
            damping=np.array([d.stop_damping for d in devices]),
            n_linear=n_linear,
            time_constant=time_constant,
            delay_steps=delay_steps,
            linear_step=linear_step,
        )

    @property
    def size(self) -> int:
        """The registers' length in the plant's state."""
        return REGISTERS * self.devices.size

    def contact_matrix(self) -> np.ndarray:
        """P (dofs x d): a stop's force f acts +f on its device and -f on the device's floor."""
        building = self.building
        matrix = np.zeros((building.n_dofs, self.devices.size))
        for column, index in enumerate(self.devices):
            matrix[building.n_floors + index, column] = 1.0
            matrix[building.devices[index].floor - 1, column] = -1.0
        return matrix

    def substep_seconds(self, control_dt: float, intervals: int) -> tuple[int, float]:
        """(sub-steps per ground interval, h in s)."""
        masses = np.array([self.building.devices[i].mass for i in self.devices])
        period = float(np.min(2.0 * np.pi * np.sqrt(masses / self.stiffness)))
        longest = min(LONGEST_SUBSTEP_S, period / SUBSTEPS_PER_STOP_PERIOD)
        per_interval = int(np.ceil(control_dt / intervals / longest - 1e-9))
        return per_interval, control_dt / (intervals * per_interval)

    def maps(self, intervals: int, control_dt: float, floor_forces: bool = False) -> StopMaps:
        """The maps for `intervals` load intervals per control step, with or without floor forces (built once,
        kept)."""
        key = (intervals, floor_forces)
        if key not in self._maps:
            self._maps[key] = self._build(intervals, control_dt, floor_forces)
        return self._maps[key]

    def _substep(self, h: float):
        """(phi, gain on [command applied; stop forces], ground start, ground end, floor forces' start and end
        (q, floors)) of the inner state q over h: the building's z, with a lag also the delivered forces.
        Floor forces, linear between their samples, are discretised exactly whatever the method, as the
        plant's."""
        building, m = self.building, self.building.n_actuators
        pushed = replace(
            building, actuator_matrix=np.hstack([building.actuator_matrix, self.contact_matrix()])
        )
        if self.time_constant > 0:
            system, size = state_space(pushed), building.n_states
            a = np.zeros((size + m, size + m))
            a[:size, :size] = system.a
            a[:size, size:] = system.b_force[:, :m]
            a[size:, size:] = -np.eye(m) / self.time_constant
            b = np.zeros((size + m, m + self.devices.size))
            b[size:, :m] = np.eye(m) / self.time_constant
            b[:size, m:] = system.b_force[:, m:]
            sub = exact_substep(
                StateSpace(a=a, b_force=b, b_ground=np.concatenate([system.b_ground, np.zeros(m)])), h
            )
        elif self.simulation.method == "newmark":
            sub = newmark_substep(pushed, h, self.simulation.newmark_beta, self.simulation.newmark_gamma)
        else:
            sub = exact_substep(state_space(pushed), h)
        loads = np.zeros((sub.phi.shape[0], 2, building.n_floors))
        loads[: building.n_states] = load_map(building, h).gain
        return sub.phi, sub.force_gain, sub.ground_start, sub.ground_end, loads[:, 0], loads[:, 1]

    def _build(self, intervals: int, control_dt: float, floor_forces: bool) -> StopMaps:
        building, m, d, n_x = self.building, self.building.n_actuators, self.devices.size, self.n_linear
        per_interval, h = self.substep_seconds(control_dt, intervals)
        phi, gain, ground_start, ground_end, load_start, load_end = self._substep(h)
        command_gain, stop_gain = gain[:, :m], gain[:, m:]
        inner, total, floors = phi.shape[0], intervals * per_interval, building.n_floors
        loads = n_x + m + intervals + 1  # the first floor-force column
        columns = loads + (intervals + 1) * floors * floor_forces
        # the command applied over the step, from [x; u]: u itself, or with a delay the buffer's oldest entry
        applied = np.zeros((m, columns))
        if self.delay_steps > 0:
            oldest = inner + (self.delay_steps - 1) * m
            applied[:, oldest : oldest + m] = np.eye(m)
        else:
            applied[:, n_x : n_x + m] = np.eye(m)
        strokes_on_q = np.zeros((2 * d, inner))
        dofs = building.n_dofs
        rows = building.stroke_matrix()[self.devices]
        strokes_on_q[:d, :dofs], strokes_on_q[d:, dofs : 2 * dofs] = rows, rows
        state = np.zeros((inner, columns))  # q at sub-step j as a map of [x; u; ground window]
        state[:, :inner] = np.eye(inner)
        strokes = np.empty((total + 1, 2 * d, columns))
        strokes[0] = strokes_on_q @ state
        for j in range(total):
            interval, part = divmod(j, per_interval)
            state = phi @ state + command_gain @ applied
            for weight, column in (
                (ground_start, part / per_interval),
                (ground_end, (part + 1) / per_interval),
            ):
                state[:, n_x + m + interval] += weight * (1.0 - column)
                state[:, n_x + m + interval + 1] += weight * column
            if floor_forces:  # sample i's forces in columns loads + i floors ... + (i + 1) floors
                here, after = (loads + (interval + i) * floors for i in (0, 1))
                for weight, column in (
                    (load_start, part / per_interval),
                    (load_end, (part + 1) / per_interval),
                ):
                    state[:, here : here + floors] += weight * (1.0 - column)
                    state[:, after : after + floors] += weight * column
            strokes[j + 1] = strokes_on_q @ state
        response = np.empty((total, 2 * d, d))
        end = np.zeros((total, n_x, d))
        pushed = stop_gain
        for lag in range(total):  # pushed = phi^lag B_c: a force held over one sub-step, `lag` sub-steps on
            response[lag] = strokes_on_q @ pushed
            end[total - 1 - lag, :inner] = pushed
            pushed = phi @ pushed
        step = self.linear_step(intervals)
        linear = np.zeros((n_x, columns))
        linear[:, :n_x], linear[:, n_x : n_x + m], linear[:, n_x + m : loads] = (
            step.phi,
            step.force_gain,
            step.ground_gain,
        )
        if floor_forces:  # the plant's own load map over the control step (`SampledPlant.load`)
            gain = load_map(building, control_dt, intervals).gain  # (2 n, r + 1, floors)
            linear[: gain.shape[0], loads:] = gain.reshape(gain.shape[0], -1)
        return StopMaps(
            strokes=np.ascontiguousarray(strokes),
            response=np.ascontiguousarray(response),
            end=np.ascontiguousarray(end),
            linear=linear,
        )

    def step(
        self,
        state: np.ndarray,
        action: np.ndarray,
        ground: np.ndarray,
        control_dt: float,
        *,
        floor_forces: np.ndarray | None = None,
    ) -> np.ndarray:
        """The state after one control step with `action` (forces / force limits) held, `ground` the r + 1
        ground samples (m/s^2) spanning it and `floor_forces` the r + 1 floor-force samples (r + 1, floors;
        N), if the load has them."""
        forces = None if floor_forces is None else floor_forces[None]
        return self.step_many(state[None], action[None], ground[None], control_dt, floor_forces=forces)[0]

    def step_many(
        self,
        states: np.ndarray,
        actions: np.ndarray,
        grounds: np.ndarray,
        control_dt: float,
        *,
        floor_forces: np.ndarray | None = None,
    ) -> np.ndarray:
        """`step` for many buildings of this plant at once (states (N, S), actions (N, m), grounds (N, r + 1),
        floor forces (N, r + 1, floors) or None)."""
        maps = self.maps(grounds.shape[1] - 1, control_dt, floor_forces is not None)
        loads = [actions * self.building.force_limits, grounds]
        if floor_forces is not None:
            loads.append(floor_forces.reshape(len(states), -1))
        # numba: imported when first needed; its arguments named, so that no two can swap
        from rlcontroller.physics.integrators.stops import stop_step_many

        return stop_step_many(
            states=np.ascontiguousarray(states),
            loads=np.ascontiguousarray(np.hstack(loads)),
            linear=maps.linear,
            strokes=maps.strokes,
            response=maps.response,
            end=maps.end,
            limits=self.limits,
            stiffness=self.stiffness,
            damping=self.damping,
        )
