"""Every controller judged on a suite of loads: `rlc evaluate`, `rlc compare lqg`, `rlc compare passive`
and `rlc robustness` as functions. Each builds the plant once, resolves the suite (`physics.motions.loads`),
simulates, writes its tables and plots into a new folder and returns what it computed."""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rlcontroller.api.common import (
    DEFAULT_JUDGING,
    QUIET,
    Judging,
    Report,
    folder_experiment,
    keep_model_messages,
    load,
    model_folder,
    motions_text,
    output_folder,
)
from rlcontroller.assets import SAFETY_STANDARD
from rlcontroller.bounds import MAX_HORIZON
from rlcontroller.config import ConfigError, Experiment
from rlcontroller.config.scenarios import standard_scenarios
from rlcontroller.files import check_new_folder, new_folder
from rlcontroller.simulation.fanout import model_messages

# J1-J4 always; "benchmark" adds Ohtori et al.'s J1-J17 (evaluation.benchmark)
CRITERIA = ("paper", "benchmark")


def comparison(
    experiment: Experiment,
    run_dir: Path | None,
    *,
    judging: Judging,
    report: Report = QUIET,
    mpc: int | None = None,
):
    """The plant, the loads and the evaluation of every controller on `judging`'s records (the run's policy
    if given; MPC with a horizon of `mpc` control steps if given); with the criteria "benchmark" an FE plant's
    member ends are read too (`physics.fe.connections`)."""
    from rlcontroller.control.policy_file import read_policy
    from rlcontroller.evaluation.evaluation import compare, progress_total
    from rlcontroller.physics.motions.loads import load_suite
    from rlcontroller.physics.plant import Plant

    criteria = judging.criteria
    if criteria not in CRITERIA:
        raise ConfigError(f"--criteria {criteria}: expected one of {', '.join(CRITERIA)}")
    plant = Plant(experiment)
    if criteria == "benchmark" and plant.building.story_heights is None:
        name = experiment.building.name
        raise ConfigError(
            f"--criteria benchmark: the building {name} has no story_heights (J1, J4: drift ratios)"
        )
    if plant.fe_model is not None:
        report.note(
            f"plant: the OpenSees model {plant.fe_model.path} (designed on: {experiment.building.name})"
        )
        plant.fe_model.record_connections = plant.bare.fe_model.record_connections = criteria == "benchmark"
    policy = read_policy(run_dir, judging.model, plant) if run_dir is not None else None
    extra = ()
    if mpc is not None:
        from rlcontroller.control.mpc_controllers import mpc_controller

        extra = (mpc_controller(plant.design, mpc),)
    motions, label = load_suite(judging.records, judging.scale_pga, plant, report.note)
    with report.progress(
        f"evaluating {motions_text(len(motions))}", progress_total(plant, motions)
    ) as advance:
        evaluation = compare(plant, motions, label, policy=policy, on_motions=advance, extra=extra)
    for controller in extra:
        if controller.fallbacks:
            report.note(
                f"{controller.name}: OSQP did not solve {controller.fallbacks} steps; the last plan's next "
                "action taken (LQR's clipped action where none was left)"
            )
    return plant, motions, evaluation


def evaluate(
    *,
    run_dir: Path | None = None,
    judging: Judging = DEFAULT_JUDGING,
    out: Path | None = None,
    config: Path | None = None,
    report: Report = QUIET,
):
    """A run's (default: the default model's) policy against LQG and no control on `judging`'s records:
    returns the `Evaluation` and the folder its J1-J4 tables and the paper's plots were written to (with the
    criteria "benchmark" benchmark_criteria.csv and .md too). `config`: the experiment to judge it in instead
    of its own (another plant, e.g. an OpenSees model, for the same design: its building, actuators and
    sensors)."""
    from rlcontroller.api.safety import unchecked_note
    from rlcontroller.evaluation.benchmark import write_benchmark
    from rlcontroller.evaluation.report import write_report

    folder = model_folder(run_dir, report)
    out = output_folder(out, f"evaluate-{folder.resolve().name}")
    check_new_folder(out)
    experiment = folder_experiment(folder) if config is None else load(config)
    # matplotlib's import and the plots on the other core
    with drawing() as plots, model_messages() as messages:
        plant, _, evaluation = comparison(experiment, folder, judging=judging, report=report)
        with new_folder(out) as staging:
            # once the records are read (a bad one is its only line), while the plots are drawn
            write_report(
                evaluation,
                staging,
                plots,
                meanwhile=lambda: report.note(unchecked_note(folder, judging.model)),
            )
            if judging.criteria == "benchmark":
                write_benchmark(evaluation, plant.building, staging)
            keep_model_messages(messages, staging, report)
    return evaluation, out


@contextmanager
def drawing() -> Iterator:
    """A drawing process for `write_report` where there is a second core to run it on (and fork), else
    None."""
    if (os.cpu_count() or 1) < 2 or not hasattr(os, "fork"):
        yield None
        return
    from rlcontroller.evaluation.report import Drawing

    with Drawing() as plots:
        yield plots


