"""Training as the commands do it: `rlc train` (a new run or a resumed one, then its safety check) and
`rlc demo` (train the demo, evaluate it, check it)."""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

from rlcontroller.api.common import QUIET, Judging, Report, folder_experiment, load
from rlcontroller.api.safety import check
from rlcontroller.assets import DEMO_CONFIG
from rlcontroller.config import ConfigError, Experiment, load_experiment, with_overrides
from rlcontroller.config.experiment import LEARNED_ON_FE_MODEL


@dataclass
class Trained:
    """A training's summary (`learning.training.TrainingSummary`), its safety verdict and verdict file
    (None when training stopped before the end), and for the demo its evaluation and folder."""

    summary: object
    verdict: object = None
    verdict_file: Path | None = None
    evaluation: object = None
    evaluation_folder: Path | None = None


def train(
    *,
    config: Path | None = None,
    resume: Path | None = None,
    total_steps: int | None = None,
    seed: int | None = None,
    run_dir: Path | None = None,
    device: str = "auto",
    time_limit_minutes: float | None = None,
    progress_bar: bool = False,
    tensorboard: bool = False,
    report: Report = QUIET,
) -> Trained:
    """Train the experiment of `config` (with `total_steps` and `seed` overriding its own) into a new run
    folder, or continue the run folder `resume` from its newest checkpoint; a run that reaches its end
    is safety-checked."""
    from rlcontroller.learning.training import train as run_training

    if device not in ("cpu", "cuda", "auto"):
        raise ConfigError(f"--device: expected cpu, cuda or auto, got {device!r}")
    if device == "cuda":
        import torch

        if not torch.cuda.is_available():
            raise ConfigError(
                "--device cuda: no CUDA GPU is visible to torch here; use --device cpu (or auto)"
            )
    limit = None if time_limit_minutes is None else 60.0 * time_limit_minutes
    options = {
        "device": device,
        "progress_bar": progress_bar,
        "time_limit_s": limit,
        "tensorboard": tensorboard,
    }
    if resume is not None:
        experiment = _fe_experiment_of(resume, config)
        if (config is not None and experiment is None) or total_steps is not None or seed is not None:
            raise ConfigError(
                "--resume: continues the run's own config; drop CONFIG, --total-steps and --seed"
            )
        report.line(resume_line(resume))
        summary = run_training(experiment=experiment, resume=resume, **options)
    else:
        if config is None:
            raise ConfigError(
                "rlc train: expected an experiment YAML (e.g. configs/experiments/demo.yaml; "
                "configs/README.md "
                "lists them) or --resume RUN"
            )
        experiment = load(config)
        overrides = {"algorithm.total_steps": total_steps, "seed": seed}
        given = {key: value for key, value in overrides.items() if value is not None}
        if given:
            experiment = with_overrides(experiment, given, "--total-steps/--seed")
        summary = run_training(experiment=experiment, run_dir=run_dir, **options)
    report.line(summary.line())
    if summary.interrupted or summary.time_limit_reached:
        return Trained(summary)
    fe_model = experiment.plant.opensees if experiment is not None and experiment.plant is not None else None
    # the plant it learned on
    judged_in = config if fe_model is not None and fe_model.train_on == "fe" else None
    return Trained(summary, *check(summary.run_dir, model="best", report=report, config=judged_in))


def _fe_experiment_of(run: Path, config: Path | None) -> Experiment | None:
    """The experiment of a run that learned on an OpenSees model, which its folder does not keep: the
    folder's own, with the plant of `config` (named again, naming the same model file); None for any other
    run."""
    kept = run / "config.yaml"
    lines = kept.read_text().splitlines()[:2] if kept.is_file() else []
    if not any(line.startswith(LEARNED_ON_FE_MODEL) for line in lines):
        return None
    if config is None:
        raise ConfigError(
            f"{kept}: learned on an OpenSees model, which a run folder never runs: name its experiment to "
            f"continue (rlc train EXPERIMENT --resume {run})"
        )
    named = load(config)
    fe_model = named.plant.opensees if named.plant is not None else None
    if fe_model is None or f" {fe_model.model} " not in lines[0]:
        raise ConfigError(
            f"{config}: does not name the OpenSees model {run} learned on ({lines[0].lstrip('# ')})"
        )
    return folder_experiment(run).model_copy(update={"plant": named.plant})


def resume_line(run: Path) -> str:
    """Where a resumed run continues from: its newest complete checkpoint, or the start."""
    from rlcontroller.learning.run_folder import RunFolder

    if not (run / "config.yaml").is_file():
        return f"resuming {run}"
    total = load_experiment(run / "config.yaml", self_contained=True).algorithm.total_steps
    checkpoints = RunFolder(run).checkpoints()
    step = int(checkpoints[-1].name.removeprefix("step_")) if checkpoints else 0
    return f"resuming {run} at step {step:,} of {total:,}" + (
        "" if checkpoints else " (no checkpoint yet: from the start)"
    )


def demo(records: Path | None = None, progress_bar: bool = False, report: Report = QUIET) -> Trained:
    """The main job end to end: learn a controller from nothing, with no model of the building
    (configs/experiments/demo.yaml), evaluate it against LQG and the uncontrolled building on `records`
    (RUN/evaluation), and run the safety check on it."""
    from rlcontroller.api.judging import comparison, summary_text
    from rlcontroller.evaluation.report import write_report
    from rlcontroller.files import new_folder
    from rlcontroller.learning.training import train as run_training
    from rlcontroller.physics.motions.records import choose_motions

    choose_motions(records)  # a bad --records stops here, before training
    summary = run_training(experiment=load_experiment(DEMO_CONFIG), progress_bar=progress_bar)
    report.line(summary.line())
    report.line(learned_line(summary.run_dir))
    experiment = folder_experiment(summary.run_dir)
    _, _, evaluation = comparison(
        experiment, summary.run_dir, judging=Judging(records=records), report=report
    )
    out = summary.run_dir / "evaluation"
    with new_folder(out) as staging:
        write_report(evaluation, staging)
    report.line(summary_text(evaluation, out))
    return Trained(summary, *check(summary.run_dir, model="best", report=report), evaluation, out)


def learned_line(run: Path) -> str:
    """What training changed, from the run's learning curve: validation J1 at the start and at the best
    model, beside the LQGs' on the same validation motions."""

    with (run / "learning_curve.csv").open(newline="") as file:
        rows = list(csv.DictReader(file))
    start, best = rows[0], min(rows, key=lambda row: float(row["eval_J1"]))
    return (
        f"learned: validation J1 {float(start['eval_J1']):.3f} at step 0 -> {float(best['eval_J1']):.3f} at "
        f"step {int(best['steps']):,} ({float(best['wall_time_s']):.0f} s); LQG with the same cost and "
        f"sensors, designed on the building's matrices: {float(best['lqg_J1']):.3f} (LQG + ground model "
        f"{float(best['lqg_ground_model_J1']):.3f}), on the same generated validation motions"
    )
