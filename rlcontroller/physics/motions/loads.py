"""What loads a building: in training and validation a ground motion from a ground-motion generator
(`physics.motions.excitation`) or wind forces on its floors from a wind generator (`physics.motions.wind`); in
evaluation the suite a `--records` value names (`load_suite`), resolved here and nowhere else."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rlcontroller.config import (
    ConfigError,
    GeneratorConfig,
    WindGeneratorConfig,
    load_wind_suite,
    names_wind_suite,
)
from rlcontroller.errors import MotionError
from rlcontroller.physics.motions import generators
from rlcontroller.physics.motions.excitation import FLOOR_FORCES, Load
from rlcontroller.physics.motions.records import RECORDS_VARIABLE, choose_motions
from rlcontroller.physics.motions.wind import generated_wind, suite_label, wind_suite
from rlcontroller.physics.structure import Building

if TYPE_CHECKING:
    from rlcontroller.physics.plant import Plant


def generate(
    config: GeneratorConfig, rng: np.random.Generator, building: Building, name: str | None = None
) -> Load:
    """One load record from the configured generator, on `building` (whose floors wind loads)."""
    if isinstance(config, WindGeneratorConfig):
        return generated_wind(config, building, rng, name or "wind")
    return generators.generate(config, rng, name)


def generate_suite(config: GeneratorConfig, count: int, seed: int, building: Building) -> list[Load]:
    """`count` load records from one seed (the same seed gives the same suite)."""
    rng = np.random.default_rng(seed)
    return [generate(config, rng, building, f"{config.kind}_{seed}_{i}") for i in range(count)]


def load_suite(
    records: Path | str | None,
    scale_pga: float | None = None,
    plant: Plant | None = None,
    echo: Callable[[str], None] | None = None,
) -> tuple[list[Load], str]:
    """The loads a `--records` value names and their label: a folder or file of ground-motion records
    (default $RLC_RECORDS, else the labelled synthetic suite, said through `echo`), or a wind suite
    (a YAML file, kind: wind) generated on `plant`'s floors. Loads the plant cannot take are refused in
    one line (ConfigError, MotionError); without a plant a wind suite is refused. Loads of another kind than
    the plant's experiment is made for (`Experiment.load_kind`) are said through `echo`: they are judged all
    the same (a wind controller during an earthquake is a real question)."""
    records = Path(records) if records is not None else None
    if names_wind_suite(records):
        suite = load_wind_suite(records)
        if plant is None:
            raise ConfigError(f"--records {records}: a wind suite is not taken by this command")
        if scale_pga is not None:
            raise ConfigError("--scale-pga: a wind suite has no ground acceleration to scale")
        motions, label = wind_suite(suite, plant.building), suite_label(suite, str(records))
    else:
        if records is None and not os.environ.get(RECORDS_VARIABLE) and echo is not None:
            echo(
                "no --records given: using the embedded synthetic suite (labelled SYNTHETIC in every output)"
            )
        motions, label = choose_motions(records, scale_pga)
    if plant is not None:
        check_loads(plant, motions, records, echo)
    return motions, label


def check_loads(
    plant: Plant, motions: list[Load], records: Path | None, echo: Callable[[str], None] | None
) -> None:
    """Refuse, in one line, floor loads the plant cannot take or on another number of floors; say through
    `echo` when the loads are not the kind its experiment is made for."""
    floor_loads = [motion for motion in motions if motion.kind == FLOOR_FORCES]
    if floor_loads:
        refuse_floor_forces(plant, records)
    for motion in floor_loads:
        floors, building = motion.floor_forces.shape[1], plant.building
        if floors != building.n_floors:
            raise MotionError(
                f"{motion.name}: forces on {floors} floors, the building has {building.n_floors}"
            )
    made_for = plant.experiment.load_kind
    given = "wind" if motions and len(floor_loads) == len(motions) else "ground motion"
    if given != made_for and echo is not None:
        loads = "floor forces (wind)" if given == "wind" else "ground motions"
        echo(
            f"note: the controllers were made for {made_for}; these loads are {loads}: judged on loads not "
            "their own"
        )


def refuse_floor_forces(plant: Plant, records: Path | None) -> None:
    """Floor loads (wind, force records) on a plant that cannot take them: refused in one line."""
    refusal = plant.cannot_take(FLOOR_FORCES)
    if refusal is not None:
        raise ConfigError(f"--records {records}: {refusal}; use ground-motion records")
