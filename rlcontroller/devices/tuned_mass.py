"""A passive tuned mass damper: its configuration, Warburton's optimum tuning and the mass device
it becomes on a building (one extra degree of freedom, see `physics.structure.with_devices`), with the
end-stops of its housing (`physics.end_stops`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, PositiveInt

from rlcontroller.devices.base import Device


@dataclass(frozen=True)
class MassDevice:
    """A tuned mass (active or not) as built: on `floor` (1-based), mass (kg), stiffness (N/m) and
    damping (N*s/m) to its floor, the tuning it came from, and its limits."""

    kind: str  # tuned_mass | active_mass
    floor: int
    mass: float
    stiffness: float
    damping: float
    frequency_ratio: float
    damping_ratio: float
    mass_ratio: float
    stroke_limit: float | None  # m: its end-stops at +- this stroke; None: a free mass
    force_limit: float | None  # active masses only
    stop_stiffness: float = 0.0  # N/m, the stops' spring (with a stroke limit)
    stop_damping: float = 0.0  # N*s/m, the stops' dashpot (with a stroke limit)

    @property
    def active(self) -> bool:
        return self.force_limit is not None


STOP_FREQUENCY_HZ = 10.0  # the default stop: the device's mass rings on it at this frequency
STOP_RESTITUTION = 0.5  # the default stop's coefficient of restitution


def stop_damping_ratio(restitution: float) -> float:
    """The damping ratio of a linear spring-dashpot contact whose rebound speed is `restitution` times the
    approach speed (Anagnostopoulos 1988, Earthquake Eng. Struct. Dyn. 16, 443-456):
    zeta = -ln e / sqrt(pi^2 + ln^2 e); 0 for a perfectly elastic stop (e = 1)."""
    log = np.log(restitution)
    return float(-log / np.sqrt(np.pi**2 + log**2))


def warburton_optimum(mass_ratio: float, tuning: str = "random") -> tuple[float, float]:
    """Warburton's optimum (frequency ratio, damping ratio) of a tuned mass on an undamped primary
    under base acceleration (Warburton 1982, Earthquake Eng. Struct. Dyn. 10, 381-401, Table I):
    the same frequency ratio sqrt(1 - mu/2) / (1 + mu) for both; damping for white-noise
    (`random`, least mean-square displacement) sqrt(mu (1 - mu/4) / (4 (1 + mu)(1 - mu/2))), for
    `harmonic` excitation (least peak response) sqrt(3 mu / (8 (1 + mu)(1 - mu/2)))."""
    mu = mass_ratio
    frequency = np.sqrt(1.0 - mu / 2.0) / (1.0 + mu)
    if tuning == "random":
        return float(frequency), float(np.sqrt(mu * (1.0 - mu / 4.0) / (4.0 * (1.0 + mu) * (1.0 - mu / 2.0))))
    if tuning == "harmonic":
        return float(frequency), float(np.sqrt(3.0 * mu / (8.0 * (1.0 + mu) * (1.0 - mu / 2.0))))
    raise ValueError(f"unknown tuning {tuning!r}, expected random or harmonic")


class TunedMassConfig(Device):
    """A passive tuned mass damper: an auxiliary mass on `floor`, joined to it by a spring and a
    dashpot; its stroke is its displacement relative to the floor (m).

    `mass_ratio` is its mass over the modal mass of the target `mode` (shape scaled to 1 at
    `floor`). `frequency_ratio` (its frequency over the mode's) and `damping_ratio` default to
    Warburton's optimum for an undamped primary under base acceleration, `tuning` random (white
    noise, least mean-square displacement) or harmonic (least peak of the frequency response).

    `stroke_limit` (m) is where its housing stops it: beyond it the mass meets an end-stop, a linear spring
    (`stop_stiffness`, N/m; by default the device's mass rings on it at 10 Hz) with a dashpot that makes its
    rebound `stop_restitution` times its approach speed (Anagnostopoulos 1988). Without a stroke limit the
    mass is free (a model only: no built mass damper is)."""

    type: Literal["tuned_mass"]
    floor: PositiveInt
    mass_ratio: Annotated[float, Field(gt=0.0, le=0.5)]
    mode: PositiveInt = 1
    tuning: Literal["random", "harmonic"] = "random"
    frequency_ratio: Annotated[float, Field(gt=0.0, le=10.0)] | None = None
    damping_ratio: Annotated[float, Field(ge=0.0, lt=1.0)] | None = None
    # m: its end-stops; None: a free mass
    stroke_limit: Annotated[float, Field(gt=0.0, le=100.0)] | None = None
    stop_stiffness: Annotated[float, Field(gt=0.0, le=1e12)] | None = None  # N/m; None: STOP_FREQUENCY_HZ
    stop_restitution: Annotated[float, Field(gt=0.0, le=1.0)] = STOP_RESTITUTION

    def tuned(self, mass: np.ndarray, omega: np.ndarray, shapes: np.ndarray) -> MassDevice:
        """The device tuned on a building of mass matrix `mass` (kg) with natural frequencies `omega`
        (rad/s) and mode shapes `shapes` (the design model: a plant that differs from it gets a
        detuned device, as a real one would)."""
        shape = shapes[:, self.mode - 1] / shapes[self.floor - 1, self.mode - 1]
        device_mass = self.mass_ratio * float(shape @ mass @ shape)
        frequency_ratio, damping_ratio = warburton_optimum(self.mass_ratio, self.tuning)
        frequency_ratio = self.frequency_ratio if self.frequency_ratio is not None else frequency_ratio
        damping_ratio = self.damping_ratio if self.damping_ratio is not None else damping_ratio
        frequency = frequency_ratio * omega[self.mode - 1]
        stop_stiffness = self.stop_stiffness or device_mass * (2.0 * np.pi * STOP_FREQUENCY_HZ) ** 2
        stop_damping = 2.0 * stop_damping_ratio(self.stop_restitution) * np.sqrt(stop_stiffness * device_mass)
        return MassDevice(
            kind=self.type,
            floor=self.floor,
            mass=device_mass,
            stiffness=device_mass * frequency**2,
            damping=2.0 * damping_ratio * device_mass * frequency,
            frequency_ratio=frequency_ratio,
            damping_ratio=damping_ratio,
            mass_ratio=self.mass_ratio,
            stroke_limit=self.stroke_limit,
            force_limit=getattr(self, "force_limit", None),
            stop_stiffness=stop_stiffness if self.stroke_limit is not None else 0.0,
            stop_damping=stop_damping if self.stroke_limit is not None else 0.0,
        )

    def describe(self, built: MassDevice, total_mass: float) -> str:
        frequency = np.sqrt(built.stiffness / built.mass) / (2 * np.pi)
        text = (
            f"{self.type} on floor {self.floor}, {built.mass / 1e3:.4g} t ({self.mass_ratio:g} of mode "
            f"{self.mode}'s modal mass, {built.mass / total_mass:.3%} of the building's), {frequency:.4g} Hz "
            f"(ratio {built.frequency_ratio:.4f}), damping ratio {built.damping_ratio:.4f}"
        )
        if built.stroke_limit is None:
            return text + ", no end-stops: a free mass (stroke_limit null)"
        return text + (
            f", end-stops at +-{built.stroke_limit:g} m ({built.stop_stiffness / 1e6:.4g} MN/m, restitution "
            f"{self.stop_restitution:g})"
        )
