"""A policy as a controller: its network's deterministic action (`control.networks`), behind the observation
normalisation of training, added to a residual prior's (LQG on the env's Kalman estimate), or a classical MPC
law acting in its place. Files: `control.policy_file`; classical laws: `control.classical`."""

from __future__ import annotations

import numpy as np

from rlcontroller.control.controllers import LQGPrior, residual_action
from rlcontroller.control.mpc_controllers import ObservedMPC
from rlcontroller.control.networks import Actor, Normalizer


class PolicyController:
    """A trained policy as a controller: deterministic actions in [-1, 1] for one observation or a
    batch (one forward pass). A residual policy's action is added to its prior's (`residual_action`).

    Parameters
    ----------
    actor : the deterministic network.
    normalizer : the observation normalisation of training, if it used one.
    prior : the residual prior (maps an observation to an action), or None.
    mpc : a classical MPC law (acts in place of the network and prior), or None.
    name, source : the controller's name in tables, and what was loaded (for reports).
    steps : training steps of the saved policy; algorithm: the learner that trained it.
    """

    def __init__(
        self,
        actor: Actor,
        normalizer: Normalizer | None = None,
        prior: LQGPrior | None = None,
        name: str = "RL",
        source: str = "",
        steps: int = 0,
        algorithm: str = "",
        law: str | None = None,
        designed: str = "",
        mpc: ObservedMPC | None = None,
    ) -> None:
        self.actor, self.normalizer, self.prior, self.mpc = actor, normalizer, prior, mpc
        self.name, self.source, self.steps, self.algorithm = name, source, steps, algorithm
        self.law, self.designed = law, designed  # a classical controller's law (a key of LAWS) and its design

    def reset(self) -> None:
        if self.mpc is not None:
            self.mpc.reset()

    def act(self, observation: np.ndarray) -> np.ndarray:
        if self.mpc is not None:
            return self.mpc(observation)
        raw = observation
        if self.normalizer is not None:
            observation = self.normalizer(observation)
        action = self.actor(observation)
        if self.prior is None:
            return np.asarray(action).clip(-1.0, 1.0)
        return residual_action(action, self.prior(raw))
