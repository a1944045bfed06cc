"""The safety check as a command does it: run it on a folder's policy and write the verdict, read a
folder's verdict back, and say when a policy about to be used failed or was never checked."""

from __future__ import annotations

from pathlib import Path

import yaml

from rlcontroller.api.common import QUIET, Report, folder_experiment, keep_model_messages, load, output_folder
from rlcontroller.assets import MODELS
from rlcontroller.config import ConfigError
from rlcontroller.config.scenarios import safety_standard
from rlcontroller.config.scenarios import standard_scenarios as default_scenarios


def check(
    folder: Path,
    *,
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
    from rlcontroller.evaluation.verdict import write_verdict
    from rlcontroller.simulation.fanout import model_messages

    experiment = folder_experiment(folder) if config is None else load(config)
    own = safety_standard(experiment)
    standard = standard or own
    with model_messages() as messages:  # what an FE model prints goes to opensees.log beside the verdict
        verdict = judged(folder, model, experiment, standard, scenarios=scenarios, report=report)
        target = folder
        if config is not None or folder.resolve().is_relative_to(MODELS.resolve()):
            on = "" if config is None else f"-on-{experiment.name}"
            target = output_folder(None, f"check-{folder.resolve().name}{on}")
            target.mkdir(parents=True)
        keep_model_messages(messages, target, report)
    other = "" if standard.resolve() == own.resolve() else standard.stem  # keeps the standard's verdict
    return verdict, write_verdict(verdict, target, model, other)


def judged(folder: Path, model: str, experiment, standard: Path, *, scenarios: Path | None, report: Report):
    """A folder's policy run through the check of the standard in `standard` on `experiment`'s plant, with the
    digests of what it judged; a progress bar per criterion."""
    from rlcontroller.config import display_path, load_safety_check, load_scenarios
    from rlcontroller.control.policy_file import read_policy
    from rlcontroller.evaluation.safety import safety_check
    from rlcontroller.evaluation.verdict import judged_digests
    from rlcontroller.physics.plant import Plant

    plant = Plant(experiment)
    policy = read_policy(folder, model, plant)
    checking = load_safety_check(standard)
    loads = "wind loads" if checking.generator.kind == "wind" else "motions"
    if (also := checking.also) is not None:
        generated = "wind loads" if also.generator.kind == "wind" else "ground motions"
        also = f", {also.motions} generated {generated}"
    report.line(
        f"checking {display_path(folder)}'s {model} policy: {checking.motions} generated {loads}, "
        f"{checking.rest_runs} runs at rest{also or ''}, closed-loop stability..."
    )
    named = load_scenarios(scenarios or default_scenarios(experiment), experiment)
    with report.progress("safety check", 3 + (checking.also is not None)) as advance:
        try:
            verdict = safety_check(
                plant, policy, checking, named, on_criterion=lambda name: advance(1, f"{name} done")
            )
        except ConfigError as error:  # the standard asks for what this building has not
            raise ConfigError(f"{display_path(standard)}: {error}") from None
    verdict.judged = judged_digests(folder, model, checking)
    return verdict


def verify(
    folder: Path, model: str = "best", scenarios: Path | None = None, report: Report = QUIET
) -> list[str]:
    """`rlc check FOLDER --verify`: re-run the check of a folder's verdict under the project's standard and
    return each recorded figure the re-run does not reproduce (`evaluation.verdict.differences`; empty:
    they agree). The recorded verdict must exist; whether it judged these files is one of the figures."""

    from rlcontroller.config import display_path
    from rlcontroller.evaluation.verdict import differences, verdict_data, verdict_path

    path = verdict_path(folder, model)
    if not path.is_file():
        raise ConfigError(
            f"{display_path(path)}: no verdict to verify; run 'rlc check {display_path(folder)}'"
        )
    try:
        recorded = verdict_data(path.read_text(encoding="utf-8"))
    except (yaml.YAMLError, UnicodeDecodeError) as error:
        raise ConfigError(
            f"{display_path(path)}: unreadable ({type(error).__name__}); nothing to verify"
        ) from None
    if not isinstance(recorded, dict):
        raise ConfigError(
            f"{display_path(path)}: expected a verdict (a mapping), got {type(recorded).__name__}"
        )
    experiment = folder_experiment(folder)
    standard = safety_standard(experiment)
    report.line(f"verifying {display_path(path)}: re-running its check...")
    verdict = judged(folder, model, experiment, standard, scenarios=scenarios, report=report)
    return differences(recorded, yaml.safe_load(verdict.to_yaml()))


def verdict_state(folder: Path, model: str):
    """The verdict on a folder's policy under the project's standard for its experiment, if it judged these
    files and its figures agree with it."""
    from rlcontroller.config import load_safety_check
    from rlcontroller.evaluation.verdict import read_verdict

    experiment = folder_experiment(folder)
    standard = load_safety_check(safety_standard(experiment))
    return read_verdict(folder, model, standard, experiment.building.system)


def claim(folder: Path) -> str:
    """What a verdict read from a folder is, in a few words, and how to verify it."""
    from rlcontroller.config import display_path

    return f"the folder's claim until re-run: 'rlc check {display_path(folder)} --verify'"


def unchecked_note(folder: Path, model: str) -> str:
    """One line on the policy's verdict as its files are now: never checked, FAILED, or passed (whether it
    dominates) as the folder's claim, with the command that verifies it."""
    from rlcontroller.evaluation.verdict import verdict_path

    state = verdict_state(folder, model)
    if state.passed is None:
        why = "" if state.reason == "never safety-checked" else f" ({state.reason})"
        return (
            f"note: {folder}'s {model} policy counts as never safety-checked{why}; run 'rlc check {folder}'"
        )
    if not state.passed:
        return (
            f"warning: {folder}'s {model} policy FAILED the safety check (it can be worse than no control): "
            f"{verdict_path(folder, model)}"
        )
    passed = "passed the safety check, dominating" if state.dominates else "passed the safety check"
    return f"note: {folder}'s {model} policy {passed}: {claim(folder)}"


def verdict_lines(folder: Path, model: str) -> tuple[list[str], bool]:
    """`rlc check --show`: the verdict's lines when it judged the folder's files as they are and agrees with
    its own figures, and whether it passed (False too when there is no such verdict)."""

    from rlcontroller.evaluation.verdict import Verdict, verdict_data, verdict_path

    state = verdict_state(folder, model)
    if state.passed is None:
        return [f"{folder}'s {model} policy counts as never safety-checked: {state.reason}"], False
    path = verdict_path(folder, model)
    lines = Verdict.read(verdict_data(path.read_text(encoding="utf-8"))).lines()
    lines.append(f"verdict in {path}: it judged these files and agrees with its own figures; {claim(folder)}")
    return lines, bool(state.passed)
