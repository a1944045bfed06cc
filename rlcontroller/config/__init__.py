"""Typed, validated experiment configuration, one module per group of parts.

An experiment YAML names (or inlines) its parts: building, actuators, sensors, reward, excitation,
simulation and algorithm, and optionally plant, plant_randomization and supervisor. A part given as a
string is a path to its own YAML file, relative to the experiment file, so one building can serve many
experiments. Every model rejects unknown keys, wrong types and impossible values; `load_experiment`
turns the first problem into a one-line `ConfigError` naming the file, the key path and what was
expected, and checks the parts against each other (and the learner's keyword arguments) once, at
loading: what loads, trains.

All values are SI: kg, N/m, N, m, s, m/s^2. Every number must be finite and inside a physically sane
bound (the `MAX_*` constants of `base`); the message names the bound.

| module | holds |
|---|---|
| `base` | bounds, shared types, one-line errors, YAML input |
| `building` | building, actuators, sensors |
| `control` | reward (the cost LQG shares), supervisor |
| `excitation` | ground-motion generators |
| `plant` | integration, the simulated plant's differences, randomisation |
| `learning` | learner, policy network, schedule, search space |
| `experiment` | the whole experiment and its parts |
| `loading` | reading an experiment from YAML files, overrides |
| `checks` | the parts checked against each other, once, at loading |
| `scenarios` | robustness scenarios, the safety check's standard |
"""

from rlcontroller.bounds import (  # noqa: F401
    MAX_DURATION,
    MAX_ENVS,
    MAX_FLOORS,
    MAX_FORCE,
    MAX_GROUND_ACCELERATION,
    MAX_HISTORY,
    MAX_MASS,
    MAX_SEED,
    MAX_STIFFNESS,
    MAX_TIME_STEP,
    MAX_TOTAL_STEPS,
    MIN_TIME_STEP,
)
from rlcontroller.config.base import (  # noqa: F401
    GENERATOR_KINDS,
    MAX_NESTING,
    AccelerationRange,
    ConfigError,
    DurationRange,
    Factor,
    IntRange,
    NoiseStd,
    Quantity,
    Range,
    Scale,
    Seed,
    StrictModel,
    TimeStep,
    bounded_range,
    check_seed,
    display_path,
    finite,
    first_error,
    first_repeat,
    format_location,
    inside,
    location,
    read_yaml,
    text_byte,
    unique,
)
from rlcontroller.config.building import (  # noqa: F401
    ActuatorConfig,
    Actuators,
    BuildingConfig,
    DampingConfig,
    Devices,
    MatrixBuildingConfig,
    MeasurementConfig,
    RayleighPair,
    SensorConfig,
    paper_actuators,
)
from rlcontroller.config.checks import check_plant  # noqa: F401
from rlcontroller.config.control import (  # noqa: F401
    AssuranceConfig,
    FallbackConfig,
    RewardConfig,
    RewardTerm,
    SupervisorConfig,
)
from rlcontroller.config.excitation import (  # noqa: F401
    ExcitationConfig,
    GeneratorConfig,
    KanaiTajimiConfig,
    MixtureComponent,
    MixtureConfig,
    NearFaultConfig,
    NoiseImpulsesConfig,
    SiteBasedConfig,
    SourceConfig,
    WindGeneratorConfig,
    WindSuiteConfig,
    load_wind_suite,
    names_wind_suite,
)
from rlcontroller.config.experiment import OPTIONAL_PARTS, PARTS, Experiment  # noqa: F401
from rlcontroller.config.learner_checks import check_algorithm  # noqa: F401
from rlcontroller.config.learning import (  # noqa: F401
    AlgorithmConfig,
    PolicyConfig,
    SearchRange,
)
from rlcontroller.config.loading import build_experiment, load_experiment, with_overrides  # noqa: F401
from rlcontroller.config.plant import (  # noqa: F401
    RANDOMIZED_FIELDS,
    ActuatorDynamicsConfig,
    DamageConfig,
    HysteresisConfig,
    OpenSeesConfig,
    PlantConfig,
    PlantRandomization,
    RandomRange,
    SensorBias,
    SensorFaultConfig,
    SimulationConfig,
    randomized_plant,
)
from rlcontroller.config.scenarios import (  # noqa: F401
    SafetyCheckConfig,
    Scenario,
    ScenarioFile,
    check_generator,
    load_safety_check,
    load_scenarios,
)
from rlcontroller.config.state_space import (  # noqa: F401
    BuildingPart,
    StateSpaceBuildingConfig,
    StateSpaceInputs,
    StateSpaceOutputs,
)
from rlcontroller.devices import (  # noqa: F401
    ActiveMassConfig,
    DeviceConfig,
    MRDamperConfig,
    TunedMassConfig,
    VariableDamperConfig,
)
