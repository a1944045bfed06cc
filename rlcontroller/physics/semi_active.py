"""Semi-active dampers between floors and their integrator over one control step.

A damper on story j (drift d = x_j - x_{j-1}, drift velocity d') pushes floor j with -F and floor
j - 1 with +F, where F is its force on the story (positive when it resists a positive drift
velocity). The action a in [-1, 1] of each damper is its command for the whole control step:

each damper type's law (`devices.variable_damper`, `devices.mr_damper`) is a branch of the compiled
step in `integrators.py`, numbered by the type's `kernel`, reading its `kernel_row`.

The plant's state is [x; x'; per damper (y, z, u, F)]: the floors' (and mass devices')
displacements and velocities, then each damper's internal displacement y (m), evolutionary
variable z (m), filtered voltage u (V; for a variable damper its c) and its force F at the end of
the step (N), a register through which every output stays linear in the state. Over a control
step the building advances by its exact linear map over `substep` (s) sub-steps, each damper's force
held over each sub-step; z takes an implicit Euler step (it is stiff: its rate reaches 10^3-10^4
1/s), y an explicit one, u its exact exponential (compiled with numba in `integrators.py`).
`tests/physics/test_semi_active.py` compares the result with scipy's Radau on the same equations.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rlcontroller.physics.dynamics import StateSpace, exact_substep, state_space
from rlcontroller.physics.structure import Building

INTERNAL = 4  # y, z, u, F per damper
SUBSTEP_S = 0.001  # the longest sub-step (s)


@dataclass(frozen=True)
class SemiActiveDampers:
    """The dampers of a building and its linear sub-step maps: what the integrator needs (SI)."""

    building: Building
    first_command: int  # the action's index of the first damper (after the active devices)
    kinds: np.ndarray  # (d,) each damper type's `kernel` number
    stories: np.ndarray  # (d,) 1-based
    parameters: np.ndarray  # (d, 13): each damper's `kernel_row`
    _maps: dict = field(default_factory=dict, compare=False, repr=False)

    @classmethod
    def of(cls, building: Building) -> SemiActiveDampers:
        return cls(
            building=building,
            first_command=building.n_actuators - len(building.dampers),
            kinds=np.array([d.kernel for d in building.dampers]),
            stories=np.array([d.story for d in building.dampers]),
            parameters=np.array([d.kernel_row() for d in building.dampers], dtype=float),
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

    def step(
        self, state: np.ndarray, action: np.ndarray, ground: np.ndarray, control_dt: float
    ) -> np.ndarray:
        """The state after one control step: the action held (the active devices' forces / force
        limits, the dampers' commands in [-1, 1]), `ground` the r + 1 ground samples (m/s^2) spanning
        the step."""
        return self.step_many(state[None], action[None], ground[None], control_dt)[0]

    def step_many(
        self, states: np.ndarray, actions: np.ndarray, grounds: np.ndarray, control_dt: float
    ) -> np.ndarray:
        """`step` for many buildings of this plant at once (states (N, S), actions (N, m), grounds
        (N, r + 1)), in one compiled call."""
        per_interval, phi, force_gain, ground_start, ground_end = self._substep_maps(
            grounds.shape[1] - 1, control_dt
        )
        first, building = self.first_command, self.building
        active = actions[:, :first] @ (building.actuator_matrix[:, :first] * building.force_limits[:first]).T
        h = control_dt / ((grounds.shape[1] - 1) * per_interval)
        # numba: imported when first needed; its arguments named, so that no two can swap
        from rlcontroller.physics.integrators.dampers import damper_step_many

        return damper_step_many(
            states=states,
            active=active,
            actions=np.ascontiguousarray(actions[:, first:]),
            grounds=grounds,
            per_interval=per_interval,
            h=h,
            phi=phi,
            force_gain=force_gain,
            ground_start=ground_start,
            ground_end=ground_end,
            stories=self.stories,
            kinds=self.kinds,
            parameters=self.parameters,
        )
