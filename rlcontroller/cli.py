"""Command line: parses arguments and calls the library; no physics or RL logic lives here."""

from __future__ import annotations

import os
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
    time_limit: Annotated[float | None, typer.Option(min=0.0, help="Stop after this many minutes (resumable).")] = None,
    progress: Annotated[
        bool, typer.Option(help="Show a progress bar (default: when on a terminal).")
    ] = sys.stdout.isatty(),
) -> None:
    """Train SAC, PPO, TD3, DDPG or A2C on generated ground motions; checkpoints resume."""
    from rlcontroller.training import train as run_training

    if device not in ("cpu", "cuda", "auto"):
        raise ConfigError(f"--device: expected cpu, cuda or auto, got {device!r}")
    limit = None if time_limit is None else 60.0 * time_limit
    if resume is not None:
        if config is not None or total_steps is not None or seed is not None:
            raise ConfigError("--resume: continues the run's own config; drop CONFIG, --total-steps and --seed")
        summary = run_training(resume=resume, device=device, progress_bar=progress, time_limit_s=limit)
    else:
        experiment = load(config)
        if total_steps is not None:
            experiment = experiment.model_copy(
                update={"algorithm": experiment.algorithm.model_copy(update={"total_steps": total_steps})}
            )
        if seed is not None:
            experiment = experiment.model_copy(update={"seed": seed})
        summary = run_training(experiment, run_dir=run_dir, device=device, progress_bar=progress, time_limit_s=limit)
    typer.echo(summary.line())
    if summary.interrupted:
        typer.echo(f"resume with: rlc train --resume {summary.run_dir}")
        raise typer.Exit(130)


DEFAULT_MODEL = Path(__file__).resolve().parents[1] / "models" / "five_story"
SMOKE_CONFIG = Path(__file__).resolve().parents[1] / "configs" / "smoke.yaml"


def model_folder(run_dir: Path | None) -> Path:
    """The run folder given, or the committed default model."""
    folder = run_dir or DEFAULT_MODEL
    if not (folder / "config.yaml").is_file():
        hint = "" if run_dir else " (no RUN_DIR given and no committed default model)"
        raise ConfigError(f"{folder}: not a run folder: no config.yaml{hint}; train one with 'rlc train CONFIG'")
    return folder


def model_file(folder: Path, model: str) -> Path:
    path = folder / f"{model}_model.zip"
    if not path.is_file():
        raise ConfigError(f"{folder}: no {path.name}; expected a run folder written by 'rlc train'")
    return path


def run_comparison(
    experiment: Experiment, run_dir: Path | None, model: str, records: Path | None, scale_pga: float | None
):
    """Uncontrolled, the three LQGs (accelerations only; + measured ground; + ground model), RL (if a run)
    and the optimal reference."""
    from rlcontroller.controllers import PolicyController
    from rlcontroller.env import BuildingEnv
    from rlcontroller.evaluation import LQG_VARIANTS, RECORDS_VARIABLE, choose_motions, evaluate
    from rlcontroller.lqg import LQGController, design_lqg, design_lqg_ground_model

    if records is None and not os.environ.get(RECORDS_VARIABLE):
        typer.echo(
            "no --records given: using the embedded synthetic suite (labelled SYNTHETIC in every output)", err=True
        )
    motions, label = choose_motions(records, scale_pga)
    env = BuildingEnv(experiment)
    designs = [design_lqg(experiment), design_lqg(experiment, known_ground=True), design_lqg_ground_model(experiment)]
    controllers = [LQGController(design, env, name) for design, name in zip(designs, LQG_VARIANTS, strict=True)]
    if run_dir is not None:
        controllers.append(PolicyController.load(model_file(run_dir, model), env.force_limits, name="RL"))
    return evaluate(experiment, motions, controllers, label), motions, label


def print_summary(evaluation, out: Path) -> None:
    from rlcontroller.report import improvement_table, markdown_table, summary_table

    typer.echo(f"# {evaluation.label}")
    typer.echo(markdown_table(summary_table(evaluation)))
    improvement = improvement_table(evaluation)
    if improvement is not None:
        typer.echo(markdown_table(improvement, digits=1))
    typer.echo(f"evaluated {len(evaluation.records)} motions in {evaluation.seconds:.1f} s; tables and plots in {out}")


RecordsOption = Annotated[
    Path | None, typer.Option(help="Folder with the seven .AT2 records (default $RLC_RECORDS, else a synthetic suite).")
]
ScaleOption = Annotated[float | None, typer.Option(min=0.0, help="Scale every record to this PGA (g).")]
ModelOption = Annotated[str, typer.Option(help="Which saved model of the run: best or final.")]


