"""Controllers share one interface: `reset()` before a record, then `act(observation)` -> action.

The action is what the env takes: each actuator's force as a fraction of its force limit, in
[-1, 1] (force = action * force_limit, N). Every controller reads the same observation the agent
gets (the plant's `ObservationLayout` says where each reading sits) and runs in the same simulator.
`act` also takes a batch of observations, one row per building (the same rows from one `reset()`
to the next), and returns one action row per building.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from rlcontroller.config import RewardConfig
from rlcontroller.control.lqg import LQGDesign, design_lqg, design_lqg_ground_model, design_lqg_wind_model
from rlcontroller.physics.plant import Plant


class Controller(Protocol):
    name: str

    def reset(self) -> None: ...

    def act(self, observation: np.ndarray) -> np.ndarray:
        """The action for the next control step (forces / force limits, in [-1, 1]), shape (..., m)."""
        ...


class Uncontrolled:
    """Zero force: the bare building."""

    name = "uncontrolled"

    def __init__(self, n_actuators: int) -> None:
        self.n_actuators = n_actuators

    def reset(self) -> None:
        pass

    def act(self, observation: np.ndarray) -> np.ndarray:
        return np.zeros(np.shape(observation)[:-1] + (self.n_actuators,))


def residual_action(action: np.ndarray, prior_action: np.ndarray) -> np.ndarray:
    """A residual policy's rule: its action (clipped) plus the prior's, clipped to [-1, 1]."""
    return (np.asarray(action).clip(-1.0, 1.0) + prior_action).clip(-1.0, 1.0)


class LinearFeedback:
    """a = clip(W o + b): a fixed linear map of the observation, odd without a `bias` b; W is
    (m, observation size). With a `prior` (an `LQGPrior`), W o + b is a residual on the prior's
    action (`residual_action`)."""

    def __init__(
        self,
        weights: np.ndarray,
        name: str = "linear feedback",
        prior: LQGPrior | None = None,
        bias: np.ndarray | None = None,
    ) -> None:
        self.weights = np.asarray(weights, dtype=float)
        self.bias = None if bias is None else np.asarray(bias, dtype=float)
        self.name = name
        self.prior = prior

    def reset(self) -> None:
        pass

    def act(self, observation: np.ndarray) -> np.ndarray:
        observation = np.asarray(observation, dtype=float)
        action = observation @ self.weights.T
        if self.bias is not None:
            action += self.bias
        return (
            action.clip(-1.0, 1.0) if self.prior is None else residual_action(action, self.prior(observation))
        )


class LQGController:
    """Kalman filter + LQR on the observation (the same readings the agent gets), run as one linear
    system with the observation's scales folded in: its state z = [estimate, ground reading] follows
    z_k = z_(k-1) F + o_k H (the filter's update, the previous ground reading included), and the
    action is clip(z_k K) = clip(-feedback @ estimate - feedforward * ground)."""

    def __init__(self, design: LQGDesign, plant: Plant, name: str = "LQG") -> None:
        self.design = design
        self.name = name
        layout = plant.layout
        free, observed, previous_ground_gain = design.filter.on_observations(layout)
        n = free.shape[0]
        self.transition = np.zeros((n + 1, n + 1))  # F (F, H and K are read by `LQGBank`)
        self.transition[:n, :n] = free
        if previous_ground_gain is not None:
            self.transition[n, :n] = previous_ground_gain
        self.input = np.zeros((layout.size, n + 1))  # H
        self.input[:, :n] = observed
        self.input[layout.ground, n] = 1.0
        self.output = np.vstack([-design.feedback.T, -design.feedforward * layout.ground_scale])  # K
        self.reset()

    def reset(self) -> None:
        self._state: np.ndarray | None = None  # z, one row per building

    @property
    def estimate(self) -> np.ndarray | None:
        """The filter's estimate, one row per building (None before the first action)."""
        return None if self._state is None else self._state[..., :-1]

    def act(self, observation: np.ndarray) -> np.ndarray:
        observation = np.asarray(observation)
        if self._state is None:
            self._state = np.zeros(observation.shape[:-1] + (self.transition.shape[0],))
        self._state = self._state @ self.transition + observation @ self.input
        return (self._state @ self.output).clip(-1.0, 1.0)


class LQGBank:
    """Several `LQGController`s, each on its own `rows` consecutive buildings of a batch, stepped as one
    batched linear system (their states zero-padded to the largest): two batched products a step instead
    of two per controller, in the batch's hot loop. The same actions as each controller alone."""

    def __init__(self, controllers: list[LQGController], rows: int) -> None:
        size = max(controller.transition.shape[0] for controller in controllers)
        count, observations = len(controllers), controllers[0].input.shape[0]
        self.rows = rows
        self.transition = np.zeros((count, size, size))
        self.input = np.zeros((count, observations, size))
        self.output = np.zeros((count, size, controllers[0].output.shape[1]))
        for i, controller in enumerate(controllers):
            n = controller.transition.shape[0]
            self.transition[i, :n, :n] = controller.transition
            self.input[i, :, :n] = controller.input
            self.output[i, :n] = controller.output
        self._state = np.zeros((count, rows, size))

    def act(self, observations: np.ndarray) -> np.ndarray:
        """Actions (count * rows, m) for observations (count * rows, size), controller by controller."""
        count = self.transition.shape[0]
        self._state = self._state @ self.transition + observations.reshape(count, self.rows, -1) @ self.input
        return (self._state @ self.output).reshape(count * self.rows, -1).clip(-1.0, 1.0)


class LQGPrior:
    """The action of LQG + measured ground, of LQG + ground model with `sensors.ground_model`, or of
    LQG + wind model in an experiment trained under wind (action units, unclipped), from an
    observation that holds the env's own Kalman estimate (`sensors.state_estimate`), for residual
    policies: -feedback @ scaled estimate - feedforward * scaled ground reading."""

    def __init__(self, feedback: np.ndarray, feedforward: np.ndarray, layout) -> None:
        self.feedback = np.asarray(feedback, dtype=float)  # (m, estimate size), on the scaled estimate
        self.feedforward = np.asarray(feedforward, dtype=float)  # (m,), on the scaled ground reading
        self._gain = np.zeros((layout.size, self.feedback.shape[0]))  # both, as one map of the observation
        self._gain[layout.estimate] = -self.feedback.T
        self._gain[layout.ground] = -self.feedforward

    @classmethod
    def design(cls, plant: Plant) -> LQGPrior:
        """Designed on `plant`'s design model, as the estimate is: a prior never reads the simulated
        plant's parameters."""
        sensors = plant.experiment.sensors
        if not sensors.state_estimate:
            raise ValueError("a residual on LQG needs sensors.state_estimate: true")
        model = plant.design
        if model.wind is not None:
            design = design_lqg_wind_model(model)
        elif sensors.ground_model:
            design = design_lqg_ground_model(model)
        else:
            design = design_lqg(model, known_ground=True)
        layout = plant.layout
        return cls(design.feedback * layout.estimate_scale, design.feedforward * layout.ground_scale, layout)

    def __call__(self, observation: np.ndarray) -> np.ndarray:
        return np.asarray(observation, dtype=float) @ self._gain

    @property
    def observation_gain(self) -> np.ndarray:
        """The prior as one matrix (m, observation size): action = gain @ observation."""
        return self._gain.T


class ConstantCommand:
    """Every commanded device held at one action (`value`: one for all, or one per command): for
    dampers, passive-off (-1: the least voltage or damping) and passive-on (+1: the most); each
    device's fail-safe action (`Experiment.fail_safe_actions`)."""

    def __init__(self, value: float | np.ndarray, n_commands: int, name: str) -> None:
        self.value = np.broadcast_to(np.asarray(value, dtype=float), (n_commands,))
        self.n_commands, self.name = n_commands, name

    def reset(self) -> None:
        pass

    def act(self, observation: np.ndarray) -> np.ndarray:
        return np.broadcast_to(self.value, np.shape(observation)[:-1] + (self.n_commands,)).copy()


class ClippedOptimal:
    """Clipped-optimal control of semi-active dampers (Dyke, Spencer, Sain and Carlson 1996, Smart
    Mater. Struct. 5, 565-575): an LQG + ground model with the experiment's cost, designed as if
    each damper were an ideal actuator of its capacity (`Plant.active_equivalent`), whose Kalman
    filter takes the measured damper forces as the applied ones; each damper is switched fully on
    (+1) when (f_desired - f_measured) f_measured > 0, else off (-1). Needs every damper's force
    among the sensors (`quantity: force`). `reward`: another cost for the LQG (trade-off sweeps)."""

    def __init__(
        self, plant: Plant, name: str = "clipped-optimal", reward: RewardConfig | None = None
    ) -> None:
        self.name = name
        equivalent = plant.active_equivalent
        self.design = design_lqg_ground_model(equivalent, reward=reward)
        self.capacity = equivalent.force_limits
        self.layout = plant.layout
        self.force_rows = _force_rows(plant)
        self.reset()

    def reset(self) -> None:
        self.estimate: np.ndarray | None = None
        self._previous_ground = np.zeros(())

    def update(self, observation: np.ndarray) -> np.ndarray:
        """The filter's step on `observation` (the estimate kept in `estimate`); returns the measured damper
        forces (N, on the floor above: an actuator's sign)."""
        layout, design = self.layout, self.design
        observation = np.asarray(observation, dtype=float)
        readings = observation[..., layout.readings] * layout.reading_scale
        ground = observation[..., layout.ground] * layout.ground_scale
        measured = readings[..., self.force_rows]
        if self.estimate is None:
            self.estimate = np.zeros(observation.shape[:-1] + (design.filter.size,))
        held = measured / self.capacity
        self.estimate = design.filter.update(
            self.estimate, readings, held_action=held, ground=ground, previous_ground=self._previous_ground
        )
        self._previous_ground = ground
        return measured

    @staticmethod
    def switch(desired: np.ndarray, measured: np.ndarray) -> np.ndarray:
        """Each damper fully on (+1) where (f_desired - f_measured) f_measured > 0, else off (-1)."""
        return np.where((desired - measured) * measured > 0.0, 1.0, -1.0)

    def act(self, observation: np.ndarray) -> np.ndarray:
        measured = self.update(observation)
        return self.switch(-(self.estimate @ self.design.feedback.T) * self.capacity, measured)


def fail_safe_controller(plant: Plant) -> ConstantCommand:
    """Every command at its device's fail-safe action (actuators off): the safety check's reference."""
    actions = plant.experiment.fail_safe_actions()
    return ConstantCommand(actions, len(actions), "fail-safe")


def _force_rows(plant: Plant) -> np.ndarray:
    """The reading row of each commanded device's force; a clear error when one is not measured."""
    rows: dict[int, int] = {}
    start = 0
    for measurement in plant.experiment.sensors.measurements:
        count = plant.outputs(measurement.quantity)[0].shape[0]
        chosen = list(range(count)) if measurement.floors is None else [f - 1 for f in measurement.floors]
        if measurement.quantity == "force":
            rows.update({device: start + i for i, device in enumerate(chosen)})
        start += len(chosen)
    missing = [k + 1 for k in range(plant.building.n_actuators) if k not in rows]
    if missing:
        raise ValueError(
            f"clipped-optimal control needs the force of every damper measured; not of {missing}"
        )
    return np.array([rows[k] for k in range(plant.building.n_actuators)])
