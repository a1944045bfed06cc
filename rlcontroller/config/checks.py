"""The checks across an experiment's parts, once, at loading: what the reward, sensors, supervisor and
learner ask of the building, actuators and devices, the time steps, the randomisation ranges, a plant
part against its building, and the learner's settings (`config.learner_checks`)."""

from __future__ import annotations

from pydantic import ValidationError

from rlcontroller.config.base import ConfigError, format_location, location
from rlcontroller.config.building import MatrixBuildingConfig
from rlcontroller.config.experiment import Experiment
from rlcontroller.config.learner_checks import check_algorithm
from rlcontroller.config.plant import RANDOMIZED_FIELDS, PlantConfig, randomized_plant
from rlcontroller.config.state_space import StateSpaceBuildingConfig


def check_cross_references(experiment: Experiment) -> None:
    check_algorithm(experiment)
    supervisor, sensors = experiment.supervisor, experiment.sensors
    if supervisor is not None and supervisor.measured:
        _check_measured_velocity(experiment)
    assured = supervisor is not None and supervisor.assurance is not None
    twin = "the fail-safe twin is the Kalman estimate's"
    estimate_users = [  # (part, field, asked, what the estimate is to it)
        ("algorithm", "residual_lqg", experiment.algorithm.residual_lqg, "the prior's feedback"),
        (
            "supervisor",
            "dissipative",
            supervisor is not None and supervisor.dissipative is True,
            "its velocities",
        ),
        ("supervisor", "assurance", assured, twin),
        ("sensors", "ground_model", sensors.ground_model, "its states join the estimate"),
        ("sensors", "twin", sensors.twin, twin),
    ]
    for part, key, asked, why in estimate_users:
        if asked and not sensors.state_estimate:
            raise ConfigError(
                f"{location(*experiment.origin(part), key)}: needs sensors.state_estimate: true ({why})"
            )
        if asked and key in ("assurance", "twin") and experiment.has_dampers:
            raise ConfigError(
                f"{location(*experiment.origin(part), key)}: not with semi-active dampers (a command "
                "is not a force: the twin cannot take its response out)"
            )
        stopped = any(getattr(device, "stroke_limit", None) is not None for device in experiment.devices)
        if asked and key in ("assurance", "twin") and stopped:
            raise ConfigError(
                f"{location(*experiment.origin(part), key)}: not with a mass device on end-stops (its "
                "stroke_limit): the stops make the building nonlinear and the twin is superposition"
            )
    if (cutoff := sensors.integration_cutoff) is not None:
        where = location(*experiment.origin("sensors"), "integration_cutoff")
        if sensors.state_estimate:
            raise ConfigError(
                f"{where}: the observation holds either integrated readings or state_estimate, not both"
            )
        nyquist = 0.5 / experiment.simulation.control_dt
        if cutoff >= 0.5 * nyquist:
            raise ConfigError(
                f"{where}: {cutoff:g} Hz, expected below half the Nyquist frequency ({0.5 * nyquist:g} Hz)"
            )
    fe_model = experiment.plant.opensees if experiment.plant is not None else None
    if fe_model is not None and experiment.devices:
        raise ConfigError(
            f"{location(*experiment.origin('devices'), '')}: not with an OpenSees plant: model the devices "
            "in its file"
        )
    if fe_model is not None and fe_model.train_on == "fe":
        _check_learning_on_fe_model(experiment)
    models = [(experiment.building, *experiment.origin("building"))]
    if experiment.plant is not None and experiment.plant.building is not None:
        file, prefix = experiment.origin("plant")
        models.append((experiment.plant.building, file, location("", prefix, "building").lstrip(": ")))
    for building, file, prefix in models:
        if isinstance(building, StateSpaceBuildingConfig):
            _check_state_space(building, experiment, file, prefix)
    n_floors = experiment.building.n_floors
    file, prefix = experiment.origin("actuators")
    if not experiment.actuators and not experiment.devices:
        raise ConfigError(f"{location(file, prefix, '')}: no actuators and no devices: expected at least one")
    for index, story in enumerate(actuator.story for actuator in experiment.actuators):
        if story > n_floors:
            raise ConfigError(
                f"{file}: {prefix}[{index}].story: story {story} does not exist, expected 1..{n_floors}"
            )
    _check_devices(experiment)
    file, prefix = experiment.origin("sensors")
    masses = sum(d.type in ("tuned_mass", "active_mass") for d in experiment.devices)
    counts = {
        "force": (len(experiment.command_labels()), "commanded device"),
        "stroke": (masses, "mass device"),
    }
    for index, measurement in enumerate(experiment.sensors.measurements):
        key = format_location(("measurements", index, "floors"), prefix)
        count, what = counts.get(measurement.quantity, (n_floors, "floor"))
        if count == 0:
            raise ConfigError(
                f"{file}: {format_location(('measurements', index), prefix)}: there is no {what}"
            )
        for floor in measurement.floors or []:
            if floor > count:
                raise ConfigError(f"{file}: {key}: {what} {floor} does not exist, expected 1..{count}")
    _check_time_steps(experiment)
    if any(source.kind == "wind" for source in experiment.excitation.sources()):
        yielding = experiment.plant is not None and experiment.plant.hysteresis is not None
        if yielding or experiment.has_dampers:
            where = location(*experiment.origin("excitation"), "generator")
            raise ConfigError(f"{where}: wind loads with yielding stories or dampers are not modelled")
    if experiment.plant is not None:
        check_plant(experiment.plant, experiment, *experiment.origin("plant"))
    if experiment.plant_randomization is not None:
        _check_randomization(experiment)


