"""The safety check: a controller must never make the building worse than it is when the controller fails safe.

The reference is the building as it stands when its controller fails safe (`fail_safe`): without
devices, the building with no control; with devices, each at its fail-safe action (tuned masses as
tuned, mass drivers switched off: the tuned masses they are, dampers at their minimum command:
passive-off). Three criteria (the standard, `configs/checks/standard.yaml`, fixes the suite and the bounds;
for a building controlled against wind `configs/checks/wind.yaml`, whose suite is generated wind and which
`also` judges on standard.yaml's suite, a fourth: a building controlled against wind will also shake):

1. **check suite** — on every one of its generated motions (own seed, never used in training or
   selection): the building's peak inter-story drift (max over stories and time) is no larger than
   the reference's and the mean over stories of J1 (to the reference) is at most 1, each within the
   standard's `tolerance` (1 %: sensor noise and another CPU's arithmetic move these ratios by about
   0.1 %; the motions above 1 at all are counted beside, the strict count); on a motion whose
   reference peak drift ratio is below the insignificance bound, the controlled peak drift ratio
   stays below the bound instead. Over the significant motions the mean J1 and the mean J2 (peak
   absolute floor acceleration, to the reference's, mean over floors) are at most 1 as well: a
   controller that trades floor accelerations for drift does not pass.
2. **at rest** — sensor noise only, no ground motion: the peak drift ratio stays below the bound.
3. **closed-loop stability** — for a policy (a function of the observation), the closed loop
   linearised at rest on the design model, without the experiment's supervisor (whose trigger would
   switch the policy off at rest), has spectral radius < 1; the same number on every linear plant of
   the standard scenarios is reported (not a pass criterion: the verdict says where it is not stable).

The verdict is a YAML file (`best_check.yaml`, `final_check.yaml`) beside the policy it judges, with the
sha256 of what it judged (the policy's files, the experiment, the standard): a verdict whose digests no
longer match the folder is read as no verdict (`read_verdict`).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from rlcontroller.config import SafetyCheckConfig, Scenario, check_generator
from rlcontroller.control.controllers import Controller, fail_safe_controller
from rlcontroller.control.policy import PolicyController
from rlcontroller.evaluation.evaluation import PASSIVE, evaluate
from rlcontroller.files import atomic_write
from rlcontroller.physics.excitation import FLOOR_FORCES, STANDARD_GRAVITY, Load
from rlcontroller.physics.loads import generate_suite
from rlcontroller.physics.metrics import ratio_to_reference
from rlcontroller.physics.plant import Plant
from rlcontroller.simulation.batch import BuildingBatch
from rlcontroller.simulation.rollout import batch_rollout

ROUNDING = 1e-9  # a controller that never acts equals the uncontrolled building to this relative rounding
FAIL_SAFE = "fail-safe"


@dataclass
class Verdict:
    """Pass or fail per criterion, with the worst motion and the numbers behind each."""

    controller: str
    passed: bool
    criteria: dict[str, dict] = field(default_factory=dict)
    judged: dict[str, str] = field(default_factory=dict)  # sha256 of what it judged (`judged_digests`)

    def to_yaml(self) -> str:
        fields = {"controller": self.controller, "passed": self.passed, "criteria": self.criteria}
        fields |= {"judged": self.judged} if self.judged else {}
        return yaml.safe_dump(fields, sort_keys=False, default_flow_style=None)  # a motion's numbers on one line

    def lines(self) -> list[str]:
        head = f"safety check of {self.controller}: {'PASSED' if self.passed else 'FAILED'}"
        return [head] + [
            f"  {name}: {'pass' if item['passed'] else 'FAIL'} - {item['summary']}"
            for name, item in self.criteria.items()
        ]


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
        name = "wind suite" if also.generator.kind == "wind" else "ground-motion suite"
        judges[name] = lambda: suite_criterion(plant, controller, also, drift_bounds(plant, also))
    if isinstance(controller, PolicyController):
        judges["closed-loop stability"] = lambda: stability_criterion(plant, controller, scenarios)
    criteria = {}
    for name, judge in judges.items():
        criteria[name] = judge()
        if on_criterion is not None:
            on_criterion(name)
    passed = all(item["passed"] for item in criteria.values())
    return Verdict(controller.name, passed, criteria)


def check_suite(plant: Plant, standard: SafetyCheckConfig) -> list[Load]:
    """The standard's suite of generated loads on `plant` (`config.check_generator`)."""
    generator = check_generator(standard, plant.experiment)
    return generate_suite(generator, standard.motions, standard.seed, plant.building)


