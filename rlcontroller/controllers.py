"""Controllers share one interface: `reset()` before a record, then `act(observation)` -> forces (N).

Every controller runs in the same environment (same simulator, sensors, noise and force limits);
`rollout` drives one through one ground motion and returns the full response.
"""

from __future__ import annotations

from pathlib import Path
from typing import Protocol

import numpy as np

from rlcontroller.dynamics import Response, response
from rlcontroller.env import BuildingEnv
from rlcontroller.excitation import GroundMotion


class Controller(Protocol):
    name: str

    def reset(self) -> None: ...

    def act(self, observation: np.ndarray) -> np.ndarray:
        """Actuator forces (N) for the next control step."""
        ...


class Uncontrolled:
    """Zero force: the bare building."""

    name = "uncontrolled"

    def __init__(self, n_actuators: int) -> None:
        self._zero = np.zeros(n_actuators)

    def reset(self) -> None:
        pass

    def act(self, observation: np.ndarray) -> np.ndarray:
        return self._zero


class PolicyController:
    """A trained stable-baselines3 policy, deterministic actions scaled to the force limits.

    `normalize` is the run's observation normaliser (a VecNormalize), if it used one; `prior`
    maps an observation to the action the policy's output is added to (residual policies).
    """

    def __init__(
        self, model, force_limits: np.ndarray, normalize=None, name: str = "RL", prior=None, source: str = ""
    ) -> None:
        self.model = model
        self.source = source  # the saved model file, for reports
        self.force_limits = force_limits
        self.normalize = normalize
        self.name = name
        self.prior = prior

    @classmethod
    def load(cls, model_path: Path, force_limits: np.ndarray, name: str = "RL") -> PolicyController:
        from rlcontroller.training import load_policy

        model, normalize, prior = load_policy(model_path)
        return cls(model, force_limits, normalize, name, prior, source=str(model_path))

    def reset(self) -> None:
        pass

    def act(self, observation: np.ndarray) -> np.ndarray:
        raw = observation
        if self.normalize is not None:
            observation = self.normalize.normalize_obs(observation)
        action, _ = self.model.predict(observation, deterministic=True)
        action = np.clip(action, -1.0, 1.0)
        if self.prior is not None:
            action = np.clip(action + self.prior(raw), -1.0, 1.0)
        return action * self.force_limits


def rollout(env: BuildingEnv, motion: GroundMotion, controller: Controller, seed: int = 0) -> tuple[Response, float]:
    """Run `controller` on `motion` in `env` (sensor noise seeded by `seed`).

    Returns the whole response and the episode's total reward.
    """
    observation, info = env.reset(seed=seed, options={"motion": motion})
    controller.reset()
    n_steps = info["steps"]
    n_state = 2 * env.building.n_floors
    states = np.zeros((n_steps + 1, n_state))
    held = np.zeros((n_steps + 1, env.building.n_actuators))
    total_reward = 0.0
    for k in range(1, n_steps + 1):
        force = controller.act(observation)
        observation, reward, _, _, _ = env.step(force / env.force_limits)
        total_reward += reward
        states[k] = env.state
        held[k] = env.held_force
    time = np.arange(n_steps + 1) * env.control_dt
    return response(env.building, states, held, time, env.ground_samples), total_reward