def _check_state_space(
    building: StateSpaceBuildingConfig, experiment: Experiment, file: str, prefix: str
) -> None:
    """What a state-space model can be in an experiment: a building with its actuators' inputs and the
    responses its sensors and reward read, no devices, stepped exactly at a multiple of its sample time."""
    count, columns = len(experiment.actuators), len(building.inputs.actuators)
    if count != columns:
        where = location(file, prefix, "inputs.actuators")
        raise ConfigError(
            f"{where}: {columns} columns, expected one per actuator ({count}, in the actuators' order)"
        )
    refusals = {
        "devices": (
            experiment.devices,
            "devices on a state-space model are not modelled (it has no floors to attach them to)",
        ),
        "simulation": (
            experiment.simulation.method != "exact",
            "method: newmark needs M, K, C; a state-space model is stepped exactly",
        ),
        "plant_randomization": (
            experiment.plant_randomization,
            "a state-space model has no stories to randomise",
        ),
        "excitation": (
            any(source.kind == "wind" for source in experiment.excitation.sources()),
            "a state-space model takes the ground acceleration only, not floor forces (wind)",
        ),
    }
    for part, (refused, why) in refusals.items():
        if refused:
            raise ConfigError(f"{location(*experiment.origin(part))}: {why}")
    plant = experiment.plant
    simulated = plant.building if plant is not None and plant.building is not None else experiment.building
    if plant is not None and simulated is building:  # a design model may be simulated as another building
        changed = [key for key in ("stiffness", "mass", "damping") if getattr(plant, key) != 1.0]
        changed += ["damage"] * bool(plant.damage) + ["hysteresis"] * (plant.hysteresis is not None)
        if changed:
            where = location(*experiment.origin("plant"), changed[0])
            raise ConfigError(f"{where}: a state-space model has no stiffness, mass or stories to change")
    if building.sample_time is not None:
        ratio = experiment.simulation.control_dt / building.sample_time
        if abs(ratio - round(ratio)) > 1e-6 * ratio or round(ratio) < 1:
            raise ConfigError(
                f"{location(file, prefix, 'sample_time')}: {building.sample_time:g} s does not divide the "
                f"control step ({experiment.simulation.control_dt:g} s); resample the model or choose "
                "control_dt = r * dt"
            )
    declared = set(building.outputs.declared()) | {"force"}
    declared |= {"base_shear"} if "story_shear" in declared else set()
    asked = [("sensors", m.quantity) for m in experiment.sensors.measurements]
    asked += [
        ("reward", term.quantity) for term in experiment.reward.terms if term.quantity != "force_change"
    ]
    for part, quantity in asked:
        if quantity not in declared:
            raise ConfigError(
                f"{location(*experiment.origin(part))}: reads {quantity}, which the state-space model "
                f"{location(file, prefix, 'outputs')} does not declare (it has {', '.join(sorted(declared))})"
            )
    physical = experiment.sensors.state_estimate or (
        experiment.supervisor is not None and experiment.supervisor.dissipative is True
    )
    if physical and building.state != "physical":
        raise ConfigError(
            f"{location(*experiment.origin('sensors'), 'state_estimate')}: an estimate of displacements and "
            f"velocities needs a model with state: physical ({location(file, prefix, 'state')} is abstract)"
        )
    if building.n_floors != experiment.building.n_floors:
        raise ConfigError(
            f"{location(file, prefix, 'outputs.drift')}: {building.n_floors} stories, the design model has "
            f"{experiment.building.n_floors}"
        )