def suite_criterion(plant: Plant, controller: Controller, standard: SafetyCheckConfig, bounds: np.ndarray) -> dict:
    motions = check_suite(plant, standard)
    reference, words = fail_safe(plant)
    controllers = [controller] if reference is None else [controller, reference]
    settle = plant.fe_model is None  # peaks are judged: an FE model's residual drifts would double its runs
    evaluation = evaluate(plant, motions, controllers, "safety check suite", include_optimal=False, settle=settle)
    key = "uncontrolled" if reference is None else FAIL_SAFE
    return judge_suite(evaluation, motions, controller.name, key, words, bounds, standard.tolerance)


def passive_verdict(plant: Plant, standard: SafetyCheckConfig) -> dict:
    """The check suite's criterion for a building's devices left passive (tuned masses as tuned, drivers
    off, dampers at their least command) against the building without them: what the devices alone do."""
    motions = check_suite(plant, standard)
    evaluation = evaluate(plant, motions, [], "safety check suite", include_optimal=False)
    bounds = drift_bounds(plant, standard)
    words = "the building without its devices"
    verdict = judge_suite(evaluation, motions, PASSIVE, "uncontrolled", words, bounds, standard.tolerance)
    first = 1.0 / plant.bare.building.periods()[0]
    share = {motion.name: energy_near(motion, first) for motion in motions}
    failing = {row["motion"] for row in verdict["failures"]}
    for row in verdict["failures"]:
        row["ground_energy_near_first_mode"] = round(share[row["motion"]], 4)
    if failing:
        passing = [share[name] for name in verdict["J1_J2_per_motion"] if name not in failing]
        verdict["summary"] += (
            f"; the motions it fails carry a median {np.median([share[name] for name in failing]):.1%} of their "
            f"ground energy within {NEAR_MODE:.0%} of the first mode's {first:.3f} Hz "
            f"(the significant ones it passes {np.median(passing):.1%})"
        )
    return verdict


NEAR_MODE = 0.15  # the band around the first mode a tuned mass acts in (of its frequency)


def energy_near(motion: Load, frequency: float) -> float:
    """The share of a motion's ground-acceleration energy (Fourier amplitude squared) within NEAR_MODE
    of `frequency` (Hz)."""
    spectrum = np.abs(np.fft.rfft(motion.acceleration)) ** 2
    frequencies = np.fft.rfftfreq(motion.acceleration.size, motion.dt)
    near = np.abs(frequencies / frequency - 1.0) < NEAR_MODE
    return float(np.sum(spectrum[near]) / np.sum(spectrum))


def judge_suite(
    evaluation, motions: list[Load], judged: str, reference: str, words: str, bounds: np.ndarray, tolerance: float
) -> dict:
    """The check suite's criterion from an evaluation of its `motions`: the responses named `judged`
    against those named `reference` (described by `words`); a significant motion fails when its ratio to the
    reference exceeds 1 + `tolerance` (the motions above 1 are counted beside: the strict count)."""
    failures, per_motion, worst, worst_j2, worst_ratio, strict = [], {}, None, None, None, 0
    for motion in motions:
        reference_run = evaluation.responses[reference, motion.name]
        controlled = evaluation.responses[judged, motion.name]
        reference_peak, peak = np.max(np.abs(reference_run.drift), axis=0), np.max(np.abs(controlled.drift), axis=0)
        row = {"motion": motion.name} | strength(motion)
        if np.max(reference_peak / bounds) < 1.0:  # insignificant: stay below the bound
            score = float(np.max(peak / bounds))
            ok, kind = score < 1.0, "peak drift / insignificance bound"
        else:
            j1 = float(np.mean(peak / reference_peak))
            j2 = float(np.mean(peak_acceleration(controlled) / peak_acceleration(reference_run)))
            per_motion[motion.name] = [round(j1, 4), round(j2, 4)]
            if worst_j2 is None or j2 > worst_j2["value"]:
                worst_j2 = row | {"value": round(j2, 4)}
            score = ratio_to_reference(controlled, reference_run)
            row["reference_peak_drift_m"] = round(float(np.max(reference_peak)), 4)  # beside the story height
            kind = "peak drift ratio to the reference (or mean J1, the larger)"
            ok = score <= 1.0 + tolerance
            strict += score > 1.0 + ROUNDING
            if worst_ratio is None or score > worst_ratio["value"]:
                worst_ratio = row | {"value": round(score, 4)}
        row["value"] = round(score, 4)
        if not ok:
            failures.append(row)
        if worst is None or score > worst["value"]:
            worst = row | {"measure": kind}
    significant = len(per_motion)
    mean_j1, mean_j2 = (float(v) for v in np.mean(list(per_motion.values()), axis=0)) if significant else (np.nan,) * 2
    passed = not failures and (not significant or (mean_j1 <= 1.0 + ROUNDING and mean_j2 <= 1.0 + ROUNDING))
    summary = (
        f"{len(motions) - len(failures)} of {len(motions)} motions no worse than {words} (within {tolerance:.0%}; "
        f"{strict} worse at all, {len(motions) - significant} insignificant); "
        f"mean J1 {mean_j1:.3f}, mean J2 {mean_j2:.3f}; "
        f"worst {worst['motion']} ({strength_text(worst)}): {worst['value']:.3f}"
    )
    if worst_ratio is not None:
        summary += f"; worst significant {worst_ratio['value']:.3f} ({worst_ratio['motion']})"
    if worst_j2 is not None:
        summary += f"; worst J2 {worst_j2['value']:.3f} ({worst_j2['motion']})"
    strokes = {name: peak_strokes(evaluation, name, motions) for name in (judged, reference)}
    if strokes[judged].size:
        metres = [", ".join(f"{value:.2f}" for value in strokes[name]) + " m" for name in (judged, reference)]
        summary += f"; peak stroke {metres[0]} ({metres[1]} for the reference)"
    return {
        "passed": passed,
        "summary": summary,
        "reference": words,
        "motions": len(motions),
        "insignificant_motions": len(motions) - significant,
        "mean_J1": round(mean_j1, 4),
        "mean_J2": round(mean_j2, 4),
        "worst": worst,
        "worst_significant": worst_ratio,  # the largest ratio to the reference among the significant motions
        "worst_J2": worst_j2,
        "J1_J2_per_motion": per_motion,  # the significant motions
        "failures": failures,
        "failure_count": len(failures),
        "tolerance": tolerance,
        "strict_failure_count": strict,  # significant motions above the reference by more than rounding
    } | ({"peak_stroke_m": [round(float(value), 4) for value in strokes[judged]]} if strokes[judged].size else {})