@app.command()
@user_errors
def evaluate(
    run_dir: Annotated[
        Path | None, typer.Argument(help="Run folder (default: the committed models/five_story).")
    ] = None,
    records: RecordsOption = None,
    out: Annotated[Path | None, typer.Option(help="Output folder (default RUN_DIR/evaluation).")] = None,
    scale_pga: ScaleOption = None,
    model: ModelOption = "best",
) -> None:
    """Uncontrolled vs LQG vs the trained policy on the records: J1-J4 tables and the paper's plots."""
    from rlcontroller.report import write_report

    if model not in ("best", "final"):
        raise ConfigError(f"--model: expected best or final, got {model!r}")
    folder = model_folder(run_dir)
    evaluation, _, _ = run_comparison(load_experiment(folder / "config.yaml"), folder, model, records, scale_pga)
    out = out or folder / "evaluation"
    write_report(evaluation, out)
    print_summary(evaluation, out)


@app.command()
@user_errors
def demo(
    records: RecordsOption = None,
    progress: Annotated[
        bool, typer.Option(help="Show a progress bar (default: when on a terminal).")
    ] = sys.stdout.isatty(),
) -> None:
    """The main job end to end: train the small smoke experiment, then evaluate it against LQG."""
    from rlcontroller.report import write_report
    from rlcontroller.training import train as run_training

    summary = run_training(load_experiment(SMOKE_CONFIG), progress_bar=progress)
    typer.echo(summary.line())
    evaluation, _, _ = run_comparison(
        load_experiment(summary.run_dir / "config.yaml"), summary.run_dir, "best", records, None
    )
    out = summary.run_dir / "evaluation"
    write_report(evaluation, out)
    print_summary(evaluation, out)
    typer.echo("the smoke policy is barely trained; 'rlc evaluate' shows the committed benchmark policy")


compare_app = typer.Typer(no_args_is_help=True, help="Compare controllers.")
app.add_typer(compare_app, name="compare")


@compare_app.command("lqg")
@user_errors
def compare_lqg(
    run_dir: Annotated[Path | None, typer.Argument(help="Optional run folder: adds its RL policy.")] = None,
    config: Annotated[
        Path | None, typer.Option(help="Experiment YAML when no run is given (default: embedded).")
    ] = None,
    records: RecordsOption = None,
    out: Annotated[
        Path | None, typer.Option(help="Output folder (default RUN_DIR/compare_lqg or results/compare_lqg).")
    ] = None,
    scale_pga: ScaleOption = None,
    sweep: Annotated[bool, typer.Option(help="Trace LQG's J1-J3 trade-off over force weights.")] = False,
    preview: Annotated[
        bool, typer.Option(help="Full-state LQR knowing the ground 0-1 s ahead: what prediction could buy.")
    ] = False,
    model: ModelOption = "best",
) -> None:
    """LQG (same cost) against the uncontrolled building, and against the RL policy of a run."""
    import numpy as np

    from rlcontroller.evaluation import LQG_VARIANTS, OPTIMAL, lqg_sweep, mean_metric, preview_study
    from rlcontroller.report import write_preview, write_report, write_sweep

    if run_dir is not None:
        run_dir = model_folder(run_dir)
        experiment = load_experiment(run_dir / "config.yaml")
    else:
        experiment = load(config)
    evaluation, motions, label = run_comparison(experiment, run_dir, model, records, scale_pga)
    out = out or (run_dir / "compare_lqg" if run_dir else Path("results") / "compare_lqg")
    write_report(evaluation, out)
    print_summary(evaluation, out)
    if sweep:
        table = lqg_sweep(experiment, motions, label, np.logspace(-2, 2, 9))
        names = [name for name in ("RL", *LQG_VARIANTS[1:], OPTIMAL) if name in evaluation.controllers]
        points = {name: (mean_metric(evaluation, name, "J3"), mean_metric(evaluation, name, "J1")) for name in names}
        write_sweep(table, out, label, points)
        typer.echo((out / "lqg_sweep.md").read_text())
    if preview:
        names = [name for name in evaluation.controllers if name not in ("uncontrolled", OPTIMAL)]
        references = {
            name: (mean_metric(evaluation, name, "J1"), mean_metric(evaluation, name, "J2")) for name in names
        }
        write_preview(preview_study(experiment, motions), out, label, references)
        typer.echo((out / "preview.md").read_text())


def main() -> None:
    app(prog_name="rlc")


if __name__ == "__main__":
    main()
    sys.exit(0)
