"""What loads a building in training and validation: a ground motion from a ground-motion generator
(`physics.excitation`), or wind forces on its floors from a wind generator (`physics.wind`)."""

from __future__ import annotations

import numpy as np

from rlcontroller.config import GeneratorConfig, WindGeneratorConfig
from rlcontroller.physics import excitation
from rlcontroller.physics.excitation import GroundMotion
from rlcontroller.physics.structure import Building
from rlcontroller.physics.wind import generated_wind


def generate(
    config: GeneratorConfig, rng: np.random.Generator, building: Building, name: str | None = None
) -> GroundMotion:
    """One load record from the configured generator, on `building` (whose floors wind loads)."""
    if isinstance(config, WindGeneratorConfig):
        return generated_wind(config, building, rng, name or "wind")
    return excitation.generate(config, rng, name)


def generate_suite(config: GeneratorConfig, count: int, seed: int, building: Building) -> list[GroundMotion]:
    """`count` load records from one seed (the same seed gives the same suite)."""
    rng = np.random.default_rng(seed)
    return [generate(config, rng, building, f"{config.kind}_{seed}_{i}") for i in range(count)]