def peak_strokes(evaluation, name: str, motions: list[Load]) -> np.ndarray:
    """Each mass device's largest stroke (m) over the motions, under the controller `name`."""
    peaks = [np.max(np.abs(evaluation.responses[name, motion.name].stroke), axis=0) for motion in motions]
    return np.max(peaks, axis=0)


def strength(motion: Load) -> dict:
    """How strong a load is, for a verdict's rows: a ground motion's PGA (g), a wind load's mean speed."""
    if motion.kind == FLOOR_FORCES:
        return {"load": motion.description or "floor forces"}
    return {"pga_g": round(motion.pga / STANDARD_GRAVITY, 5)}


def strength_text(row: dict) -> str:
    return f"PGA {row['pga_g']:g} g" if "pga_g" in row else row["load"]


def rest_criterion(plant: Plant, controller: Controller, standard: SafetyCheckConfig, bounds: np.ndarray) -> dict:
    dt = plant.control_dt
    still = Load("at rest", dt, np.zeros(round(standard.rest_duration / dt) + 1), synthetic=True)
    seeds = [standard.seed + 1 + run for run in range(standard.rest_runs)]
    runs = batch_rollout(plant, [still] * standard.rest_runs, [controller], seeds=seeds)[0]
    worst = max(float(np.max(np.max(np.abs(response.drift), axis=0) / bounds)) for response, _ in runs)
    return {
        "passed": worst < 1.0,
        "summary": f"peak drift {worst:.3f} of the bound over {standard.rest_runs} noise realisations of "
        f"{standard.rest_duration:g} s",
        "peak_drift_over_bound": round(worst, 4),
    }


def stability_criterion(plant: Plant, controller: PolicyController, scenarios: list[Scenario]) -> dict:
    design = spectral_radius(plant.design, controller)
    experiment = plant.experiment
    per_scenario, unstable = {}, []
    for scenario in scenarios:
        if scenario.plant is not None and scenario.plant.hysteresis is not None:
            per_scenario[scenario.name] = "not linear: not checked"
            continue
        radius = spectral_radius(Plant(experiment.model_copy(update={"plant": scenario.plant})), controller)
        per_scenario[scenario.name] = round(radius, 6)
        if radius >= 1.0:
            unstable.append(scenario.name)
    where = f"; unstable on {', '.join(unstable)}" if unstable else "; stable on every linear standard scenario"
    unsupervised = ", without the supervisor" if experiment.supervisor is not None else ""
    return {
        "passed": design < 1.0,
        "summary": f"spectral radius {design:.5f} on the design model (linearised at rest{unsupervised}){where}",
        "spectral_radius_design_model": round(design, 6),
        "spectral_radius_scenarios": per_scenario,
    }


