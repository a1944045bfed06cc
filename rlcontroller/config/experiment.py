"""A whole experiment: its parts, each validated on its own (read and checked across parts by `loading`)."""

from __future__ import annotations

from typing import Annotated, Any

import yaml
from pydantic import (
    Field,
    PrivateAttr,
)

from rlcontroller.config.base import (
    Seed,
    StrictModel,
)
from rlcontroller.config.building import (
    Actuators,
    BuildingConfig,
    Devices,
    SensorConfig,
    paper_actuators,
)
from rlcontroller.config.control import RewardConfig, SupervisorConfig
from rlcontroller.config.excitation import ExcitationConfig, WindGeneratorConfig
from rlcontroller.config.learning import (
    AlgorithmConfig,
)
from rlcontroller.config.plant import (
    PlantConfig,
    PlantRandomization,
    SimulationConfig,
)
from rlcontroller.config.state_space import BuildingPart

PARTS: dict[str, Any] = {
    "building": BuildingConfig,
    "actuators": Actuators,
    "devices": Devices,
    "sensors": SensorConfig,
    "reward": RewardConfig,
    "excitation": ExcitationConfig,
    "simulation": SimulationConfig,
    "algorithm": AlgorithmConfig,
    "plant": PlantConfig,
    "plant_randomization": PlantRandomization,
    "supervisor": SupervisorConfig,
}


LEARNED_ON_FE_MODEL = (
    "# learned on the OpenSees model"  # a run folder's config.yaml: resumed only with it named
)
OPTIONAL_PARTS = ("plant", "plant_randomization", "supervisor")  # may be null: see the fields of Experiment


class Experiment(StrictModel):
    """A whole experiment. `Experiment()` is the paper's five-story case."""

    name: Annotated[str, Field(min_length=1, max_length=100, pattern=r"^[A-Za-z0-9_.+-]+$")] = "paper_sac"
    seed: Seed = 0
    building: BuildingPart = BuildingConfig()
    actuators: Actuators = Field(default_factory=paper_actuators)
    devices: Devices = []  # tuned masses and active mass drivers (see config.building)
    sensors: SensorConfig = SensorConfig()
    reward: RewardConfig = RewardConfig()
    excitation: ExcitationConfig = ExcitationConfig()
    simulation: SimulationConfig = SimulationConfig()
    algorithm: AlgorithmConfig = AlgorithmConfig()
    plant: PlantConfig | None = None  # None: the simulated building is the design model
    plant_randomization: PlantRandomization | None = None  # training and validation only
    supervisor: SupervisorConfig | None = None  # None: actions go to the actuators as they are
    _origins: dict[str, tuple[str, str]] = PrivateAttr(default_factory=dict)

    def origin(self, part: str) -> tuple[str, str]:
        """(file, key prefix) of a part, for error messages."""
        return self._origins.get(part, ("<default>", part))

    @property
    def has_dampers(self) -> bool:
        """Semi-active dampers among the devices."""
        return any(device.semi_active for device in self.devices)

    @property
    def load_kind(self) -> str:
        """What the building is controlled against: "wind" or "ground motion" (its excitation's kind)."""
        return "wind" if isinstance(self.excitation.generator, WindGeneratorConfig) else "ground motion"

    def hardware(self) -> dict:
        """What a controller is made for, beyond its own sensors and cost: the building (and the plant part
        simulated for it), its actuators and devices, and the load: experiments that agree here can share one.
        Where a building's matrices were read from (`source`) is not what it is."""
        parts = {"building", "plant", "actuators", "devices"}
        return self.model_dump(mode="json", include=parts, exclude={"building": {"source"}}) | {
            "load": self.load_kind
        }

    def commanded_devices(self) -> list:
        """The devices that take a command, in the action's order after the actuators: the mass
        drivers, then the dampers."""
        commanded = [device for device in self.devices if device.command_label() is not None]
        return [d for d in commanded if not d.semi_active] + [d for d in commanded if d.semi_active]

    def command_labels(self) -> list[str]:
        """Short labels of the commanded devices, in the order of the action: each actuator's story,
        then each commanded device's ("AMD 5", "MR 1", "VD 1")."""
        return [str(actuator.story) for actuator in self.actuators] + [
            device.command_label() for device in self.commanded_devices()
        ]

    def fail_safe_actions(self) -> list[float]:
        """The action, in the order of `command_labels`, of a controller that has failed safe: each
        actuator off (0), each device at its fail-safe action (a driver off, a damper at its minimum)."""
        return [0.0] * len(self.actuators) + [device.fail_safe_action for device in self.commanded_devices()]

    def to_yaml(self) -> str:
        """The resolved experiment as a folder keeps it. An OpenSees plant is left out (a folder never runs
        code, `config.loading.UNTRUSTED_MODEL`): a comment names its file; the building is its reduced
        model."""
        if self.plant is None or self.plant.opensees is None:
            return yaml.safe_dump(self.model_dump(mode="json"), sort_keys=False)
        note = (
            f"# plant: the OpenSees model {self.plant.opensees.model} (not kept: a folder never runs code)\n"
        )
        if self.plant.opensees.train_on == "fe":
            note += f"{LEARNED_ON_FE_MODEL}: resume with rlc train EXPERIMENT --resume RUN\n"
        return note + yaml.safe_dump(self.model_dump(mode="json") | {"plant": None}, sort_keys=False)