@dataclass
class LQGComparison:
    """What `compare_lqg` computed: the evaluation, the folder, and the text of the studies asked for."""

    evaluation: object
    out: Path
    sweep: str | None = None
    preview: str | None = None


def compare_lqg(
    *,
    run_dir: Path | None = None,
    config: Path | None = None,
    judging: Judging = DEFAULT_JUDGING,
    out: Path | None = None,
    sweep: bool = False,
    preview: bool = False,
    mpc: int | None = None,
    report: Report = QUIET,
) -> LQGComparison:
    """LQG with the reward's cost (and its variants) against no control and, given a run, its policy, on
    `judging`'s records; with `sweep` LQG's trade-off over force weights (dampers: passive levels and
    clipped-optimal weights), with `preview` full-state LQR knowing the ground ahead, with `mpc` MPC over
    that many control steps (docs/mpc.md); with the criteria "benchmark" the nonlinear benchmark's J1-J17 too
    (`evaluate`)."""

    from rlcontroller.evaluation.benchmark import write_benchmark
    from rlcontroller.evaluation.evaluation import (
        DAMPER_LEVELS,
        LQG_VARIANTS,
        OPTIMAL,
        PREVIEW_SECONDS,
        damper_sweep,
        lqg_sweep,
        mean_metric,
        preview_study,
    )
    from rlcontroller.evaluation.report import write_report
    from rlcontroller.evaluation.study_report import write_damper_sweep, write_preview, write_sweep

    if config is not None and run_dir is not None:
        raise ConfigError("--config: either a run folder or --config, not both")
    if config is None:
        run_dir = model_folder(run_dir, report)
        experiment = folder_experiment(run_dir)
    else:
        experiment = load(config)
    if not experiment.command_labels():
        raise ConfigError(
            f"{config}: nothing to command (no actuators, no active devices): try rlc compare passive"
        )
    if mpc is not None and not 1 <= mpc <= MAX_HORIZON:
        raise ConfigError(f"--mpc {mpc}: expected a horizon of 1..{MAX_HORIZON} control steps")
    if experiment.has_dampers and preview:
        raise ConfigError("--preview: the preview bound needs a plant without semi-active dampers")
    out = output_folder(out, f"compare_lqg-{run_dir.resolve().name if run_dir else experiment.name}")
    check_new_folder(out)
    with model_messages() as messages:  # what an FE model prints goes to opensees.log
        plant, motions, evaluation = comparison(experiment, run_dir, judging=judging, report=report, mpc=mpc)
        label = evaluation.label
        with new_folder(out) as staging:
            write_report(evaluation, staging)
            if judging.criteria == "benchmark":
                write_benchmark(evaluation, plant.building, staging)
            if sweep and experiment.has_dampers:
                levels, multipliers = DAMPER_LEVELS, np.logspace(-2, 2, 9)
                with report.progress("dampers' trade-off", len(motions)) as advance:
                    table = damper_sweep(
                        plant, motions, label, levels, multipliers=multipliers, on_motions=advance
                    )
                names = [name for name in evaluation.controllers if name not in ("uncontrolled",)]
                points = {n: tuple(mean_metric(evaluation, n, m) for m in ("J1", "J2", "J3")) for n in names}
                write_damper_sweep(table, staging, label, points)
            elif sweep:
                multipliers = np.logspace(-2, 2, 9)
                with report.progress("LQG trade-off", multipliers.size) as advance:
                    table = lqg_sweep(plant, motions, label, multipliers, on_point=lambda: advance())
                names = [
                    name for name in ("RL", *LQG_VARIANTS[1:], OPTIMAL) if name in evaluation.controllers
                ]
                points = {
                    n: (mean_metric(evaluation, n, "J3"), mean_metric(evaluation, n, "J1")) for n in names
                }
                write_sweep(table, staging, label, points)
            if preview:
                names = [name for name in evaluation.controllers if name not in ("uncontrolled", OPTIMAL)]
                references = {
                    n: (mean_metric(evaluation, n, "J1"), mean_metric(evaluation, n, "J2")) for n in names
                }
                with report.progress("preview horizons", len(PREVIEW_SECONDS)) as advance:
                    study = preview_study(plant, motions, on_horizon=lambda: advance())
                write_preview(study, staging, label, references)
            keep_model_messages(messages, staging, report)
    sweep_file = "damper_sweep.md" if experiment.has_dampers else "lqg_sweep.md"
    return LQGComparison(
        evaluation,
        out,
        (out / sweep_file).read_text() if sweep else None,
        (out / "preview.md").read_text() if preview else None,
    )


