"""An active mass driver (active tuned mass damper): a tuned mass with an actuator between its floor
and the mass. Switched off, it is the tuned mass it was built as."""

from __future__ import annotations

from typing import Annotated, ClassVar, Literal

from pydantic import Field

from rlcontroller.bounds import MAX_FORCE
from rlcontroller.devices.tuned_mass import MassDevice, TunedMassConfig


class ActiveMassConfig(TunedMassConfig):
    """A tuned mass with an actuator between the floor and the mass, commanded like an actuator, with
    a force limit (N) and a stroke limit (m): its end-stops, as a tuned mass's."""

    fail_safe_action: ClassVar[float | None] = 0.0  # switched off: the tuned mass

    type: Literal["active_mass"]  # type: ignore[assignment]
    force_limit: Annotated[float, Field(gt=0.0, le=MAX_FORCE)]
    stroke_limit: Annotated[float, Field(gt=0.0, le=100.0)]  # type: ignore[assignment]

    def command_label(self) -> str:
        return f"AMD {self.floor}"

    def describe(self, built: MassDevice, total_mass: float) -> str:
        return super().describe(built, total_mass) + f", force limit {self.force_limit / 1e3:g} kN"
