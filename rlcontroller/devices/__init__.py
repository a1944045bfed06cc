"""The device types a building can carry, one module each, and their registry.

Each type is its configuration schema (a `devices.base.Device`) carrying what the rest of rlc
needs of it: where it sits, whether it is a mass device (a degree of freedom, `tuned` on the
design model) or a semi-active damper (a command column and its law in the compiled damper step),
its command's label, its fail-safe command and its one-line description. Adding a type: write its
module and list its class in `DEVICE_TYPES` (docs/architecture.md, "Adding a device type").
"""

from typing import Annotated, Union

from pydantic import Field

from rlcontroller.devices.active_mass import ActiveMassConfig
from rlcontroller.devices.base import Damper, Device
from rlcontroller.devices.mr_damper import MRDamperConfig
from rlcontroller.devices.tuned_mass import MassDevice, TunedMassConfig
from rlcontroller.devices.variable_damper import VariableDamperConfig

DEVICE_TYPES = (TunedMassConfig, ActiveMassConfig, VariableDamperConfig, MRDamperConfig)
DeviceConfig = Annotated[Union[DEVICE_TYPES], Field(discriminator="type")]  # noqa: UP007

__all__ = [
    "DEVICE_TYPES",
    "ActiveMassConfig",
    "Damper",
    "Device",
    "DeviceConfig",
    "MRDamperConfig",
    "MassDevice",
    "TunedMassConfig",
    "VariableDamperConfig",
]