def _check_devices(experiment: Experiment) -> None:
    """Each mass device on an existing floor, tuned to an existing mode; each semi-active damper on
    an existing story without another damper or an actuator; no residual on LQG with dampers."""
    n_floors = experiment.building.n_floors
    file, prefix = experiment.origin("devices")
    taken = {actuator.story: "an actuator" for actuator in experiment.actuators}
    for index, device in enumerate(experiment.devices):
        where = format_location((index,), prefix)
        if device.semi_active:
            if device.story > n_floors:
                raise ConfigError(
                    f"{file}: {where}.story: story {device.story} does not exist, expected 1..{n_floors}"
                )
            if device.story in taken:
                raise ConfigError(
                    f"{file}: {where}.story: story {device.story} already has {taken[device.story]}"
                )
            taken[device.story] = f"a damper (devices[{index}])"
            continue
        if device.floor > n_floors:
            raise ConfigError(
                f"{file}: {where}.floor: floor {device.floor} does not exist, expected 1..{n_floors}"
            )
        if device.mode > n_floors:
            raise ConfigError(
                f"{file}: {where}.mode: mode {device.mode} does not exist, expected 1..{n_floors}"
            )
        if device.stroke_limit is not None and experiment.has_dampers:
            raise ConfigError(
                f"{file}: {where}.stroke_limit: end-stops with semi-active dampers are not modelled; "
                "drop the dampers, or the limit (a free mass)"
            )
    if experiment.has_dampers and experiment.supervisor is not None:
        raise ConfigError(
            f"{location(*experiment.origin('supervisor'))}: not with semi-active dampers (a damper's action "
            "0 is its middle command, not off, and a damper dissipates by itself); leave the supervisor out"
        )
    if experiment.has_dampers and experiment.algorithm.residual_lqg:
        raise ConfigError(
            f"{location(*experiment.origin('algorithm'), 'residual_lqg')}: not with semi-active dampers "
            "(an LQG force is not a damper command)"
        )


def _check_time_steps(experiment: Experiment) -> None:
    """The control step must hold a whole number of generated samples, and every generated motion
    at least one control step: otherwise what is simulated is not what was configured."""
    control_dt = experiment.simulation.control_dt
    file, prefix = experiment.origin("excitation")
    for source in experiment.excitation.sources():
        ratio = control_dt / source.dt
        if abs(ratio - round(ratio)) > 1e-6 * ratio or round(ratio) < 1:
            where = location(*experiment.origin("simulation"), "control_dt")
            raise ConfigError(
                f"{where}: {control_dt:g} s is not a whole multiple of the {source.kind} generator's "
                f"dt = {source.dt:g} s; choose control_dt = r * dt"
            )
        if source.kind == "site_based":  # lasts to 99.9 % of its Arias intensity: seconds at least
            continue
        duration, field = (
            (source.duration, "duration")
            if source.kind != "near_fault"
            else (
                source.background.duration,
                "background.duration",  # a near-fault motion lasts as its background
            )
        )
        if duration[0] < control_dt:
            raise ConfigError(
                f"{location(file, prefix, 'generator.' + field)}: {duration[0]:g} s is shorter than one "
                f"control step ({control_dt:g} s)"
            )


def _check_learning_on_fe_model(experiment: Experiment) -> None:
    """Learning on an OpenSees model: one model per process, the model as it is."""
    algorithm = experiment.algorithm
    if algorithm.n_envs > 1 and algorithm.vec_env != "subproc" and algorithm.name != "RandomSearch":
        where = location(*experiment.origin("algorithm"), "vec_env")
        raise ConfigError(
            f"{where}: learning on an OpenSees model takes one model per process: vec_env: subproc, or "
            "n_envs: 1"
        )
    if experiment.plant_randomization is not None:
        where = location(*experiment.origin("plant_randomization"), "")
        raise ConfigError(
            f"{where}: not with plant.opensees.train_on: fe (the FE model is the plant as it is)"
        )


def _check_randomization(experiment: Experiment) -> None:
    """Both ends of every range must make a valid plant for this experiment."""
    randomization = experiment.plant_randomization
    file, prefix = experiment.origin("plant_randomization")
    fe_model = experiment.plant is not None and experiment.plant.opensees is not None
    base = None if fe_model else experiment.plant  # randomised around an FE experiment's design model
    for key in RANDOMIZED_FIELDS:
        bounds = getattr(randomization, key)
        if bounds is None:
            continue
        if key == "device_frequency" and all(device.semi_active for device in experiment.devices):
            raise ConfigError(
                f"{location(file, prefix, key)}: the experiment has no tuned or active mass to detune"
            )
        if key == "yield_drift" and (base is None or base.hysteresis is None):
            raise ConfigError(
                f"{location(file, prefix, key)}: the plant has no yielding stories (plant.hysteresis)"
            )
        ends = bounds if isinstance(bounds, tuple) else (bounds.low, bounds.high)
        for end in ends:
            try:
                check_plant(randomized_plant(base, {key: end}), experiment, file, prefix)
            except ValidationError as error:
                detail = error.errors(include_url=False)[0]["msg"]
                raise ConfigError(
                    f"{location(file, prefix, key)}: {end:g} gives no valid plant: {detail}"
                ) from None


