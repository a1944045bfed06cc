"""The plant: what the simulator steps and the controllers are designed on, built once per experiment.

From the experiment's building, actuators, sensors and simulation: the `Building` (M, K, C, Gamma,
force limits), its control-step maps (cached per number of ground sub-steps), the sensor matrices
(readings = C z + D u, with their scales and noise) and the observation layout. The env simulates
a plant; LQG, the Kalman filters, the residual prior and the optimal reference are designed on
one; none of them rebuilds it. (A later `plant` part of an experiment, the real building differing
from the design drawings, will make two: the simulated plant and the design model.)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rlcontroller.config import Experiment, RewardTerm, SensorConfig
from rlcontroller.physics.dynamics import StepMap, ground_model_step, output_matrices, step_map
from rlcontroller.physics.excitation import GroundModel
from rlcontroller.physics.structure import Building, build


@dataclass(frozen=True)
class SensorMatrices:
    """The readings y = c z + d u (SI units, one row per reading), their scales and noise std."""

    c: np.ndarray
    d: np.ndarray  # per newton of actuator force
    scale: np.ndarray
    noise_std: np.ndarray


@dataclass(frozen=True)
class ObservationLayout:
    """Where the newest readings, ground reading, state estimate and last action sit in an
    observation, and the scales that turn them back into SI units."""

    readings: slice
    ground: int
    estimate: slice  # empty without `sensors.state_estimate`
    action: slice
    reading_scale: np.ndarray
    ground_scale: float
    estimate_scale: np.ndarray
    size: int


def sensor_matrices(building: Building, sensors: SensorConfig) -> SensorMatrices:
    """The measurement rows of `sensors`: y = C z + D u, one row per reading."""
    rows_c, rows_d, scales, noises = [], [], [], []
    for measurement in sensors.measurements:
        c, d = output_matrices(building, measurement.quantity)
        if measurement.floors is not None:
            index = [floor - 1 for floor in measurement.floors]
            c, d = c[index], d[index]
        rows_c.append(c)
        rows_d.append(d)
        scales.append(np.full(c.shape[0], measurement.scale))
        noises.append(np.full(c.shape[0], measurement.noise_std))
    return SensorMatrices(np.vstack(rows_c), np.vstack(rows_d), np.concatenate(scales), np.concatenate(noises))


def reward_matrices(
    building: Building, terms: list[RewardTerm]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[slice]]:
    """(C, D, weight^(1/power)/scale per row, one slice of rows per term) for terms on linear outputs,
    so that a term's value is the sum over its rows of |factor * (C z + D u)|^power."""
    rows_c, rows_d, factors, slices = [], [], [], []
    start = 0
    for term in terms:
        c, d = output_matrices(building, term.quantity)
        rows_c.append(c)
        rows_d.append(d)
        factors.append(np.full(c.shape[0], term.weight ** (1.0 / term.power) / term.scale))
        slices.append(slice(start, start + c.shape[0]))
        start += c.shape[0]
    if not terms:
        n_state = 2 * building.n_floors
        return np.zeros((0, n_state)), np.zeros((0, building.n_actuators)), np.zeros(0), []
    return np.vstack(rows_c), np.vstack(rows_d), np.concatenate(factors), slices


def observation_layout(building: Building, sensors: SensorConfig, n_readings: int, reading_scale: np.ndarray):
    """H blocks of (readings, ground reading), newest first, the state estimate if configured, then
    the last action."""
    n = building.n_floors
    estimate_scale = np.zeros(0)
    if sensors.state_estimate:
        estimate_scale = np.array([sensors.displacement_scale] * n + [sensors.velocity_scale] * n)
        if sensors.ground_model:
            estimate_scale = np.append(estimate_scale, GroundModel().state_scale(sensors.ground_scale))
    estimate_start = sensors.history * (n_readings + 1)
    action_start = estimate_start + estimate_scale.size
    return ObservationLayout(
        readings=slice(0, n_readings),
        ground=n_readings,
        estimate=slice(estimate_start, action_start),
        action=slice(action_start, action_start + building.n_actuators),
        reading_scale=reading_scale,
        ground_scale=sensors.ground_scale,
        estimate_scale=estimate_scale,
        size=action_start + building.n_actuators,
    )


class Plant:
    """An experiment's building with its actuators, sensors and discretisation, built once.

    Attributes: `experiment`, `building`, `force_limits` (N), `control_dt` (s), `sensors`
    (`SensorMatrices`), `layout` (`ObservationLayout`), `ground_model` (the Kanai-Tajimi model of
    LQG + ground model and of `sensors.ground_model`).
    """

    def __init__(self, experiment: Experiment) -> None:
        self.experiment = experiment
        self.building = build(experiment.building, experiment.actuators)
        self.force_limits = self.building.force_limits
        self.control_dt = experiment.simulation.control_dt
        self.sensors = sensor_matrices(self.building, experiment.sensors)
        self.layout = observation_layout(self.building, experiment.sensors, self.sensors.c.shape[0], self.sensors.scale)
        self.ground_model = GroundModel()
        self._maps: dict[int, StepMap] = {}

    def step_map(self, substeps: int = 1) -> StepMap:
        """The configured control-step map for `substeps` ground samples per step (cached)."""
        if substeps not in self._maps:
            self._maps[substeps] = step_map(self.building, self.experiment.simulation, substeps)
        return self._maps[substeps]

    def ground_model_step(self) -> StepMap:
        """Exact control-step map of the building and its Kanai-Tajimi ground model (cached)."""
        if -1 not in self._maps:
            self._maps[-1] = ground_model_step(self.building, self.control_dt, self.ground_model)
        return self._maps[-1]
