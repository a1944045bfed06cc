"""The plant: what the simulator steps and the controllers are designed on, built once per experiment.

From the experiment's building, actuators, sensors and simulation: the `Building` (M, K, C, Gamma,
force limits), the outputs on its whole state (`outputs`, `load_outputs`), the sensor matrices
(readings = C x + D u, with their scales, noise and bias) and the observation layout
(`physics.observation`). How it is stepped: `plant.sampled(r)`, the plant sampled at its control step with
r load samples per step (`physics.sampled`: its step, load and design maps, forcing, transition, simulate,
response; built once per r and kept). The env and the batch simulate a plant; LQG, the Kalman filters, MPC,
the residual prior and the optimal reference are designed on one; none of them rebuilds it.

Plant and design model: an experiment's building, actuators and sensors are the *design model*,
what an engineer designs on. Its optional `plant` part says how the simulated building differs:
factors on stiffness, mass and damping, damaged stories, actuator dynamics, sensor faults.
`Plant(experiment)` is the simulated plant and `plant.design` the design model (the plant itself
when there is no `plant` part, bit for bit).

Actuator dynamics make the state x longer than z = [x_floors; v_floors]: with a lag, the delivered
forces f (N) follow the command u through tau f' = u - f; with a delay of d steps, the commands of
the last d steps wait in a buffer, and without a lag a register holds the force applied over the
last step. Every output is then C x (no feed-through), and z is always x[:2n]. Yielding stories
(Bouc-Wen, `physics.hysteresis`) make the state [x_floors; v_floors; z_stories]: the step is then
the non-linear integrator, and every output is still linear in that state and the command. Mass devices with
a stroke limit meet end-stops (`physics.end_stops`): the state gains their registers, the step their
integrator; the design model has no stops (a linear design knows the stroke limit only as a limit).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from rlcontroller.config import (
    ActuatorConfig,
    BuildingPart,
    ConfigError,
    Experiment,
    Quantity,
    SensorConfig,
    StateSpaceBuildingConfig,
    WindGeneratorConfig,
    location,
)
from rlcontroller.physics.dynamics import load_feedthrough, output_matrices
from rlcontroller.physics.end_stops import EndStops
from rlcontroller.physics.fe.integrator import OpenSeesIntegrator
from rlcontroller.physics.fishbone import hysteretic_model
from rlcontroller.physics.motions.excitation import FLOOR_FORCES
from rlcontroller.physics.motions.generators import GroundModel
from rlcontroller.physics.motions.wind import WindLoadModel, floor_field, load_model
from rlcontroller.physics.observation import observation_layout
from rlcontroller.physics.sampled import SampledPlant
from rlcontroller.physics.semi_active import SemiActiveDampers
from rlcontroller.physics.sensors import sensor_matrices
from rlcontroller.physics.state_space import StateSpaceBuilding, from_state_space
from rlcontroller.physics.structure import Building, build, tune_devices, with_dampers, with_devices
from rlcontroller.physics.variations import true_building


def design_wind(experiment: Experiment) -> WindLoadModel | None:
    """The wind an experiment trains under (an excitation generator of kind wind; else None) at the
    middle of its speed range, as the load model of LQG + wind model and of the wind-model state
    estimate: fitted at the first natural frequency of the design building without its mass devices.
    Never the records it is judged on."""
    generator = experiment.excitation.generator
    if not isinstance(generator, WindGeneratorConfig):
        return None
    bare = build(experiment.building, experiment.actuators)
    frequency = float(bare.modes()[0][0] / (2.0 * np.pi))
    return load_model(floor_field(generator, bare, 0.5 * sum(generator.speed)), frequency)


def build_any(building: BuildingPart, actuators: list[ActuatorConfig]) -> Building | StateSpaceBuilding:
    """The building of a building part: M, K, C (`structure.build`) or a state-space model."""
    if isinstance(building, StateSpaceBuildingConfig):
        return from_state_space(building, actuators)
    return build(building, actuators)


class Plant:
    """An experiment's building with its actuators, sensors and discretisation, built once.

    Attributes: `experiment`, `config` (its `plant` part, or None), `building`, `force_limits` (N),
    `control_dt` (s), `n_state` (length of x), `sensors` (`SensorMatrices`), `layout`
    (`ObservationLayout`), `ground_model` (the Kanai-Tajimi model of LQG + ground model and of
    `sensors.ground_model`), `wind` (the design wind's load model of LQG + wind model, or None:
    `design_wind`), `design` (the design model), `end_stops` (the mass devices' stops, or None).

    `stops=False` leaves the mass devices free: the linear model a design takes (`design`, `elastic`).
    """

    def __init__(self, experiment: Experiment, *, stops: bool = True) -> None:
        self.experiment = experiment
        self.config = experiment.plant
        building = (
            experiment.building if self.config is None else true_building(experiment.building, self.config)
        )
        self.building = build_any(building, experiment.actuators)
        if experiment.devices:  # tuned on the design model's floors, attached to this plant's
            design = (
                self.building if self.config is None else build(experiment.building, experiment.actuators)
            )
            devices = tune_devices(design, experiment.devices)
            if self.config is not None:
                factors = self.config.devices
                devices = tuple(
                    replace(
                        d, stiffness=d.stiffness * factors.frequency**2, damping=d.damping * factors.damping
                    )
                    for d in devices
                )
            self.building = with_devices(self.building, devices)
        if experiment.has_dampers:
            dampers = [d for d in experiment.devices if d.semi_active]
            factor = self.config.devices.force if self.config is not None else 1.0
            if factor != 1.0:  # as built: stronger or weaker than designed
                dampers = [d.scaled(factor) for d in dampers]
            self.building = with_dampers(self.building, dampers)
        hysteresis = self.config.hysteresis if self.config is not None else None
        self.yielding = None
        if hysteresis is not None:
            try:
                self.yielding = hysteretic_model(self.building, hysteresis)
            except ValueError as error:  # known only with the building's matrices: a fault of the file
                raise ConfigError(f"{location(*experiment.origin('plant'), 'hysteresis')}: {error}") from None
        self.semi_active = SemiActiveDampers.of(self.building) if self.building.dampers else None
        fe = self.config.opensees if self.config is not None else None
        self.fe_model = None
        if fe is not None:  # the building is its design model; the FE model steps itself
            self.fe_model = OpenSeesIntegrator(
                Path(fe.model),
                fe.function,
                fe.analysis_dt,
                self.building.actuator_matrix,
                self.building.force_limits,
            )
        self.force_limits = self.building.force_limits
        self.control_dt = experiment.simulation.control_dt
        dynamics = self.config.actuators if self.config is not None else None
        self.time_constant = dynamics.time_constant if dynamics else 0.0
        self.delay_steps = dynamics.delay_steps if dynamics else 0
        size, m = self.building.n_states, self.building.n_actuators
        lag = m if self.time_constant > 0 else 0
        held = m if self.delay_steps > 0 and not lag else 0
        self.n_state = size + lag + self.delay_steps * m + held
        self.n_state += self.building.n_floors if self.yielding is not None else 0
        self.n_state += self.semi_active.size if self.semi_active is not None else 0
        # [x; v; absolute accelerations]
        self.n_state += self.building.n_dofs if self.fe_model is not None else 0
        self.end_stops = None
        # dampers with stopped masses: refused by the experiment's checks
        if stops and self.semi_active is None:
            self.end_stops = EndStops.of(
                self.building,
                experiment.simulation,
                n_linear=self.n_state,
                time_constant=self.time_constant,
                delay_steps=self.delay_steps,
                linear_step=self._linear_step,
            )
        self.n_state += self.end_stops.size if self.end_stops is not None else 0
        # when not linear
        self.integrator = self.fe_model or self.yielding or self.semi_active or self.end_stops
        faults = self.config.sensors if self.config is not None else None
        self.sensors = sensor_matrices(self.outputs, self.building, experiment.sensors, faults)
        self.wind = design_wind(experiment)
        load_scale = np.sqrt(np.diag(self.wind.covariance)) if self.wind is not None else None
        self.layout = observation_layout(
            self.building,
            experiment.sensors,
            self.sensors.c.shape[0],
            self.sensors.scale,
            load_scale=load_scale,
        )
        self.ground_model = GroundModel()
        self._sampled: dict[int, SampledPlant] = {}  # sub-steps -> this plant sampled
        self._design = self if self.config is None and self.end_stops is None else None
        self._elastic: Plant | None = None
        self._bare = None if experiment.devices or experiment.supervisor is not None else self
        self._failed_safe = self if experiment.supervisor is None else None
        self._pushover = None  # an FE plant's, once asked for its yield drifts

    @property
    def design(self) -> Plant:
        """The design model: the experiment without its plant part."""
        if self._design is None:
            self._design = Plant(self.experiment.model_copy(update={"plant": None}), stops=False)
        return self._design

    @property
    def bare(self) -> Plant:
        """This plant without its mass devices: the uncontrolled building every J is taken against.
        (Its sensors and reward are the floors' only; with no actuators it gets one that is never
        commanded.)"""
        if self._bare is None:
            experiment = self.experiment
            kept = [m for m in experiment.sensors.measurements if m.quantity not in ("stroke", "force")]
            sensors = experiment.sensors.model_copy(
                update={"measurements": kept or SensorConfig().measurements}
            )
            terms = [term for term in experiment.reward.terms if term.quantity != "stroke"]
            reward = experiment.reward.model_copy(update={"terms": terms})
            update = {"devices": [], "sensors": sensors, "reward": reward, "supervisor": None}
            if not experiment.actuators:
                update["actuators"] = [ActuatorConfig(story=1)]
            self._bare = Plant(experiment.model_copy(update=update))
        return self._bare

    @property
    def failed_safe(self) -> Plant:
        """This plant with its control system failed safe: the devices stay, the supervisor is gone (its
        fallback would act on its own). The safety check's reference runs here."""
        if self._failed_safe is None:
            self._failed_safe = Plant(self.experiment.model_copy(update={"supervisor": None}))
        return self._failed_safe

    @property
    def active_equivalent(self) -> Plant:
        """This plant with each semi-active damper replaced by an ideal actuator whose force limit is the
        damper's capacity: what clipped-optimal control designs its LQG on (on the design model, or
        on the plant itself for the robustness study's oracle)."""
        experiment = self.experiment
        dampers = [d for d in experiment.devices if d.semi_active]
        actuators = [
            *experiment.actuators,
            *(ActuatorConfig(story=d.story, force_limit=d.capacity) for d in dampers),
        ]
        masses = [d for d in experiment.devices if not d.semi_active]
        # the action's order: actuators, drivers, dampers
        if any(d.command_label() is not None for d in masses):
            raise ValueError(
                "clipped-optimal control with active mass drivers and dampers together is not built"
            )
        return Plant(experiment.model_copy(update={"actuators": actuators, "devices": masses}))

    @property
    def elastic(self) -> Plant:
        """This plant made linear, what a linear design can know: stories at their initial stiffness, mass
        devices without their stops."""
        if self.yielding is None and self.end_stops is None:
            return self
        if self._elastic is None:
            part = None if self.config is None else self.config.model_copy(update={"hysteresis": None})
            self._elastic = Plant(self.experiment.model_copy(update={"plant": part}), stops=False)
        return self._elastic

    @property
    def yield_drift(self) -> np.ndarray | None:
        """Each story's yield drift (m): a yielding plant's d_y; an FE plant's from its model's first-mode
        pushover (`physics.fe.pushover`, run here once, when first asked); None for a linear plant."""
        if self.yielding is not None:
            return self.yielding.yield_drift
        if self.fe_model is None:
            return None
        if self._pushover is None:
            from rlcontroller.physics.fe.pushover import pushover

            n = self.building.n_floors  # the building is the FE model's reduced one
            floors = (self.building.mass[:n, :n], self.building.stiffness[:n, :n])
            self._pushover = pushover(self.fe_model.path, self.fe_model.function, *floors)
        return self._pushover.yield_drift

    def _linear_step(self, substeps: int):
        """This plant's own linear control-step map, what its end-stops superpose on (a method: it
        pickles)."""
        return self.sampled(substeps).step

    @property
    def n_linear(self) -> int:
        """The length of the state's linear part, before the stops' registers."""
        return self.n_state - (self.end_stops.size if self.end_stops is not None else 0)

    @property
    def has_actuator_dynamics(self) -> bool:
        return self.time_constant > 0 or self.delay_steps > 0

    def outputs(self, quantity: Quantity) -> tuple[np.ndarray, np.ndarray]:
        """(C, D) with quantity = C x + D u on this plant's state x and command u (N)."""
        if self.end_stops is not None:
            return self._stopped_outputs(quantity)
        return self._linear_outputs(quantity)

    def _stopped_outputs(self, quantity: Quantity) -> tuple[np.ndarray, np.ndarray]:
        """The linear plant's outputs with the stops' force registers: a stop pushes its mass with f and its
        floor with -f, which the floor's acceleration feels at once (`physics.end_stops`); a story shear
        counts the mass's inertia with its floor's, to which the stop's force is internal: it feels the impact
        through the motion."""
        c, d = self._linear_outputs(quantity)
        stops = self.end_stops
        full = np.zeros((c.shape[0], self.n_state))
        full[:, : c.shape[1]] = c
        if quantity in ("absolute_acceleration", "story_shear", "base_shear"):
            pushed = replace(self.building, actuator_matrix=stops.contact_matrix())
            full[:, stops.n_linear : stops.n_linear + stops.devices.size] = output_matrices(pushed, quantity)[
                1
            ]
        return full, d

    def _linear_outputs(self, quantity: Quantity) -> tuple[np.ndarray, np.ndarray]:
        if self.fe_model is not None:
            return self._fe_outputs(quantity)
        if self.yielding is not None:
            return self._yielding_outputs(quantity)
        if self.semi_active is not None:
            return self._damper_outputs(quantity)
        c, d = output_matrices(self.building, quantity)
        if not self.has_actuator_dynamics:
            return c, d
        size, m = self.building.n_states, self.building.n_actuators
        full = np.zeros((c.shape[0], self.n_linear))
        full[:, :size] = c
        if self.time_constant > 0:
            full[:, size : size + m] = d  # the delivered force is a state
        else:
            # the register of the force applied over the last step
            full[:, self.n_linear - m : self.n_linear] = d
        return full, np.zeros_like(d)

    def _fe_outputs(self, quantity: Quantity) -> tuple[np.ndarray, np.ndarray]:
        """Outputs on the FE model's [x; v; a] at its floors: the kinematic ones as the design building's,
        the absolute accelerations read, the story shears their floors' inertia forces above."""
        c, d = output_matrices(self.building, quantity)
        n = self.building.n_dofs
        if quantity == "absolute_acceleration":
            return np.hstack([np.zeros((n, 2 * n)), np.eye(n)]), np.zeros_like(d)
        if quantity in ("story_shear", "base_shear"):
            shear = np.triu(np.ones((n, n))) @ self.building.mass
            return np.hstack([np.zeros((n, 2 * n)), shear])[: c.shape[0]], np.zeros_like(d)
        return np.hstack([c, np.zeros((c.shape[0], n))]), d

    def _yielding_outputs(self, quantity: Quantity) -> tuple[np.ndarray, np.ndarray]:
        """Outputs on [x; v; z]: the restoring force is K_e x + B z (story springs: B = D' diag(h),
        `physics.hysteresis`; a fishbone, `physics.fishbone`)."""
        n, yielding = self.building.n_floors, self.yielding
        hysteretic = yielding.hysteretic_matrix
        c, d = output_matrices(replace(self.building, stiffness=yielding.linear_stiffness), quantity)
        z_columns = np.zeros((c.shape[0], n))
        if quantity == "absolute_acceleration":
            z_columns = -np.linalg.inv(self.building.mass) @ hysteretic
        elif quantity in ("story_shear", "base_shear"):
            z_columns = -(np.triu(np.ones((n, n))) @ hysteretic)[: c.shape[0]]
        return np.hstack([c, z_columns]), d

    def _damper_outputs(self, quantity: str) -> tuple[np.ndarray, np.ndarray]:
        """Outputs on [z; per damper (y, z, u, F)]: a damper's column of D moves onto its force register
        (its action commands the damper, it applies no force itself); its "force" is the force it puts
        on its floor, -F, in the sign of an actuator's."""
        c, d = output_matrices(self.building, quantity)
        first, count = self.semi_active.first_command, len(self.building.dampers)
        full = np.zeros((c.shape[0], self.n_state))
        full[:, : c.shape[1]] = c
        registers = c.shape[1] + 4 * np.arange(count) + 3
        full[:, registers] = -d[:, first:]  # the damper pushes its floor with -F
        d = d.copy()
        d[:, first:] = 0.0
        return full, d

    def load_outputs(self, quantity: Quantity) -> np.ndarray:
        """How floor forces (N) enter `quantity` directly, (rows, floors) (`dynamics.load_feedthrough`)."""
        return load_feedthrough(self.building, quantity)

    def sampled(self, substeps: int = 1) -> SampledPlant:
        """This plant sampled at its control step with `substeps` load samples per step: every discrete map
        of it, built once (`physics.sampled`)."""
        if substeps not in self._sampled:
            self._sampled[substeps] = SampledPlant(self, substeps)
        return self._sampled[substeps]

    def cannot_take(self, kind: str) -> str | None:
        """Why this plant cannot be loaded by a load of `kind` (`excitation.FLOOR_FORCES` or
        `GROUND_ACCELERATION`), in one line; None when it can."""
        if kind == FLOOR_FORCES and self.integrator not in (None, self.end_stops):
            return (
                "floor loads (wind) on a building with yielding stories or semi-active dampers are not "
                "modelled"
            )
        if kind == FLOOR_FORCES and isinstance(self.building, StateSpaceBuilding):
            return (
                "a state-space model takes the ground acceleration only (it declares no floor-force inputs)"
            )
        return None
