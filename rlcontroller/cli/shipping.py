"""Commands about controllers that leave the project: `rlc models`, `design`, `export`, `convert`."""

from __future__ import annotations

from enum import Enum
from pathlib import Path
from typing import Annotated

import typer

from rlcontroller.cli.app import RUN_HELP, ModelOption, Printed, app, user_errors


@app.command(short_help="The shipped controllers and their safety verdicts.")
@user_errors
def models() -> None:
    """The shipped controllers: learner, training steps, safety verdict; the default is marked."""
    from rlcontroller import api

    typer.echo("models/ (card.md in each says what it is, what it observes and its numbers)")
    for line in api.shipped_models():
        typer.echo(line)


@app.command(short_help="A classical controller (LQG, MPC, passive dampers) as data.")
@user_errors
def design(
    config: Annotated[Path, typer.Argument(help="Experiment YAML the controller is designed for.")],
    out: Annotated[Path, typer.Option(help="New controller folder; never overwritten.")],
    law: Annotated[
        str,
        typer.Option(
            help="lqg_ground_model, lqg_ground or lqg_wind_model (the experiment's LQG on its Kalman "
            "estimate, as its sensors give), mpc (MPC over 20 steps on LQG + ground model's estimate; not "
            "exportable), passive-on or passive-off (dampers)."
        ),
    ] = "lqg_ground_model",
) -> None:
    """Design a classical controller for an experiment and save it as data (config.yaml, best_policy.yaml
    and .npz), so that evaluate, check, export and the model list treat it like a trained policy."""
    from rlcontroller import api

    api.design(config, law, out, Printed())


class ExportFormat(str, Enum):
    onnx = "onnx"


@app.command(short_help="The controller as one ONNX file.")
@user_errors
def export(
    run_dir: Annotated[Path | None, typer.Argument(help=RUN_HELP)] = None,
    format: Annotated[ExportFormat, typer.Option("--format", help="File format.")] = ExportFormat.onnx,
    out: Annotated[
        Path | None,
        typer.Option(
            help="New output file (default: results/FOLDER_MODEL_controller.onnx); never overwritten."
        ),
    ] = None,
    model: ModelOption = "best",
) -> None:
    """The trained controller as one file: sensor readings (SI) and its own state in, forces (N) out."""
    from rlcontroller import api

    api.export(run_dir, out, model, Printed())


@app.command(short_help="Convert an old run's stable-baselines3 zips to policy data.")
@user_errors
def convert(
    run_dir: Annotated[Path, typer.Argument(help="Run folder with best_model.zip / final_model.zip.")],
    trust_pickle: Annotated[
        bool,
        typer.Option(
            "--trust-pickle",
            help="Required. Opening a stable-baselines3 zip or .pkl unpickles it, which runs any code its "
            "author put in it with your permissions: only for folders you made yourself or whose author you "
            "trust.",
        ),
    ] = False,
) -> None:
    """Write a run's stable-baselines3 models as policy data (best/final_policy.yaml + .npz), the files
    that evaluate, check and export read without unpickling. Runs trained by this rlc have them already."""
    from rlcontroller import api

    for path in api.convert(run_dir, trust_pickle):
        typer.echo(f"wrote {path} and its .npz")
