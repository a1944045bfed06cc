"""Commands that make one controller: `rlc info`, `train`, `demo`."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rlcontroller.bounds import MAX_SEED, MAX_TOTAL_STEPS
from rlcontroller.cli.app import Printed, ProgressOption, RecordsOption, app, positive_finite, user_errors


@app.command(short_help="An experiment resolved: building, periods, actuators.")
@user_errors
def info(
    config: Annotated[
        Path | None, typer.Argument(help="Experiment YAML; the default model's if omitted.")
    ] = None,
    full: Annotated[
        bool, typer.Option("--full", help="Every matrix entry, list value and mode (default: summarised).")
    ] = False,
) -> None:
    """Print the resolved config, natural periods, modal damping ratios (of the design model, and of
    the simulated plant when there is a plant part), actuator layout and devices; matrices by shape,
    source and digest unless --full."""
    from rlcontroller import api

    typer.echo(api.describe(api.load(config), full))


@app.command(short_help="Train a controller on generated motions.")
@user_errors
def train(
    *,
    config: Annotated[
        Path | None,
        typer.Argument(
            help="Experiment YAML (see configs/README.md; with --resume: only for a run learned on an "
            "OpenSees model)."
        ),
    ] = None,
    total_steps: Annotated[
        int | None, typer.Option(min=1, max=MAX_TOTAL_STEPS, help="Override algorithm.total_steps.")
    ] = None,
    seed: Annotated[
        int | None, typer.Option(min=0, max=MAX_SEED, help="Override the experiment's seed.")
    ] = None,
    run_dir: Annotated[
        Path | None, typer.Option(help="Run folder to create (default runs/NAME-seedS-TIME).")
    ] = None,
    resume: Annotated[
        Path | None, typer.Option(help="Continue this run folder from its newest checkpoint.")
    ] = None,
    device: Annotated[
        str, typer.Option(help="cpu, cuda or auto (the CPU: rlc's MLP policies step slower on a GPU).")
    ] = "auto",
    time_limit: Annotated[
        float | None,
        typer.Option(
            callback=positive_finite(1.0e6),
            help="Stop after this many minutes of this invocation (resumable).",
        ),
    ] = None,
    progress: ProgressOption = None,
    tensorboard: Annotated[
        bool,
        typer.Option(
            "--tensorboard",
            help="Also log to RUN/tensorboard (stable-baselines3's logger and the validation J1/J2 with the "
            "LQG references); follow with 'tensorboard --logdir runs'. Needs rlcontroller[tensorboard].",
        ),
    ] = False,
) -> None:
    """Train a controller (SAC, PPO, TD3, DDPG, A2C or random search) on generated ground motions;
    checkpoints resume."""
    from rlcontroller import api

    report = Printed(progress)
    trained = api.train(
        config=config,
        resume=resume,
        total_steps=total_steps,
        seed=seed,
        run_dir=run_dir,
        device=device,
        time_limit_minutes=time_limit,
        progress_bar=report.bars,
        tensorboard=tensorboard,
        report=report,
    )
    summary = trained.summary
    if summary.interrupted or summary.time_limit_reached:
        typer.echo(f"resume with: rlc train --resume {summary.run_dir}")
    if summary.interrupted:
        raise typer.Exit(130)
    if trained.verdict is not None:
        print_verdict(trained.verdict, trained.verdict_file)


def print_verdict(verdict, path: Path) -> None:
    for line in verdict.lines():
        typer.echo(line)
    typer.echo(f"verdict in {path}")


@app.command(short_help="Start here: train, evaluate and check a small controller.")
@user_errors
def demo(records: RecordsOption = None, progress: ProgressOption = None) -> None:
    """The main job end to end: learn a controller from nothing, with no model of the building
    (configs/experiments/demo.yaml, about 30 s), evaluate it against LQG and the uncontrolled building, and
    run the safety check on it (exit code 1 if it fails)."""
    from rlcontroller import api

    report = Printed(progress)
    trained = api.demo(records, report.bars, report)
    print_verdict(trained.verdict, trained.verdict_file)
    if not trained.verdict.passed:  # exit 1, as `rlc check` does: a script (or CI) sees it
        typer.echo("this run's controller failed the safety check: docs/safety_check.md says what that means")
        raise typer.Exit(1)
