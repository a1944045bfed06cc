"""The safety check: a controller must never make the building worse than it is when the controller fails
safe.

The reference is the building as it stands when its controller fails safe (`fail_safe`): without
devices, the building with no control; with devices, each at its fail-safe action (tuned masses as
tuned, mass drivers switched off: the tuned masses they are, dampers at their minimum command:
passive-off). Three criteria (the standard, `configs/checks/standard.yaml`, fixes the suite and the bounds;
for a building controlled against wind `configs/checks/wind.yaml`, whose suite is generated wind and which
`also` judges on standard.yaml's suite, a fourth: a building controlled against wind will also shake):

1. **check suite** — its generated motions (own seed, never used in training or selection), each motion's
   figures judged by the standard's rules (`evaluation.standard`): on a motion whose reference peak drift
   ratio is below the insignificance bound the controlled one stays below it; on every significant motion
   no higher performance level (FEMA 356) than the reference; the motions worse than the reference by more
   than the `tolerance` a stated risk (Clopper-Pearson bound at most `risk_bound`; none: dominates); mean J1
   and mean J2 over the significant motions at most 1.
2. **at rest** — sensor noise only, no ground motion: the peak drift ratio stays below the bound.
3. **closed-loop stability** — for a policy (a function of the observation), the closed loop
   linearised at rest on the design model, without the experiment's supervisor (whose trigger would
   switch the policy off at rest), has spectral radius < 1, or no larger than the building's failed safe
   where that has marginal modes of its own (an MR damper's hysteretic memory:
   `evaluation.standard.stability_figures`); the same number on every linear plant of
   the standard scenarios is reported, and judged on those the standard names in `stable_on` (configs/checks/:
   a 20 ms actuator lag and one control step of delay, what a real installation has).

The verdict is a YAML file beside the policy it judges (`evaluation.verdict`: what it judged, and its figures
re-derived wherever it is read).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from rlcontroller.config import SafetyCheckConfig, Scenario, check_generator
from rlcontroller.control.controllers import Controller, fail_safe_controller
from rlcontroller.control.policy_controller import PolicyController
from rlcontroller.evaluation.evaluation import PASSIVE, evaluate
from rlcontroller.evaluation.figures import (
    DeviceFigures,
    MotionFigures,
    RestFigures,
    StabilityFigures,
    SuiteFigures,
)
from rlcontroller.evaluation.standard import (
    SHAPE_DAMPING,
    SHAPE_MODES,
    rest_figures,
    stability_figures,
    suite_figures,
)
from rlcontroller.evaluation.verdict import Verdict, also_criterion
from rlcontroller.physics.metrics import ratio_to_reference, residual_drift
from rlcontroller.physics.motions.excitation import FLOOR_FORCES, STANDARD_GRAVITY, Load
from rlcontroller.physics.motions.loads import generate_suite
from rlcontroller.physics.motions.spectra import spectral_shape
from rlcontroller.physics.plant import Plant
from rlcontroller.simulation.linearised import scenario_plant, spectral_radius
from rlcontroller.simulation.rollout import batch_rollout

FAIL_SAFE = "fail-safe"


def drift_bounds(plant: Plant, standard: SafetyCheckConfig) -> np.ndarray:
    """The insignificant drift of each story (m): the bound ratio times its height."""
    heights = plant.building.story_heights
    if heights is None:
        heights = np.full(plant.building.n_floors, standard.story_height)
    return standard.insignificant_drift_ratio * np.asarray(heights, dtype=float)


def fail_safe(plant: Plant) -> tuple[Controller | None, str]:
    """The check's reference: the controller a failed one is replaced by, every command at its device's
    fail-safe action (None without devices: the evaluation's uncontrolled building), and its words."""
    experiment = plant.experiment
    if not experiment.devices:
        return None, "no control"
    parts = []
    if any(not device.semi_active and device.fail_safe_action is None for device in experiment.devices):
        parts.append("tuned masses as tuned")
    if any(not device.semi_active and device.fail_safe_action is not None for device in experiment.devices):
        parts.append("mass drivers switched off")
    if experiment.has_dampers:
        parts.append("dampers at their minimum command")
    if experiment.actuators:
        parts.append("actuators off")
    controller = fail_safe_controller(plant)
    controller.name = FAIL_SAFE
    return controller, f"the devices failed safe ({', '.join(parts)})"


def peak_acceleration(response) -> np.ndarray:
    """Each floor's peak absolute acceleration (m/s^2)."""
    return np.max(np.abs(response.absolute_acceleration), axis=0)


def safety_check(
    plant: Plant,
    controller: Controller,
    standard: SafetyCheckConfig,
    scenarios: list[Scenario],
    *,
    on_criterion: Callable[[str], None] | None = None,
) -> Verdict:
    """The verdict of `controller` (run on `plant`, as in evaluation) under `standard`;
    `on_criterion(name)` is called as each criterion is judged (a progress bar)."""
    bounds = drift_bounds(plant, standard)
    judges = {
        "check suite": lambda: suite_criterion(plant, controller, standard, bounds),
        "at rest": lambda: rest_criterion(plant, controller, standard, bounds),
    }
    if (also := standard.also) is not None:
        judges[also_criterion(also)] = lambda: suite_criterion(
            plant, controller, also, drift_bounds(plant, also)
        )
    if isinstance(controller, PolicyController):
        judges["closed-loop stability"] = lambda: stability_criterion(
            plant, controller, scenarios, standard.stable_on
        )
    criteria = {}
    for name, judge in judges.items():
        criteria[name] = judge()
        if on_criterion is not None:
            on_criterion(name)
    passed = all(item.passed for item in criteria.values())
    return Verdict(controller.name, passed, criteria)


def check_suite(plant: Plant, standard: SafetyCheckConfig) -> list[Load]:
    """The standard's suite of generated loads on `plant` (`config.check_generator`)."""
    generator = check_generator(standard, plant.experiment)
    return generate_suite(generator, standard.motions, standard.seed, plant.building)


def suite_criterion(
    plant: Plant, controller: Controller, standard: SafetyCheckConfig, bounds: np.ndarray
) -> SuiteFigures:
    motions = check_suite(plant, standard)
    reference, words = fail_safe(plant)
    controllers = [controller] if reference is None else [controller, reference]
    # a yielding or FE plant settles after each motion: its permanent drift is judged by FEMA 356's limits too
    evaluation = evaluate(plant, motions, controllers, "safety check suite", include_optimal=False)
    key = "uncontrolled" if reference is None else FAIL_SAFE
    return judge_suite(
        evaluation, motions, controller.name, key, words=words, bounds=bounds, standard=standard, plant=plant
    )


def passive_verdict(plant: Plant, standard: SafetyCheckConfig) -> SuiteFigures:
    """The check suite's criterion for a building's devices left passive (tuned masses as tuned, drivers
    off, dampers at their least command) against the building without them: what the devices alone do."""
    motions = check_suite(plant, standard)
    evaluation = evaluate(plant, motions, [], "safety check suite", include_optimal=False)
    bounds = drift_bounds(plant, standard)
    words = "the building without its devices"
    verdict = judge_suite(
        evaluation,
        motions,
        PASSIVE,
        "uncontrolled",
        words=words,
        bounds=bounds,
        standard=standard,
        plant=plant,
    )
    first = 1.0 / plant.bare.building.periods()[0]
    share = {motion.name: energy_near(motion, first) for motion in motions}
    failing = set(verdict.failures)
    if not failing:
        return verdict
    rows = {
        name: replace(row, ground_energy_near_first_mode=round(share[name], 4)) if name in failing else row
        for name, row in verdict.per_motion.items()
    }
    passing = [share[name] for name, row in rows.items() if row.significant and name not in failing]
    summary = verdict.summary + (
        f"; the motions it fails carry a median {np.median([share[name] for name in failing]):.1%} of "
        f"their ground energy within {NEAR_MODE:.0%} of the first mode's {first:.3f} Hz "
        f"(the significant ones it passes {np.median(passing):.1%})"
    )
    return replace(verdict, summary=summary, per_motion=rows)


NEAR_MODE = 0.15  # the band around the first mode a tuned mass acts in (of its frequency)


def energy_near(motion: Load, frequency: float) -> float:
    """The share of a motion's ground-acceleration energy (Fourier amplitude squared) within NEAR_MODE
    of `frequency` (Hz)."""
    spectrum = np.abs(np.fft.rfft(motion.acceleration)) ** 2
    frequencies = np.fft.rfftfreq(motion.acceleration.size, motion.dt)
    near = np.abs(frequencies / frequency - 1.0) < NEAR_MODE
    return float(np.sum(spectrum[near]) / np.sum(spectrum))


def judge_suite(
    evaluation,
    motions: list[Load],
    judged: str,
    reference: str,
    *,
    words: str,
    bounds: np.ndarray,
    standard,
    plant: Plant,
) -> SuiteFigures:
    """The check suite's criterion from an evaluation of its `motions`: the responses named `judged` against
    those named `reference` (described by `words`), each motion's figures in `per_motion` and the outcome
    derived from them (`evaluation.standard.suite_figures`) under `standard` for `plant`'s lateral system."""
    heights = bounds / standard.insignificant_drift_ratio  # m, each story's
    yields = plant.yielding is not None or plant.fe_model is not None
    ground = motions[0].kind != FLOOR_FORCES
    periods = [round(float(p), 4) for p in plant.bare.building.periods()[:SHAPE_MODES]] if ground else None
    rows = {}
    for motion in motions:
        reference_run = evaluation.responses[reference, motion.name]
        controlled = evaluation.responses[judged, motion.name]
        reference_peak = np.max(np.abs(reference_run.drift), axis=0)
        peak = np.max(np.abs(controlled.drift), axis=0)
        row = strength(motion)
        if ground:  # what the motion is made of at the building's own periods
            shape = spectral_shape(motion, np.array(periods), SHAPE_DAMPING)
            row = replace(row, sa_over_pga=tuple(round(float(v), 4) for v in shape))
        if np.max(reference_peak / bounds) < 1.0:  # insignificant: stay below the bound
            rows[motion.name] = replace(row, over_bound=round(float(np.max(peak / bounds)), 4))
            continue
        accelerations = peak_acceleration(controlled) / peak_acceleration(reference_run)
        row = replace(
            row,
            J1=round(float(np.mean(peak / reference_peak)), 4),
            J2=round(float(np.mean(accelerations)), 4),
            ratio=round(ratio_to_reference(controlled, reference_run), 4),
            drift_ratio=round(float(np.max(peak / heights)), 6),
            reference_drift_ratio=round(float(np.max(reference_peak / heights)), 6),
        )
        if yields:  # the permanent drift, after the settling tail
            residual, reference_residual = (
                round(float(np.max(residual_drift(run)["residual_drift_m"] / heights)), 6)
                for run in (controlled, reference_run)
            )
            row = replace(row, residual_ratio=residual, reference_residual_ratio=reference_residual)
        rows[motion.name] = row
    devices = device_figures(evaluation, judged, reference, motions, plant=plant)
    system = plant.experiment.building.system
    return suite_figures(rows, words, system, standard, devices=devices, periods=periods)


def device_figures(
    evaluation, judged: str, reference: str, motions: list[Load], *, plant: Plant
) -> DeviceFigures | None:
    """Per mass device of `plant` over the motions, under the controller `judged` and the `reference`: the
    largest stroke (m); with end-stops also their limits (m), the contacts and the largest contact force (N).
    None without mass devices."""
    figures: dict[str, list] = {}
    for name, prefix in ((judged, ""), (reference, "reference_")):
        runs = [evaluation.responses[name, motion.name] for motion in motions]
        if runs[0].stroke is None or runs[0].stroke.shape[1] == 0:  # no mass (a passive verdict's reference)
            continue
        strokes = np.max([np.max(np.abs(run.stroke), axis=0) for run in runs], axis=0)
        figures[f"{prefix}peak_stroke_m"] = [round(float(value), 4) for value in strokes]
        if runs[0].stop_contacts is None:
            continue
        figures["stroke_limit_m"] = [float(d.stroke_limit or np.nan) for d in plant.building.devices]
        contacts = np.sum([np.sum(run.stop_contacts, axis=0) for run in runs], axis=0)
        forces = np.max([np.max(run.stop_force, axis=0) for run in runs], axis=0)
        figures[f"{prefix}contacts"] = [int(value) for value in contacts]
        figures[f"{prefix}peak_contact_force_N"] = [round(float(value), 1) for value in forces]
    return DeviceFigures(**figures) if figures else None


def strength(motion: Load) -> MotionFigures:
    """How strong a load is, for a verdict's rows: a ground motion's PGA (g), a wind load's mean speed."""
    if motion.kind == FLOOR_FORCES:
        return MotionFigures(load=motion.description or "floor forces")
    return MotionFigures(pga_g=round(motion.pga / STANDARD_GRAVITY, 5))


def rest_criterion(
    plant: Plant, controller: Controller, standard: SafetyCheckConfig, bounds: np.ndarray
) -> RestFigures:
    dt = plant.control_dt
    still = Load("at rest", dt, np.zeros(round(standard.rest_duration / dt) + 1), synthetic=True)
    seeds = [standard.seed + 1 + run for run in range(standard.rest_runs)]
    runs = batch_rollout(plant, [still] * standard.rest_runs, [controller], seeds=seeds)[0]
    worst = max(float(np.max(np.max(np.abs(response.drift), axis=0) / bounds)) for response, _ in runs)
    return rest_figures(round(worst, 4), standard)


def stability_criterion(
    plant: Plant, controller: PolicyController, scenarios: list[Scenario], stable_on: list[str]
) -> StabilityFigures:
    design = spectral_radius(plant.design, controller)
    failed_safe = spectral_radius(plant.design, fail_safe_controller(plant.design))
    experiment = plant.experiment
    per_scenario: dict[str, float | str] = {}
    for scenario in scenarios:
        linear = scenario_plant(plant, scenario)
        per_scenario[scenario.name] = (
            "not linear: not checked" if linear is None else round(spectral_radius(linear, controller), 8)
        )
    supervised = experiment.supervisor is not None
    return stability_figures(
        round(design, 8), per_scenario, supervised, round(failed_safe, 8), stable_on=stable_on
    )
