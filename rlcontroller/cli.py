"""Command line: parses arguments and calls the library; no physics or RL logic lives here."""

from __future__ import annotations

import sys
from collections.abc import Callable
from functools import wraps
from pathlib import Path
from typing import Annotated, Any

import typer

from rlcontroller.config import ConfigError, Experiment, load_experiment
from rlcontroller.excitation import MotionError

app = typer.Typer(
    add_completion=False, no_args_is_help=True, help="Reinforcement-learning active control of buildings."
)

USER_ERRORS = (ConfigError, MotionError)


@app.callback()
def _commands() -> None:
    """Reinforcement-learning active control of buildings under earthquakes."""


def user_errors(command: Callable[..., Any]) -> Callable[..., Any]:
    """Print a user mistake as one line on stderr and exit with code 2, without a traceback."""

    @wraps(command)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return command(*args, **kwargs)
        except USER_ERRORS as error:
            typer.echo(f"error: {error}", err=True)
            raise typer.Exit(2) from None

    return wrapper


def load(config: Path | None) -> Experiment:
    return Experiment() if config is None else load_experiment(config)


@app.command()
@user_errors
def info(
    config: Annotated[
        Path | None, typer.Argument(help="Experiment YAML; the embedded paper default if omitted.")
    ] = None,
) -> None:
    """Print the resolved config, natural periods, modal damping ratios and actuator layout."""
    from rlcontroller.structure import build

    experiment = load(config)
    building = build(experiment.building, experiment.actuators)
    typer.echo("# resolved configuration")
    typer.echo(experiment.to_yaml())
    typer.echo("# modes")
    typer.echo(f"{'mode':>4}  {'period (s)':>10}  {'frequency (Hz)':>14}  {'damping ratio':>13}")
    for mode, (period, ratio) in enumerate(zip(building.periods(), building.modal_damping_ratios(), strict=True), 1):
        typer.echo(f"{mode:>4}  {period:>10.3f}  {1 / period:>14.3f}  {ratio:>13.4f}")
    typer.echo("\n# actuators")
    for index, actuator in enumerate(experiment.actuators):
        floors = f"floor {actuator.story}"
        if actuator.mount == "inter_story":
            floors = f"+u on floor {actuator.story}, -u on " + (
                f"floor {actuator.story - 1}" if actuator.story > 1 else "the ground"
            )
        typer.echo(
            f"{index + 1}: story {actuator.story}, {actuator.mount}, limit {actuator.force_limit / 1e3:g} kN ({floors})"
        )


@app.command()
@user_errors
def train(
    config: Annotated[Path | None, typer.Argument(help="Experiment YAML (not needed with --resume).")] = None,
    total_steps: Annotated[int | None, typer.Option(min=1, help="Override algorithm.total_steps.")] = None,
    seed: Annotated[int | None, typer.Option(help="Override the experiment's seed.")] = None,
    run_dir: Annotated[Path | None, typer.Option(help="Run folder to create (default runs/NAME-seedS-TIME).")] = None,
    resume: Annotated[Path | None, typer.Option(help="Continue this run folder from its newest checkpoint.")] = None,
    device: Annotated[str, typer.Option(help="cpu, cuda or auto.")] = "auto",
    progress: Annotated[
        bool, typer.Option(help="Show a progress bar (default: when on a terminal).")
    ] = sys.stdout.isatty(),
) -> None:
    """Train SAC, PPO, TD3, DDPG or A2C on generated ground motions; checkpoints resume."""
    from rlcontroller.training import train as run_training

    if device not in ("cpu", "cuda", "auto"):
        raise ConfigError(f"--device: expected cpu, cuda or auto, got {device!r}")
    if resume is not None:
        if config is not None or total_steps is not None or seed is not None:
            raise ConfigError("--resume: continues the run's own config; drop CONFIG, --total-steps and --seed")
        summary = run_training(resume=resume, device=device, progress_bar=progress)
    else:
        experiment = load(config)
        if total_steps is not None:
            experiment = experiment.model_copy(
                update={"algorithm": experiment.algorithm.model_copy(update={"total_steps": total_steps})}
            )
        if seed is not None:
            experiment = experiment.model_copy(update={"seed": seed})
        summary = run_training(experiment, run_dir=run_dir, device=device, progress_bar=progress)
    typer.echo(summary.line())
    if summary.interrupted:
        typer.echo(f"resume with: rlc train --resume {summary.run_dir}")
        raise typer.Exit(130)


def main() -> None:
    app(prog_name="rlc")


if __name__ == "__main__":
    main()
    sys.exit(0)
