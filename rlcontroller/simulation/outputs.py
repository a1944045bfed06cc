"""What one control step of a plant puts out, as one matrix product of the new state and the command:
the sensors' scaled readings, the reward terms, drift, absolute acceleration, base shear and the
delivered force (`StepOutputs`); and the sensors' noise and bias for a whole motion
(`noisy_readings`). The env and the batch both step with these."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rlcontroller.control.cost import reward_matrices
from rlcontroller.physics.plant import Plant


@dataclass(frozen=True)
class StepOutputs:
    """Every output of a control step as one matrix product of the new state x and the command u:
    [scaled readings | ground reading | weight^(1/power)/scale * reward quantities | drift |
    absolute acceleration | base shear | delivered force] = c x + d u (u in N). The ground reading
    row is zero here: it comes in, with the sensor noise, through the forcing. The slices index the
    outputs."""

    c: np.ndarray
    d: np.ndarray
    load: np.ndarray  # per newton of floor force (rows x floors)
    readings: slice  # scaled readings and the ground reading
    reward: slice
    drift: slice
    acceleration: slice
    base_shear: int
    force: slice
    reward_names: list[str]  # linear terms first, then force-change terms
    reward_starts: np.ndarray  # first row of each term among the reward rows (then the change rows)
    term_power: np.ndarray  # each term's power, in the order of reward_names
    per_motion: bool  # `reward.per_motion`
    row_power: np.ndarray
    quadratic: bool  # every term squared
    change_factor: np.ndarray | None  # force limit * weight^(1/power) / scale per change row

    def reward_terms(
        self, weighted: np.ndarray, action: np.ndarray, previous_action: np.ndarray
    ) -> np.ndarray:
        """Each reward term's value (positive: the reward is minus their sum), shape (..., terms), from
        the outputs' weighted reward rows `outputs[..., reward]` and the action held over the step and
        over the step before."""
        if self.change_factor is not None:
            repeats = self.change_factor.size // action.shape[-1]
            change = np.tile(action - previous_action, repeats) * self.change_factor
            weighted = np.concatenate([weighted, change], axis=-1)
        values = weighted * weighted if self.quadratic else np.abs(weighted) ** self.row_power
        starts, rows = self.reward_starts, values.shape[-1]
        if starts.size and starts[-1] < rows and np.all(np.diff(starts) > 0):
            return np.add.reduceat(values, starts, axis=-1)
        # a term without rows (the force of a building with nothing to command) is 0; reduceat would not say
        # so
        ends = np.append(starts[1:], rows)
        padded = np.concatenate([values, np.zeros(values.shape[:-1] + (1,))], axis=-1)
        return np.where(ends > starts, np.add.reduceat(padded, np.minimum(starts, rows), axis=-1), 0.0)

    def term_factors(self, ground: np.ndarray) -> np.ndarray:
        """Each term's factor for an episode whose ground acceleration at the control steps is
        `ground` (m/s^2): 1, or with `reward.per_motion` (1 m/s^2 / rms)^power (rms floored at
        1e-6 m/s^2)."""
        if not self.per_motion:
            return np.ones(self.term_power.size)
        rms = max(float(np.sqrt(np.mean(np.square(ground)))), 1e-6)
        return rms ** (-self.term_power)


def step_outputs(plant: Plant) -> StepOutputs:
    """The output rows of `plant` for its experiment's sensors and reward."""
    experiment, sensors = plant.experiment, plant.sensors
    n, m = plant.building.n_floors, plant.building.n_actuators
    linear_terms = [t for t in experiment.reward.terms if t.quantity != "force_change"]
    change_terms = [t for t in experiment.reward.terms if t.quantity == "force_change"]
    reward_c, reward_d, reward_factor, reward_slices = reward_matrices(plant, linear_terms)
    starts = [rows.start for rows in reward_slices] + [
        reward_c.shape[0] + i * m for i in range(len(change_terms))
    ]
    row_powers = [
        np.full(rows.stop - rows.start, t.power) for t, rows in zip(linear_terms, reward_slices, strict=True)
    ]
    row_powers += [np.full(m, t.power) for t in change_terms]
    change_factor = None
    if change_terms:
        change_factor = np.concatenate(
            [plant.force_limits * t.weight ** (1 / t.power) / t.scale for t in change_terms]
        )
    blocks = [
        (sensors.c / sensors.scale[:, None], sensors.d / sensors.scale[:, None]),
        (np.zeros((1, plant.n_state)), np.zeros((1, m))),
        (reward_c * reward_factor[:, None], reward_d * reward_factor[:, None]),
        plant.outputs("drift"),
        plant.outputs("absolute_acceleration"),
        plant.outputs("base_shear"),
        plant.outputs("force"),
    ]
    loads = [sensors.load / sensors.scale[:, None], np.zeros((1, n))]
    for term, rows in zip(linear_terms, reward_slices, strict=True):
        loads.append(plant.load_outputs(term.quantity) * reward_factor[rows, None])
    loads += [plant.load_outputs(q) for q in ("drift", "absolute_acceleration", "base_shear")]
    loads.append(np.zeros((m, n)))
    p, r = sensors.c.shape[0], reward_c.shape[0]
    shear = p + 1 + r + 2 * n
    return StepOutputs(
        c=np.vstack([c for c, _ in blocks]),
        d=np.vstack([d for _, d in blocks]),
        load=np.vstack(loads),
        readings=slice(0, p + 1),
        reward=slice(p + 1, p + 1 + r),
        drift=slice(p + 1 + r, p + 1 + r + n),
        acceleration=slice(p + 1 + r + n, shear),
        base_shear=shear,
        force=slice(shear + 1, shear + 1 + m),
        reward_names=[term.label for term in linear_terms + change_terms],
        reward_starts=np.array(starts, dtype=int),
        term_power=np.array([term.power for term in linear_terms + change_terms]),
        per_motion=experiment.reward.per_motion,
        row_power=np.concatenate(row_powers),
        quadratic=all(term.power == 2.0 for term in experiment.reward.terms),
        change_factor=change_factor,
    )


def noisy_readings(plant: Plant, ground: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The noise and bias of every scaled reading at the K + 1 instants of `ground` (the ground
    samples at the control steps), with the noisy scaled ground reading as the last column:
    (K + 1, p + 1). The noise is drawn readings first, then ground, as every run draws it."""
    sensors, config = plant.sensors, plant.experiment.sensors
    p = sensors.c.shape[0]
    readings = np.empty((ground.size, p + 1))
    readings[:, :p] = rng.standard_normal((ground.size, p)) * (sensors.noise_std / sensors.scale)
    readings[:, :p] += sensors.bias / sensors.scale
    readings[:, p] = (
        ground + config.ground_noise_std * rng.standard_normal(ground.size)
    ) / config.ground_scale
    return readings