class _Silent:
    """A random generator that draws zeros: the noise-free closed loop."""

    def standard_normal(self, size) -> np.ndarray:
        return np.zeros(size)


def closed_loop_matrix(plant: Plant, controller: PolicyController, step: float = 1e-4) -> np.ndarray:
    """A with s_{k+1} = A s_k for the closed loop linearised at rest without ground motion, noise or
    supervisor (`control.supervisor`: its trigger keeps a policy off at rest, its dissipative rule is
    not differentiable there), s = [plant state x; observation] (the observation holds the sensor
    history, the filter's estimate and the last actions, so it is the controller's whole state). Central differences of
    one batched control step from +/- `step` along each coordinate (exact for a linear policy)."""
    if plant.experiment.supervisor is not None:
        plant = Plant(plant.experiment.model_copy(update={"supervisor": None}))
    n_x, n_o = plant.n_state, plant.layout.size
    size = n_x + n_o
    batch = BuildingBatch(plant, 2 * size)
    still = Load("at rest", plant.control_dt, np.zeros(3), synthetic=True)
    for member in range(2 * size):
        batch.start(member, _Silent(), still)
    basis = np.vstack([np.eye(size), -np.eye(size)]) * step
    batch.plant_states()[:] = basis[:, :n_x]
    batch.observations[:] = basis[:, n_x:]
    batch.read_back_estimates()
    controller.reset()
    observations, _, _ = batch.step(controller.act(batch.observations.copy()))
    after = np.hstack([batch.plant_states(), observations])
    return ((after[:size] - after[size:]) / (2.0 * step)).T


def spectral_radius(plant: Plant, controller: PolicyController) -> float:
    return float(np.max(np.abs(np.linalg.eigvals(closed_loop_matrix(plant, controller)))))


def verdict_path(folder: Path, model: str, standard: str = "") -> Path:
    """MODEL_check.yaml: the verdict under the project's standard; MODEL_check-NAME.yaml under another."""
    return folder / f"{model}_check{'-' + standard if standard else ''}.yaml"


def judged_digests(folder: Path, model: str, standard: SafetyCheckConfig) -> dict[str, str]:
    """sha256 of what a verdict judges: the policy's files, the experiment it runs in (the run's
    config.yaml) and the standard (its resolved settings, so a comment does not count; `also` when it has one)."""
    names = (f"{model}_policy.yaml", f"{model}_policy.npz", "config.yaml")
    digests = {name: hashlib.sha256((folder / name).read_bytes()).hexdigest() for name in names}
    settings = standard.model_dump(mode="json", exclude={"also"} if standard.also is None else None)
    digests["standard"] = hashlib.sha256(json.dumps(settings, sort_keys=True).encode()).hexdigest()
    return digests


def write_verdict(verdict: Verdict, folder: Path, model: str, standard: str = "") -> Path:
    return atomic_write(verdict_path(folder, model, standard), verdict.to_yaml())


@dataclass(frozen=True)
class VerdictState:
    """What a folder's verdict says of its policy as it is now: `passed` True or False, or None with
    `reason` when there is none that judged these files."""

    passed: bool | None
    reason: str = ""


def read_verdict(folder: Path, model: str, standard: SafetyCheckConfig) -> VerdictState:
    """The verdict on a folder's `model` policy under `standard`, if it judged the files the folder holds
    now: a verdict without digests, or whose digests differ (weights, policy, experiment or standard
    changed since), or that is unreadable counts as never checked, with the reason."""
    path = verdict_path(folder, model)
    if not path.is_file():
        return VerdictState(None, "never safety-checked")
    try:
        verdict = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (yaml.YAMLError, UnicodeDecodeError, OSError):
        return VerdictState(None, f"its verdict {path.name} is unreadable")
    passed = verdict.get("passed") if isinstance(verdict, dict) else None
    judged = verdict.get("judged") if isinstance(verdict, dict) else None
    if not isinstance(passed, bool):
        return VerdictState(None, f"its verdict {path.name} says neither passed nor failed")
    if not isinstance(judged, dict):
        return VerdictState(None, f"its verdict {path.name} does not say which files it judged")
    try:
        now = judged_digests(folder, model, standard)
    except OSError:
        return VerdictState(None, "a file its verdict judged is missing")
    changed = [name for name, digest in now.items() if judged.get(name) != digest]
    if changed:
        return VerdictState(None, f"{', '.join(changed)} changed since its verdict {path.name}")
    return VerdictState(passed)
