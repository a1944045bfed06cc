"""Controllers as they leave the project: the shipped ones (`rlc models`), one as an ONNX file
(`rlc export`), and an old run's stable-baselines3 zips turned into policy data (`rlc convert`)."""

from __future__ import annotations

from pathlib import Path

import yaml

from rlcontroller.api.common import QUIET, Report, folder_experiment, load, model_folder, shipped_folders
from rlcontroller.api.safety import unchecked_note, verdict_state
from rlcontroller.assets import CONFIGS, DEFAULT_MODEL
from rlcontroller.config import ConfigError, Experiment


def shipped_models() -> list[str]:
    """The shipped controllers under models/ grouped by what they are made for (building, load, actuators,
    devices), one line each: how it was made, its safety verdict, the default marked; then what the
    experiments under configs/experiments are made for that no controller ships for."""

    from rlcontroller.api.certify import certificate_summary
    from rlcontroller.api.describe import hardware_label

    groups: dict[str, list[str]] = {}
    shipped = {folder: folder_experiment(folder) for folder in shipped_folders()}
    for folder, experiment in shipped.items():
        policy = yaml.safe_load((folder / "best_policy.yaml").read_text())
        state = verdict_state(folder, "best")
        passed = "safety check passed, dominates" if state.dominates else "safety check passed"
        verdict = {True: passed, False: "safety check FAILED"}.get(state.passed)
        mark = " (default)" if folder == DEFAULT_MODEL else ""
        made = (
            f"classical, {policy['law']}"
            if policy.get("kind") == "classical"
            else f"{policy['algorithm']}, {policy['training_steps']:,} steps"
        )
        line = f"  {folder.name}{mark}: {made}, {verdict or f'never checked ({state.reason})'}; "
        line += certificate_summary(folder)
        groups.setdefault(hardware_label(experiment), []).append(line)
    lines = [text for label, members in groups.items() for text in [f"{label}:", *members]]
    lines.append("each verdict is its folder's claim until re-run: 'rlc check models/NAME --verify'")
    unshipped, passive = unshipped_experiments()
    unserved: dict[str, list[str]] = {}
    for name, experiment in unshipped.items():
        if isinstance(experiment, str):
            lines.append(f"{name}: not read here: {experiment}")
            continue
        unserved.setdefault(hardware_label(experiment), []).append(name)
    if unserved:
        lines.append("none ships yet (models/README.md says why) for:")
        lines += [f"  {label} ({', '.join(names)})" for label, names in unserved.items()]
    if passive:
        lines.append(f"nothing to command, its verdict from 'rlc compare passive': {', '.join(passive)}")
    return lines


def unshipped_experiments() -> tuple[dict[str, Experiment | str], list[str]]:
    """The experiments under configs/experiments (by name) with something to command that no shipped
    controller is made for (or, where one cannot be read here, e.g. an FE model without OpenSees, why), and
    the names of those with nothing to command."""
    served = [folder_experiment(folder).hardware() for folder in shipped_folders()]
    unshipped: dict[str, Experiment | str] = {}
    passive: list[str] = []
    for config in sorted((CONFIGS / "experiments").glob("*.yaml")):
        try:
            experiment = load(config)
        except ConfigError as error:
            unshipped[config.stem] = str(error)
            continue
        if not experiment.command_labels():
            passive.append(config.stem)
        elif experiment.hardware() not in served:
            unshipped[config.stem] = experiment
    return unshipped, passive


def design(config: Path, law: str, out: Path, report: Report = QUIET) -> Path:
    """A classical controller as a controller folder: `law` (a key of `control.classical.LAWS`: the
    experiment's LQG on its Kalman estimate, MPC on the same, or passive-on / passive-off dampers) designed
    for the experiment of `config`, written with its resolved config.yaml to the new folder `out` (never over
    an existing one). evaluate, check and export then treat it like a trained policy. Returns `out`."""
    from rlcontroller.control.classical import LAWS, classical_policy
    from rlcontroller.control.policy_file import write_policy
    from rlcontroller.files import atomic_write
    from rlcontroller.physics.plant import Plant

    if out.exists():
        raise ConfigError(
            f"--out {out}: exists; a controller folder is never overwritten (choose another --out)"
        )
    if law not in LAWS:
        raise ConfigError(f"--law {law}: expected one of {', '.join(LAWS)}")
    experiment = load(config)
    plant = Plant(experiment)
    controller = classical_policy(plant, law)
    out.mkdir(parents=True)
    atomic_write(out / "config.yaml", experiment.to_yaml())
    write_policy(controller, plant, out, "best")
    report.line(f"wrote {out}: {controller.designed}")
    return out


def export(
    run_dir: Path | None = None, out: Path | None = None, model: str = "best", report: Report = QUIET
) -> Path:
    """A folder's policy (default: the default model's) as one ONNX file: sensor readings (SI) and its own
    state in, forces (N) out; `out` defaults to results/FOLDER_MODEL_controller.onnx and is never
    overwritten. Returns the file written."""
    from rlcontroller.deployment.export import export_onnx

    folder = model_folder(run_dir, report)
    if out is None:
        Path("results").mkdir(exist_ok=True)
        out = Path("results") / f"{folder.resolve().name}_{model}_controller.onnx"
    if out.exists():
        raise ConfigError(f"--out {out}: exists; an export is never overwritten (choose another --out)")
    if not out.parent.is_dir():
        raise ConfigError(f"--out {out}: expected a file path in an existing folder")
    report.note(unchecked_note(folder, model))
    export_onnx(folder, model, out)
    outputs = "forces (N) and damper commands" if folder_experiment(folder).has_dampers else "forces (N)"
    report.line(f"wrote {out}: readings (SI) and state in, {outputs} out; see docs/deployment.md")
    return out


def convert(run_dir: Path, trust_pickle: bool = False) -> list[Path]:
    """Write a run's stable-baselines3 models as policy data (best/final_policy.yaml + .npz), the files
    that evaluate, check and export read without unpickling; `trust_pickle` must be given, since opening
    a zip runs whatever code its author put in it. Returns the YAML files written."""
    from rlcontroller.learning.sb3_models import convert as convert_models

    if not trust_pickle:
        raise ConfigError(
            f"{run_dir}: converting opens pickles, which can run their author's code; "
            "add --trust-pickle only if you trust whoever made this folder"
        )
    model_folder(run_dir)
    return convert_models(run_dir)
