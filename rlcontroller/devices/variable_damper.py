"""An ideal variable damper: F = c (drift velocity), c commanded in [damping_min, damping_max]; it can
only dissipate (F d' >= 0 for any command)."""

from __future__ import annotations

from typing import Annotated, ClassVar, Literal

from pydantic import Field, PositiveInt, model_validator

from rlcontroller.bounds import MAX_FORCE, MAX_STIFFNESS
from rlcontroller.devices.base import Damper


class VariableDamperConfig(Damper):
    """A semi-active ideal variable damper on `story`, c commanded in [damping_min, damping_max]
    (N*s/m); `capacity` (N) is the force the clipped-optimal controller's LQG designs with."""

    short: ClassVar[str] = "VD"
    kernel: ClassVar[int] = 0

    type: Literal["variable_damper"]
    story: PositiveInt
    damping_min: Annotated[float, Field(ge=0.0, le=MAX_STIFFNESS)]
    damping_max: Annotated[float, Field(gt=0.0, le=MAX_STIFFNESS)]
    capacity: Annotated[float, Field(gt=0.0, le=MAX_FORCE)]

    @model_validator(mode="after")
    def _ordered(self) -> VariableDamperConfig:
        if self.damping_min >= self.damping_max:
            raise ValueError(
                f"damping_min {self.damping_min:g} must be below damping_max {self.damping_max:g}"
            )
        return self

    def kernel_row(self) -> list[float]:
        return [self.damping_min, self.damping_max] + [0.0] * 11

    def scaled(self, factor: float) -> VariableDamperConfig:
        return self.model_copy(
            update={"damping_min": self.damping_min * factor, "damping_max": self.damping_max * factor}
        )

    def describe(self, built: None, total_mass: float) -> str:
        return (
            f"variable_damper on story {self.story}, c {self.damping_min:g}-{self.damping_max:g} N*s/m, "
            f"capacity {self.capacity / 1e3:g} kN"
        )