def compare_passive(
    config: Path,
    *,
    records: Path | None = None,
    out: Path | None = None,
    scale_pga: float | None = None,
    report: Report = QUIET,
):
    """The building without its devices (uncontrolled) and with them passive: tuned masses as tuned,
    active mass drivers as the tuned masses they are without a command; under ground motion also the
    devices' own verdict: the safety check's suite criterion, the passive devices against the building
    without them (passive_check.yaml). Returns the evaluation, its folder and the verdict (None under
    wind)."""
    from rlcontroller.config import load_safety_check
    from rlcontroller.evaluation.evaluation import PASSIVE, progress_total
    from rlcontroller.evaluation.evaluation import evaluate as evaluate_controllers
    from rlcontroller.evaluation.report import write_report
    from rlcontroller.evaluation.safety import passive_verdict
    from rlcontroller.evaluation.verdict import Verdict
    from rlcontroller.physics.motions.loads import load_suite
    from rlcontroller.physics.plant import Plant

    experiment = load(config)
    if not experiment.devices:
        raise ConfigError(f"{config}: devices: none, so nothing passive to compare")
    out = output_folder(out, f"compare_passive-{experiment.name}")
    check_new_folder(out)
    plant = Plant(experiment)
    motions, label = load_suite(records, scale_pga, plant, report.note)
    with report.progress(
        f"evaluating {motions_text(len(motions))}", progress_total(plant, motions)
    ) as advance:
        evaluation = evaluate_controllers(
            plant, motions, [], label, include_optimal=False, on_motions=advance
        )
    verdict = None
    if experiment.load_kind == "ground motion":
        standard = load_safety_check(SAFETY_STANDARD)
        with report.progress(f"devices' verdict, {standard.motions} motions", 1) as advance:
            criterion = passive_verdict(plant, standard)
            advance(1)
        verdict = Verdict(PASSIVE, criterion.passed, {"check suite": criterion})
    with new_folder(out) as staging:
        write_report(evaluation, staging)
        if verdict is not None:
            (staging / "passive_check.yaml").write_text(verdict.to_yaml(), encoding="utf-8")
    return evaluation, out, verdict


def robustness(
    *,
    run_dir: Path | None = None,
    records: Path | None = None,
    scenarios: Path | None = None,
    out: Path | None = None,
    scale_pga: float | None = None,
    model: str = "best",
    report: Report = QUIET,
):
    """Every controller on every scenario's plant and every record: returns the mean-J1 table (scenario x
    controller), the suite's label, the scenarios run, the seconds taken and the folder written."""
    from rlcontroller.config import load_scenarios
    from rlcontroller.control.policy_file import read_policy
    from rlcontroller.evaluation.robustness import robustness as run_robustness
    from rlcontroller.evaluation.robustness import summary
    from rlcontroller.evaluation.study_report import write_robustness
    from rlcontroller.physics.motions.loads import load_suite
    from rlcontroller.physics.plant import Plant

    folder = model_folder(run_dir, report)
    experiment = folder_experiment(folder)
    named = load_scenarios(scenarios or standard_scenarios(experiment), experiment)
    plant = Plant(experiment)
    policy = read_policy(folder, model, plant)
    out = output_folder(out, f"robustness-{folder.resolve().name}")
    check_new_folder(out)
    motions, label = load_suite(records, scale_pga, plant, report.note)
    if any(motion.floor_forces is not None for motion in motions):
        linear = [
            scenario for scenario in named if scenario.plant is None or scenario.plant.hysteresis is None
        ]
        if len(linear) < len(named):
            skipped = ", ".join(s.name for s in named if s not in linear)
            report.note(
                f"note: skipped under floor loads (yielding stories are not modelled with them): {skipped}"
            )
        named = linear
    with report.progress(f"{len(named)} scenarios", len(named)) as advance:
        table, seconds = run_robustness(
            experiment, named, motions, label, policy=policy, on_scenario=lambda name: advance(1, name)
        )
    with new_folder(out) as staging:
        write_robustness(table, named, staging, label, seconds=seconds)
    mean_j1 = summary(table)["J1"].unstack("controller").rename_axis("scenario (mean J1)")
    return mean_j1, label, named, seconds, out


def summary_text(evaluation, out: Path) -> str:
    """The tables a command prints after an evaluation: J1-J4 per controller, the improvement over LQG,
    J1 and J2 by PGA band, and where the files are."""
    from rlcontroller.evaluation.tables import (
        LEGEND,
        by_pga,
        improvement_table,
        markdown_table,
        summary_table,
    )

    lines = [f"# {evaluation.label}"]
    lines += [f"{name}: {source}" for name, source in evaluation.sources.items()]
    lines += [markdown_table(summary_table(evaluation)), LEGEND]
    improvement = improvement_table(evaluation)
    if improvement is not None:
        lines.append(markdown_table(improvement, digits=1))
    for metric in ("J1", "J2"):
        banded = markdown_table(by_pga(evaluation, metric))
        lines += [f"mean {metric} by the record's PGA (records in the band):", banded]
    metrics = evaluation.metrics
    fallen = metrics[(metrics.metric == "collapsed") & (metrics.value > 0)]
    for controller, rows in fallen.groupby("controller", sort=False):
        records = ", ".join(dict.fromkeys(rows.record))
        lines.append(f"{controller}: collapsed (a story past its collapse drift) on {records}")
    if (out / "benchmark_criteria.md").is_file():
        lines.append((out / "benchmark_criteria.md").read_text().rstrip())
    count = len(evaluation.records)
    lines.append(f"evaluated {motions_text(count)} in {evaluation.seconds:.1f} s; tables and plots in {out}")
    return "\n".join(lines)
