"""The safety check as a command does it: run it on a folder's policy and write the verdict, read a
folder's verdict back, and say when a policy about to be used failed or was never checked."""

from __future__ import annotations

from pathlib import Path

from rlcontroller.api.common import QUIET, Report, folder_experiment, load, output_folder, safety_standard
from rlcontroller.api.common import standard_scenarios as default_scenarios
from rlcontroller.assets import MODELS
from rlcontroller.config import ConfigError


def check(
    folder: Path,
    model: str = "best",
    standard: Path | None = None,
    scenarios: Path | None = None,
    report: Report = QUIET,
    config: Path | None = None,
):
    """The safety check of a folder's saved policy under `standard` (default: the project's standard for
    its experiment, `safety_standard`): returns the verdict and the file it was written to, MODEL_check.yaml
    in the folder (MODEL_check-STANDARD.yaml under another standard), or for a shipped model (whose files
    stay as shipped) in a new folder under results/. `config`: the experiment to check it in instead of its
    own (another plant for the same design, e.g. an OpenSees model); its verdict goes to a new folder under
    results/, as it judges the policy on a plant its folder does not name."""
    from rlcontroller.config import display_path, load_safety_check, load_scenarios
    from rlcontroller.control.policy_file import read_policy
    from rlcontroller.evaluation.safety import judged_digests, safety_check, write_verdict
    from rlcontroller.physics.plant import Plant

    experiment = folder_experiment(folder) if config is None else load(config)
    plant = Plant(experiment)
    policy = read_policy(folder, model, plant)
    own = safety_standard(experiment)
    standard = standard or own
    checking = load_safety_check(standard)
    loads = "wind loads" if checking.generator.kind == "wind" else "motions"
    if (also := checking.also) is not None:
        also = f", {also.motions} generated {'wind loads' if also.generator.kind == 'wind' else 'ground motions'}"
    report.line(
        f"checking {display_path(folder)}'s {model} policy: {checking.motions} generated {loads}, "
        f"{checking.rest_runs} runs at rest{also or ''}, closed-loop stability..."
    )
    named = load_scenarios(scenarios or default_scenarios(experiment), experiment)
    with report.progress("safety check", 3 + (checking.also is not None)) as advance:
        try:
            verdict = safety_check(plant, policy, checking, named, on_criterion=lambda name: advance(1, f"{name} done"))
        except ConfigError as error:  # the standard asks for what this building has not
            raise ConfigError(f"{display_path(standard)}: {error}") from None
    verdict.judged = judged_digests(folder, model, checking)
    target = folder
    if config is not None or folder.resolve().is_relative_to(MODELS.resolve()):
        on = "" if config is None else f"-on-{experiment.name}"
        target = output_folder(None, f"check-{folder.resolve().name}{on}")
        target.mkdir(parents=True)
    other = "" if standard.resolve() == own.resolve() else standard.stem  # keeps the standard's verdict
    return verdict, write_verdict(verdict, target, model, other)


def verdict_state(folder: Path, model: str):
    """The verdict on a folder's policy under the project's standard for its experiment, if it judged these files."""
    from rlcontroller.config import load_safety_check
    from rlcontroller.evaluation.safety import read_verdict

    return read_verdict(folder, model, load_safety_check(safety_standard(folder_experiment(folder))))


def unchecked_note(folder: Path, model: str) -> str | None:
    """One line when the policy failed the safety check or was never checked (as its files are now)."""
    from rlcontroller.evaluation.safety import verdict_path

    state = verdict_state(folder, model)
    if state.passed is None:
        why = "" if state.reason == "never safety-checked" else f" ({state.reason})"
        return f"note: {folder}'s {model} policy counts as never safety-checked{why}; run 'rlc check {folder}'"
    if not state.passed:
        return (
            f"warning: {folder}'s {model} policy FAILED the safety check (it can be worse than no control): "
            f"{verdict_path(folder, model)}"
        )
    return None


def verdict_lines(folder: Path, model: str) -> tuple[list[str], bool]:
    """`rlc check --show`: the verdict's lines when it judged the folder's files as they are, and whether
    it passed (False too when there is no such verdict)."""
    import yaml

    from rlcontroller.evaluation.safety import Verdict, verdict_path

    state = verdict_state(folder, model)
    if state.passed is None:
        return [f"{folder}'s {model} policy counts as never safety-checked: {state.reason}"], False
    path = verdict_path(folder, model)
    lines = Verdict(**yaml.safe_load(path.read_text(encoding="utf-8"))).lines()
    lines.append(f"verdict in {path}, judging these files (sha256 of policy, experiment and standard match)")
    return lines, bool(state.passed)