def check_plant(plant: PlantConfig, experiment: Experiment, file: str, prefix: str) -> None:
    """Per-story lists and floor numbers of a plant part must fit the building; a building given by
    matrices takes scalar factors only and no damage (its stories yield as `physics.hysteresis` reads
    them)."""
    n_floors = experiment.building.n_floors
    if isinstance(experiment.building, MatrixBuildingConfig):
        per_story = [key for key in ("stiffness", "mass") if isinstance(getattr(plant, key), list)]
        per_story += ["damage"] * bool(plant.damage)
        if per_story:
            where = location(file, prefix, per_story[0])
            raise ConfigError(f"{where}: a building given by matrices takes scalar factors only (no stories)")
    for key in ("stiffness", "mass"):
        value = getattr(plant, key)
        if isinstance(value, list) and len(value) != n_floors:
            raise ConfigError(
                f"{location(file, prefix, key)}: {len(value)} factors, expected 1 or {n_floors}"
            )
    stories = [(f"damage[{i}].story", d.story) for i, d in enumerate(plant.damage)]
    stories += [(f"sensors.bias[{i}].floor", b.floor) for i, b in enumerate(plant.sensors.bias)]
    stories += [("sensors.dead_floors", floor) for floor in plant.sensors.dead_floors]
    for key, number in stories:
        if number > n_floors:
            raise ConfigError(
                f"{location(file, prefix, key)}: {number} does not exist, expected 1..{n_floors}"
            )
    if experiment.has_dampers and (plant.actuators.time_constant > 0 or plant.actuators.delay_steps > 0):
        where = location(file, prefix, "actuators")
        raise ConfigError(
            f"{where}: actuator dynamics with semi-active dampers are not modelled; drop one of them"
        )
    if plant.hysteresis is not None and experiment.devices:
        where = location(file, prefix, "hysteresis")
        raise ConfigError(f"{where}: yielding stories with mass devices are not modelled; drop one of them")
    if plant.hysteresis is not None:
        for key in plant.hysteresis.PER_STORY:
            values = getattr(plant.hysteresis, key)
            if isinstance(values, list) and len(values) != n_floors:
                where = location(file, prefix, f"hysteresis.{key}")
                raise ConfigError(f"{where}: {len(values)} values, expected 1 or {n_floors}")
        if plant.actuators.time_constant > 0 or plant.actuators.delay_steps > 0:
            where = location(file, prefix, "hysteresis")
            raise ConfigError(
                f"{where}: yielding stories with actuator dynamics are not supported yet; use one"
            )
    if plant.actuators.time_constant > 0 and experiment.simulation.method != "exact":
        raise ConfigError(
            f"{location(file, prefix, 'actuators.time_constant')}: an actuator lag needs method: exact"
        )


def _check_measured_velocity(experiment: Experiment) -> None:
    """What the measured stroke velocities (`control.fallback`) and the fallback ask of the experiment."""
    file, prefix = experiment.origin("supervisor")
    supervisor, sensors = experiment.supervisor, experiment.sensors
    first = sensors.measurements[0] if sensors.measurements else None
    if first is None or first.quantity != "absolute_acceleration" or first.floors is not None:
        where = location(*experiment.origin("sensors"), "measurements")
        raise ConfigError(
            f"{where}: the supervisor's measured stroke velocities integrate the floors' accelerations: "
            "expected the first measurement absolute_acceleration on every floor (floors left out)"
        )
    if experiment.devices:
        raise ConfigError(
            f"{location(file, prefix, 'fallback' if supervisor.fallback else 'dissipative')}: measured "
            "stroke velocities are inter-story actuators' (floor accelerations do not measure a device's "
            "own stroke)"
        )
    fallback = supervisor.fallback
    if fallback is None:
        return
    if not sensors.state_estimate:
        raise ConfigError(
            f"{location(file, prefix, 'fallback')}: needs sensors.state_estimate: true (the drift it"
            " hands over at is the Kalman estimate's)"
        )
    actuators = len(experiment.actuators)
    if len(fallback.damping) != actuators:
        raise ConfigError(
            f"{location(file, prefix, 'fallback.damping')}: {len(fallback.damping)} values, expected one per "
            f"actuator ({actuators}), in N s/m"
        )
