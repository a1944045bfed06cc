"""The plant protocol: what the closed loop (`learning.env`, `simulation.batch`), evaluation and the
controllers' designs read of a plant. `physics.plant.Plant` implements it for every plant `rlc` builds
(linear, with actuator dynamics, yielding stories, semi-active dampers, an OpenSees model as its `fe_model`
integrator, `physics.fe.opensees`); a model from outside (an identified state-space model) implements the
same and nothing else changes.

Like do-mpc's `model`, compiled once (`Model.setup()`), one object serves the simulator, the estimator and
the controllers: `sampled(r)`, the plant sampled at its control step with r load samples per step
(`physics.sampled.SampledPlant`), holds every discrete map of it, built once and kept:

- the **simulator** steps the state x (`n_state`) of a control step as one linear map (`sampled(r).step`,
  with `sampled(r).forcing` adding the load's terms) or, where the plant has its own `integrator`, through
  that; every response is linear in x, the held command and the floor loads (`outputs`, `load_outputs`),
  which is what the sensors read and J1-J4 and the device metrics are taken from (`sampled(r).response`);
  the estimators and LQG, MPC and the learners' priors take the design model's `sampled().step`,
  `.ground_model` or `.wind_model`;
- the **loads** it takes: `cannot_take(kind)` says in one line why a load kind (`excitation.FLOOR_FORCES`,
  `GROUND_ACCELERATION`) is refused;
- the **design model** (`design`) is a linear plant built from what an engineer knows — LQG, MPC, the
  Kalman filters and the learners' priors are designed on it, never on the plant itself; `bare` is the
  building without its devices (the uncontrolled reference of every J).
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from rlcontroller.config import Experiment
from rlcontroller.physics.sampled import SampledPlant
from rlcontroller.physics.structure import Building


@runtime_checkable
class Integrator(Protocol):
    """A plant's own step, where a control step is not one linear map (yielding stories, dampers, a model
    from outside): the state after one step of `control_dt` with `action` (forces / force limits) held and
    `ground` the r + 1 ground samples (m/s^2) spanning the step."""

    def step(
        self, state: np.ndarray, action: np.ndarray, ground: np.ndarray, control_dt: float
    ) -> np.ndarray: ...


@runtime_checkable
class SimulatedPlant(Protocol):
    """What is simulated, and what the controllers are designed on (`design`)."""

    experiment: Experiment  # its sensors, reward, supervisor and generators
    building: Building  # degrees of freedom, floors, actuators and force limits (N), devices
    control_dt: float  # s
    n_state: int  # length of the state x
    force_limits: np.ndarray  # N, one per command
    integrator: Integrator | None  # None: the step is `step_map`
    fe_model: Integrator | None  # a model of one domain per process (OpenSees): runs fan out over processes

    @property
    def design(self) -> SimulatedPlant: ...

    @property
    def bare(self) -> SimulatedPlant: ...

    def outputs(self, quantity: str) -> tuple[np.ndarray, np.ndarray]: ...

    def load_outputs(self, quantity: str) -> np.ndarray: ...

    def sampled(self, substeps: int = 1) -> SampledPlant: ...

    def cannot_take(self, kind: str) -> str | None: ...
