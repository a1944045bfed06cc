"""The sensors on a plant: each reading a row of y = C x + D u + load F on the plant's state x, command u
and floor forces F (SI), with its scale, noise and the plant's sensor faults (dead floors, noise factor,
bias)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from rlcontroller.config import SensorConfig, SensorFaultConfig
from rlcontroller.physics.dynamics import load_feedthrough
from rlcontroller.physics.structure import Building


@dataclass(frozen=True)
class SensorMatrices:
    """The readings y = c z + d u + load F (SI units, one row per reading; F the floor forces, N),
    their scales and noise std."""

    c: np.ndarray
    d: np.ndarray  # per newton of actuator force
    load: np.ndarray  # per newton of floor force (absolute accelerations only)
    scale: np.ndarray
    noise_std: np.ndarray
    bias: np.ndarray  # constant added to each reading (SI), zero without sensor faults


def sensor_matrices(
    outputs: Callable[[str], tuple[np.ndarray, np.ndarray]],
    building: Building,
    sensors: SensorConfig,
    faults: SensorFaultConfig | None = None,
) -> SensorMatrices:
    """The measurement rows of `sensors` on a plant's state: y = C x + D u, one row per reading, from the
    plant.s `outputs(quantity)` -> (C, D), with its sensor faults (the `sensors` of its plant part:
    dead floors read zero, noise times a factor, constant bias)."""
    rows_c, rows_d, rows_load, scales, noises, floors = [], [], [], [], [], []
    for measurement in sensors.measurements:
        c, d = outputs(measurement.quantity)
        index = list(range(c.shape[0])) if measurement.floors is None else [f - 1 for f in measurement.floors]
        rows_c.append(c[index])
        rows_d.append(d[index])
        rows_load.append(load_feedthrough(building, measurement.quantity)[index])
        scales.append(np.full(len(index), measurement.scale))
        noises.append(np.full(len(index), measurement.noise_std))
        floors.extend(i + 1 for i in index)
    c, d, load, noise = np.vstack(rows_c), np.vstack(rows_d), np.vstack(rows_load), np.concatenate(noises)
    bias = np.zeros(c.shape[0])
    if faults is not None:
        floors_array = np.array(floors)
        noise = noise * faults.noise_factor
        for entry in faults.bias:
            bias[floors_array == entry.floor] += entry.value
        dead = np.isin(floors_array, faults.dead_floors)
        c[dead], d[dead], load[dead], noise[dead], bias[dead] = 0.0, 0.0, 0.0, 0.0, 0.0
    return SensorMatrices(c, d, load, np.concatenate(scales), noise, bias)
