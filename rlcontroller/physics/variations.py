"""How a simulated plant differs from its design model: the `plant` part's factors and damage applied to
the building (a damper stronger or weaker than designed is its own `scaled`), and random plant parts drawn
from a `plant_randomization` (or its centre, what a careful engineer designs on)."""

from __future__ import annotations

import numpy as np

from rlcontroller.config import (
    RANDOMIZED_FIELDS,
    BuildingPart,
    MatrixBuildingConfig,
    PlantConfig,
    PlantRandomization,
    StateSpaceBuildingConfig,
    randomized_plant,
)


def true_building(building: BuildingPart, plant: PlantConfig) -> BuildingPart:
    """The design building (or the plant part's own `building`) changed by the plant part: factors and
    damage on stiffness, factors on mass, the damping ratios (or the damping matrix) times the damping
    factor. A building given by matrices takes scalar factors only, a state-space model none (checked at
    loading)."""
    building = plant.building if plant.building is not None else building
    if isinstance(building, StateSpaceBuildingConfig):
        return building
    if isinstance(building, MatrixBuildingConfig):
        update = {
            "mass_matrix": (np.asarray(building.mass_matrix) * plant.mass).tolist(),
            "stiffness_matrix": (np.asarray(building.stiffness_matrix) * plant.stiffness).tolist(),
        }
        if building.damping_matrix is not None:
            update["damping_matrix"] = (np.asarray(building.damping_matrix) * plant.damping).tolist()
        else:
            update["modal_damping"] = [ratio * plant.damping for ratio in building.modal_damping]
        return building.model_copy(update=update)
    n = len(building.masses)
    stiffness = np.asarray(building.stiffnesses) * np.broadcast_to(
        np.asarray(plant.stiffness, dtype=float), n
    )
    for damage in plant.damage:
        stiffness[damage.story - 1] *= 1.0 + damage.stiffness
    masses = np.asarray(building.masses) * np.broadcast_to(np.asarray(plant.mass, dtype=float), n)
    damping = building.damping
    if damping.rayleigh is not None:
        pairs = tuple(
            pair.model_copy(update={"ratio": pair.ratio * plant.damping}) for pair in damping.rayleigh
        )
        damping = damping.model_copy(update={"rayleigh": pairs})
    else:
        damping = damping.model_copy(update={"matrix": (np.asarray(damping.matrix) * plant.damping).tolist()})
    return building.model_copy(
        update={"masses": masses.tolist(), "stiffnesses": stiffness.tolist(), "damping": damping}
    )


def draw_plant(
    randomization: PlantRandomization, base: PlantConfig | None, rng: np.random.Generator
) -> PlantConfig:
    """One random plant part: the ranged fields drawn (uniform, log-uniform or whole numbers) with `rng`,
    in the fixed order of RANDOMIZED_FIELDS (a field added there goes last: earlier draws stay), the rest
    from `base`."""
    values: dict[str, float] = {}
    for key in RANDOMIZED_FIELDS:
        bounds = getattr(randomization, key)
        if bounds is None:
            continue
        if isinstance(bounds, tuple):
            values[key] = int(rng.integers(bounds[0], bounds[1] + 1))
        elif bounds.log:
            values[key] = float(np.exp(rng.uniform(np.log(bounds.low), np.log(bounds.high))))
        else:
            values[key] = float(rng.uniform(bounds.low, bounds.high))
    return randomized_plant(base, values)


def centre_of_ranges(randomization: PlantRandomization, base: PlantConfig | None) -> PlantConfig:
    """The plant part at the centre of the structural and sensor ranges (the geometric centre of log
    ranges), with the actuator dynamics of `base` (the nominal ones): what a careful engineer designs
    on without knowing which plant it will be."""
    values: dict[str, float] = {}
    for key in ("stiffness", "mass", "damping", "noise_factor", "device_frequency"):
        bounds = getattr(randomization, key)
        if bounds is None:
            continue
        if bounds.log:
            values[key] = float(np.sqrt(bounds.low * bounds.high))
        else:
            values[key] = 0.5 * (bounds.low + bounds.high)
    return randomized_plant(base, values)
