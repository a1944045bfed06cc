"""A magnetorheological damper: Spencer, Dyke, Sain and Carlson (1997, J. Eng. Mech. 123(3), 230-238),
the phenomenological model with voltage-dependent parameters, d being the damper's stroke (the
story drift):

    F = c1 y' + k1 d,   y' = [alpha z + c0 d' + k0 (d - y)] / (c0 + c1),
    z' = -gamma |d' - y'| z |z| - beta (d' - y') z^2 + A (d' - y')        (n = 2),
    alpha, c0, c1 = (..._a + ..._b u),   u' = -eta (u - v),   v = V_max (a + 1) / 2.

The prototype's parameters (the paper's Table 1 as widely reproduced, converted to SI: N, m, s, V;
not re-read from the paper here) are `SPENCER_1997`; a damper of another capacity multiplies every
force parameter (c0, c1, k0, k1, alpha) by capacity / (alpha(V_max) z_max), z_max =
sqrt(A / (beta + gamma)) being the value z saturates at, so that its yield-like force
alpha(V_max) z_max is `capacity`. The accumulator's preload k1 x0 is left out: it only shifts the
building's static equilibrium. Its states (y, z, u, F) are stepped by `physics.integrators`.
"""

from __future__ import annotations

from typing import Annotated, ClassVar, Literal

import numpy as np
from pydantic import Field, PositiveInt

from rlcontroller.bounds import MAX_FORCE
from rlcontroller.devices.base import Damper

# Spencer et al. (1997), Table 1 (prototype MR damper, N-cm-s units converted to SI).
SPENCER_1997 = {
    "c0a": 21.0e2,  # N s/m
    "c0b": 3.50e2,  # N s/(m V)
    "k0": 46.9e2,  # N/m
    "c1a": 283.0e2,  # N s/m
    "c1b": 2.95e2,  # N s/(m V)
    "k1": 5.00e2,  # N/m
    "alpha_a": 140.0e2,  # N/m
    "alpha_b": 695.0e2,  # N/(m V)
    "gamma": 363.0e4,  # 1/m^2
    "beta": 363.0e4,  # 1/m^2
    "A": 301.0,
}
PARAMETERS = ("c0a", "c0b", "k0", "c1a", "c1b", "k1", "alpha_a", "alpha_b", "gamma", "beta", "A")
FORCE_PARAMETERS = ("c0a", "c0b", "k0", "c1a", "c1b", "k1", "alpha_a", "alpha_b")


def mr_parameters(capacity: float, max_voltage: float) -> dict[str, float]:
    """Spencer's parameters with every force parameter scaled so that alpha(V_max) z_max = capacity (N)."""
    base = SPENCER_1997
    z_max = np.sqrt(base["A"] / (base["beta"] + base["gamma"]))
    scale = capacity / ((base["alpha_a"] + base["alpha_b"] * max_voltage) * z_max)
    return {key: value * scale if key in FORCE_PARAMETERS else value for key, value in base.items()}


class MRDamperConfig(Damper):
    """A semi-active magnetorheological damper on `story`, its force parameters scaled so that its
    yield-like force alpha(V_max) z_max is `capacity` (N); commanded in voltage, 0..`max_voltage`
    (V), through the current driver's first-order lag (`eta`, 1/s)."""

    short: ClassVar[str] = "MR"
    kernel: ClassVar[int] = 1

    type: Literal["mr_damper"]
    story: PositiveInt
    capacity: Annotated[float, Field(gt=0.0, le=MAX_FORCE)]
    max_voltage: Annotated[float, Field(gt=0.0, le=10.0)] = 2.25
    eta: Annotated[float, Field(gt=0.0, le=1.0e4)] = 190.0

    def kernel_row(self) -> list[float]:
        """`PARAMETERS` (scaled), V_max (V), eta (1/s)."""
        values = mr_parameters(self.capacity, self.max_voltage)
        return [values[key] for key in PARAMETERS] + [self.max_voltage, self.eta]

    def scaled(self, factor: float) -> MRDamperConfig:
        return self.model_copy(update={"capacity": self.capacity * factor})

    def describe(self, built: None, total_mass: float) -> str:
        return (
            f"mr_damper on story {self.story}, capacity {self.capacity / 1e3:g} kN, "
            f"0-{self.max_voltage:g} V, eta {self.eta:g} 1/s"
        )
