"""Study: the roof active mass driver's LQG + ground model with its command band-passed around the first mode.

Usage: python studies/devices/mass_driver_band_pass.py [Q ...]   (default: 1 3)

The driver's LQG fails the safety check against the driver switched off (docs/safety_check.md) because it
amplifies the drift below and above the first mode, where the tuned mass does not act. Aimed at that: the
command passes a band-pass filter centred on the first mode (0.69 Hz; the audio cookbook's constant-peak
biquad, gain 1 and phase 0 at the centre, bilinear at the control step) of quality factor Q, so that the
driver keeps its authority near the mode and loses it away from it. The Kalman filter reads the applied,
filtered force from the observation. Prints the check's verdict for each Q.
"""

from __future__ import annotations

import sys

import numpy as np

from rlcontroller.assets import CONFIGS
from rlcontroller.config import load_experiment, load_safety_check
from rlcontroller.config.scenarios import safety_standard
from rlcontroller.control.controllers import LQGController
from rlcontroller.control.lqg import design_lqg_ground_model
from rlcontroller.evaluation.safety import safety_check
from rlcontroller.physics.plant import Plant

FIRST_MODE_HZ = 0.69  # the five-story building's first mode (docs/safety_check.md: 0.692 Hz)


class BandPassed:
    """`inner`'s actions through a band-pass biquad (centre `centre_hz`, quality `q`) per action, then
    clipped."""

    def __init__(self, inner: LQGController, centre_hz: float, q: float, dt: float) -> None:
        self.inner, self.name = inner, f"LQG + ground model, band-pass {centre_hz:g} Hz, Q {q:g}"
        w = 2.0 * np.pi * centre_hz * dt
        alpha = np.sin(w) / (2.0 * q)
        self.b = np.array([alpha, 0.0, -alpha]) / (1.0 + alpha)
        self.a = np.array([1.0 + alpha, -2.0 * np.cos(w), 1.0 - alpha]) / (1.0 + alpha)
        self.state: np.ndarray | None = None

    def reset(self) -> None:
        self.inner.reset()
        self.state = None

    def act(self, observation: np.ndarray) -> np.ndarray:
        command = np.asarray(self.inner.act(observation), dtype=float)
        if self.state is None:
            self.state = np.zeros((2, *command.shape))
        first, second = self.state  # transposed direct form II
        filtered = self.b[0] * command + first
        self.state = np.stack(
            [self.b[1] * command - self.a[1] * filtered + second, self.b[2] * command - self.a[2] * filtered]
        )
        return np.clip(filtered, -1.0, 1.0)


def main() -> None:
    plant = Plant(load_experiment(CONFIGS / "experiments" / "five_story_amd.yaml"))
    standard = load_safety_check(safety_standard(plant.experiment))
    for q in [float(value) for value in sys.argv[1:]] or [1.0, 3.0]:
        lqg = LQGController(design_lqg_ground_model(plant.design), plant.design)
        controller = BandPassed(lqg, FIRST_MODE_HZ, q, plant.control_dt)
        print("\n".join(safety_check(plant, controller, standard, scenarios=[]).lines()), flush=True)


if __name__ == "__main__":
    main()
