"""What every controller is judged by and acts behind: the reward (the cost LQG shares) and the supervisor."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import (
    Field,
    field_validator,
    model_validator,
)

from rlcontroller.config.base import AccelerationRange, Quantity, Scale, StrictModel


class RewardTerm(StrictModel):
    """weight * sum over components of |quantity / scale|^power, subtracted from the reward.

    `force_change` is the change of each actuator force from the previous step (N). LQG is
    designed on the quadratic terms of linear quantities (power 2, not force_change) only.
    """

    quantity: Quantity | Literal["force_change"]
    weight: Annotated[float, Field(ge=0.0, le=1.0e6)]
    scale: Scale
    power: float = Field(2.0, ge=2.0, le=16.0)

    @property
    def quadratic(self) -> bool:
        return self.power == 2.0 and self.quantity != "force_change"

    @property
    def label(self) -> str:
        return f"reward_{self.quantity}" + ("" if self.power == 2.0 else f"_p{self.power:g}")


class RewardConfig(StrictModel):
    """The terms of the reward. With `per_motion`, each episode's terms are divided by the rms of its
    ground acceleration (in m/s^2) to each term's power: a linear building's reward then does not
    depend on the motion's intensity, so weak and strong motions count alike, as in J1-J4 (where the
    plain reward is dominated by the strongest motions and a learner may act on noise in weak ones).
    LQG's design is unchanged (every quadratic term is scaled alike).

    With `baseline: uncontrolled` each step's reward is the uncontrolled building's cost at that step
    (the same ground, no force) less the controlled one's: the added part does not depend on the actions,
    so no policy's ranking changes, but most of the variance the ground brings into a critic's targets
    cancels. Learning in the batched vector env on a linear plant (`algorithm.vec_env: batched`)."""

    terms: list[RewardTerm] = Field(
        default_factory=lambda: [
            RewardTerm(quantity="drift", weight=1.0, scale=0.01),
            RewardTerm(quantity="base_shear", weight=0.5, scale=5.0e5),
            RewardTerm(quantity="force", weight=1.0, scale=1.0e5),
        ],
        min_length=1,
        max_length=50,
    )
    per_motion: bool = False
    baseline: Literal["none", "uncontrolled"] = "none"

    @model_validator(mode="after")
    def _something_to_learn(self) -> RewardConfig:
        if all(term.weight == 0.0 for term in self.terms):
            raise ValueError(
                "every weight is zero: the reward would be constant; give one term a positive weight"
            )
        return self


class AssuranceConfig(StrictModel):
    """Runtime assurance (`control.assurance`): the fail-safe twin and the switching rule's levels, on the
    risk = the controlled building's largest story envelope over the twin's (or its running peak)."""

    release: Annotated[float, Field(gt=0.0, le=2.0)] = 1.0  # hand the devices back above this risk
    engage: Annotated[float, Field(gt=0.0, le=2.0)] = 0.9  # hand control back below this risk
    # drift ratio: the smallest reference peak counted
    floor: Annotated[float, Field(ge=0.0, le=0.05)] = 1.0e-5

    @model_validator(mode="after")
    def _hysteresis(self) -> AssuranceConfig:
        if self.engage > self.release:
            raise ValueError(f"engage {self.engage} above release {self.release}: expected engage <= release")
        return self


class FallbackConfig(StrictModel):
    """Past the design model's range (`control.fallback`): once any story's estimated drift passes `drift`,
    every actuator acts for good as a viscous damper on its measured stroke velocity."""

    drift: Annotated[float, Field(gt=0.0, le=1.0)]  # m: any story's estimated drift that hands over
    damping: list[Annotated[float, Field(ge=0.0, le=1.0e9)]] = Field(min_length=1)  # N s/m, one per actuator
    deadband: Annotated[float, Field(ge=0.0, le=1.0)] = 0.0  # m/s: stroke velocity the dampers ignore (noise)


class SupervisorConfig(StrictModel):
    """The control system's supervisory layer: what stands between every controller's action and
    the actuators (`control.supervisor`). The same for every controller of the experiment."""

    # m/s^2: [off below, full authority from], on the peak ground reading

    trigger: AccelerationRange | None = None
    # pass only forces that take energy out of the building: true judges by the Kalman estimate's velocities,
    # measured by each stroke's velocity integrated from the floor accelerations (no model:
    # control/fallback.py)
    dissipative: bool | Literal["measured"] = False
    # m/s: with `dissipative`, a force that would feed its story is faded out as the estimated stroke velocity
    # grows to this (passing near a velocity reversal: no force step); 0: blocked at once (the hard clip)
    fade_velocity: Annotated[float, Field(ge=0.0, le=10.0)] = 0.0
    # measured dampers past the design model's range (control/fallback.py)
    fallback: FallbackConfig | None = None
    # runtime assurance against the fail-safe twin (control/assurance.py)
    assurance: AssuranceConfig | None = None

    @field_validator("dissipative", mode="before")
    @classmethod
    def _dissipative_kind(cls, value: object) -> object:
        if (
            value not in (True, False, "measured")
            or isinstance(value, int | float)
            and not isinstance(value, bool)
        ):
            raise ValueError(f"{value!r}: expected true, false or measured")
        return value

    @property
    def measured(self) -> bool:
        """Whether a stage reads the stroke velocities measured from the floor accelerations."""
        return self.dissipative == "measured" or self.fallback is not None

    @model_validator(mode="after")
    def _fade_needs_dissipative(self) -> SupervisorConfig:
        if self.fade_velocity > 0.0 and not self.dissipative:
            raise ValueError(
                "fade_velocity fades the dissipative rule: set dissipative: true, or leave it out"
            )
        return self
