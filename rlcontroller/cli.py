"""Command line: parses arguments and calls the library; no physics or RL logic lives here."""

from __future__ import annotations

import datetime as dt
import importlib.metadata
import math
import os
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from enum import Enum
from functools import wraps
from pathlib import Path
from typing import Annotated, Any

import typer

try:  # typer 0.2x carries its own click (typer._click) and no longer installs click
    from typer import TyperException as CommandLineError
except ImportError:
    from click import ClickException as CommandLineError

from rlcontroller.assets import (
    DAMPER_SCENARIOS,
    DEFAULT_MODEL,
    DEMO_CONFIG,
    DEVICE_SCENARIOS,
    MODELS,
    SAFETY_STANDARD,
    STANDARD_SCENARIOS,
)
from rlcontroller.config import (
    MAX_SEED,
    MAX_TOTAL_STEPS,
    ConfigError,
    Experiment,
    load_experiment,
    names_wind_suite,
    with_overrides,
)
from rlcontroller.files import check_new_folder, new_folder
from rlcontroller.physics.excitation import MotionError

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    rich_markup_mode=None,
    help="Reinforcement-learning active control of buildings under earthquakes. New here? Start with 'rlc demo'.",
)

USER_ERRORS = (ConfigError, MotionError)  # a design that cannot be made on a model is a ConfigError too
INTERNAL_ERROR = 3  # exit code of a failure that is not the user's (user mistakes: 2, file system: 1)
DEBUG_VARIABLE = "RLC_DEBUG"  # set to 1: tracebacks on screen, as with --debug
debugging = False  # set for each invocation by the --debug option or the variable


def _version(value: bool) -> None:
    if value:
        typer.echo(f"rlc {importlib.metadata.version('rlcontroller')}")
        raise typer.Exit()


@app.callback()
def _commands(
    version: Annotated[
        bool, typer.Option("--version", callback=_version, is_eager=True, help="Print the version and exit.")
    ] = False,
    debug: Annotated[
        bool, typer.Option("--debug", help=f"Show an internal error's traceback on screen (or set {DEBUG_VARIABLE}=1).")
    ] = False,
) -> None:
    """Reinforcement-learning active control of buildings under earthquakes."""
    global debugging
    debugging = debug or os.environ.get(DEBUG_VARIABLE, "") not in ("", "0")


def user_errors(command: Callable[..., Any]) -> Callable[..., Any]:
    """Print a user mistake as one line on stderr and exit with code 2 (1 for a file system
    error such as a full disk or a folder without write permission), without a traceback."""

    @wraps(command)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return command(*args, **kwargs)
        except USER_ERRORS as error:
            typer.echo(f"error: {error}", err=True)
            raise typer.Exit(2) from None
        except BrokenPipeError:  # `rlc info | head -3`: the reader has what it wanted
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            raise typer.Exit(0) from None
        except OSError as error:
            where = f"{error.filename}: " if error.filename else ""
            typer.echo(f"error: {where}{error.strerror or error}", err=True)
            raise typer.Exit(1) from None
        except (typer.Exit, typer.Abort, CommandLineError):
            raise
        except Exception as error:
            if debugging:
                raise
            typer.echo(f"internal error: {internal_error(error)}", err=True)
            raise typer.Exit(INTERNAL_ERROR) from None

    return wrapper


def internal_error(error: Exception) -> str:
    """What went wrong in one line, the traceback kept in a new file (named in the line)."""
    import tempfile
    import traceback

    handle, path = tempfile.mkstemp(prefix="rlc-traceback-", suffix=".txt")
    with os.fdopen(handle, "w", encoding="utf-8") as file:
        file.write(f"rlc {' '.join(sys.argv[1:])}\n")
        file.write("".join(traceback.format_exception(error)))
    what = (str(error).splitlines() or [""])[0][:200]
    return (
        f"{type(error).__name__}{': ' + what if what else ''} (full traceback in {path}; "
        f"--debug shows it here; please report it)"
    )


def _positive_finite(high: float) -> Callable[[float | None], float | None]:
    def check(value: float | None) -> float | None:
        if value is not None and not (math.isfinite(value) and 0.0 < value <= high):
            raise typer.BadParameter(f"expected a finite number in (0, {high:g}], got {value!r}")
        return value

    return check


def stamp() -> str:
    return dt.datetime.now().strftime("%Y%m%d-%H%M%S")


RecordsOption = Annotated[
    Path | None,
    typer.Option(
        help="A folder of .AT2/.csv records (with an optional manifest.csv), one record file, or a wind "
        "suite (.yaml, kind: wind; configs/loads/) (default $RLC_RECORDS, else a synthetic suite)."
    ),
]
ScaleOption = Annotated[
    float | None, typer.Option(callback=_positive_finite(10.0), help="Scale every record to this PGA (g).")
]
ModelOption = Annotated[str, typer.Option(help="Which saved model of the run: best or final.")]
OutOption = Annotated[
    Path | None, typer.Option(help="Output folder, new or empty (default: a new folder under results/).")
]
ProgressOption = Annotated[
    bool | None,
    typer.Option(
        "--progress/--no-progress", show_default="on a terminal", help="Show a progress bar with steps/s and ETA."
    ),
]


def load(config: Path | None) -> Experiment:
    """The experiment of `config`, or of the default model."""
    return load_experiment(DEFAULT_MODEL / "config.yaml" if config is None else config)


@app.command(short_help="An experiment resolved: building, periods, actuators.")
@user_errors
def info(
    config: Annotated[Path | None, typer.Argument(help="Experiment YAML; the default model's if omitted.")] = None,
) -> None:
    """Print the resolved config, natural periods, modal damping ratios (of the design model, and of
    the simulated plant when there is a plant part), actuator layout and devices."""
    from rlcontroller.physics.plant import Plant

    experiment = load(config)
    plant = Plant(experiment)
    typer.echo("# resolved configuration")
    typer.echo(resolved_text(experiment))
    floors_only = " (floors only, without the devices)" if experiment.devices else ""
    buildings = [(f"design model{floors_only}", plant.design.bare.building)]
    if experiment.plant is not None:
        buildings.append((f"simulated plant (the plant part, elastic){floors_only}", plant.elastic.bare.building))
    for title, building in buildings:
        typer.echo(f"# modes of the {title}")
        typer.echo(f"{'mode':>4}  {'period (s)':>10}  {'frequency (Hz)':>14}  {'damping ratio':>13}")
        ratios = building.modal_damping_ratios()
        for mode, (period, ratio) in enumerate(zip(building.periods(), ratios, strict=True), 1):
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
    if experiment.devices:
        typer.echo("\n# devices (mass devices tuned on the design model)")
        for index, line in enumerate(device_lines(experiment, plant.design.building), 1):
            typer.echo(f"{index}: {line}")


def resolved_text(experiment: Experiment) -> str:
    """The resolved experiment as YAML, a building's matrices shown by their size and source."""
    import yaml

    raw = experiment.model_dump(mode="json")
    building = raw["building"]
    for key in ("mass_matrix", "stiffness_matrix", "damping_matrix"):
        if building.get(key) is not None:
            size = len(building[key])
            building[key] = f"({size} x {size}, SI, from {building.get('source') or 'the config'})"
    return yaml.safe_dump(raw, sort_keys=False)


def device_lines(experiment: Experiment, building) -> list[str]:
    """One line per device of `experiment` as built in `building` (the design model), in config order."""
    import numpy as np

    total = float(np.sum(building.floor_masses))
    labels = experiment.command_labels()
    masses = iter(building.devices)
    lines = []
    for config in experiment.devices:
        if config.type == "mr_damper":
            command = labels.index(f"MR {config.story}") + 1
            lines.append(
                f"mr_damper on story {config.story}, capacity {config.capacity / 1e3:g} kN, "
                f"0-{config.max_voltage:g} V, eta {config.eta:g} 1/s (command {command})"
            )
            continue
        if config.type == "variable_damper":
            command = labels.index(f"VD {config.story}") + 1
            lines.append(
                f"variable_damper on story {config.story}, c {config.damping_min:g}-{config.damping_max:g} N*s/m, "
                f"capacity {config.capacity / 1e3:g} kN (command {command})"
            )
            continue
        device = next(masses)
        frequency = np.sqrt(device.stiffness / device.mass) / (2 * np.pi)
        text = (
            f"{device.kind} on floor {device.floor}, {device.mass / 1e3:.4g} t ({device.mass_ratio:g} of mode "
            f"{config.mode}'s modal mass, {device.mass / total:.3%} of the building's), {frequency:.4g} Hz "
            f"(ratio {device.frequency_ratio:.4f}), damping ratio {device.damping_ratio:.4f}"
        )
        if device.stroke_limit is not None:
            text += f", stroke limit {device.stroke_limit:g} m"
        if device.active:
            text += f", force limit {device.force_limit / 1e3:g} kN (command {labels.index(f'AMD {device.floor}') + 1})"
        lines.append(text)
    return lines


@app.command(short_help="Train a controller on generated motions.")
@user_errors
def train(
    config: Annotated[
        Path | None, typer.Argument(help="Experiment YAML (see configs/README.md; not with --resume).")
    ] = None,
    total_steps: Annotated[
        int | None, typer.Option(min=1, max=MAX_TOTAL_STEPS, help="Override algorithm.total_steps.")
    ] = None,
    seed: Annotated[int | None, typer.Option(min=0, max=MAX_SEED, help="Override the experiment's seed.")] = None,
    run_dir: Annotated[Path | None, typer.Option(help="Run folder to create (default runs/NAME-seedS-TIME).")] = None,
    resume: Annotated[Path | None, typer.Option(help="Continue this run folder from its newest checkpoint.")] = None,
    device: Annotated[str, typer.Option(help="cpu, cuda or auto.")] = "auto",
    time_limit: Annotated[
        float | None,
        typer.Option(
            callback=_positive_finite(1.0e6), help="Stop after this many minutes of this invocation (resumable)."
        ),
    ] = None,
    progress: ProgressOption = None,
    tensorboard: Annotated[
        bool,
        typer.Option(
            "--tensorboard",
            help="Also log to RUN/tensorboard (stable-baselines3's logger and the validation J1/J2 with the LQG "
            "references); follow with 'tensorboard --logdir runs'. Needs rlcontroller[tensorboard].",
        ),
    ] = False,
) -> None:
    """Train a controller (SAC, PPO, TD3, DDPG, A2C or random search) on generated ground motions;
    checkpoints resume."""
    from rlcontroller.learning.training import train as run_training

    if device not in ("cpu", "cuda", "auto"):
        raise ConfigError(f"--device: expected cpu, cuda or auto, got {device!r}")
    if device == "cuda":
        import torch

        if not torch.cuda.is_available():
            raise ConfigError("--device cuda: no CUDA GPU is visible to torch here; use --device cpu (or auto)")
    limit = None if time_limit is None else 60.0 * time_limit
    progress = show_progress(progress)
    if resume is not None:
        if config is not None or total_steps is not None or seed is not None:
            raise ConfigError("--resume: continues the run's own config; drop CONFIG, --total-steps and --seed")
        typer.echo(resume_line(resume))
        summary = run_training(
            resume=resume, device=device, progress_bar=progress, time_limit_s=limit, tensorboard=tensorboard
        )
    else:
        if config is None:
            raise ConfigError(
                "rlc train: expected an experiment YAML (e.g. configs/experiments/demo.yaml; configs/README.md "
                "lists them) or --resume RUN"
            )
        experiment = load_experiment(config)
        overrides = {"algorithm.total_steps": total_steps, "seed": seed}
        given = {key: value for key, value in overrides.items() if value is not None}
        if given:
            experiment = with_overrides(experiment, given, "--total-steps/--seed")
        summary = run_training(
            experiment,
            run_dir=run_dir,
            device=device,
            progress_bar=progress,
            time_limit_s=limit,
            tensorboard=tensorboard,
        )
    typer.echo(summary.line())
    if summary.interrupted or summary.time_limit_reached:
        typer.echo(f"resume with: rlc train --resume {summary.run_dir}")
    if summary.interrupted:
        raise typer.Exit(130)
    if not summary.time_limit_reached:
        run_check(summary.run_dir, "best", progress=progress)


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


def model_folder(run_dir: Path | None) -> Path:
    """The run folder given, or the committed default model."""
    folder = run_dir or DEFAULT_MODEL
    if folder.is_file() and folder.suffix in (".yaml", ".yml"):
        raise ConfigError(
            f"{folder}: an experiment YAML, expected a run or model folder: train it first "
            f"('rlc train {folder}'), or compare LQG on it with 'rlc compare lqg --config {folder}'"
        )
    if not (folder / "config.yaml").is_file():
        hint = "" if run_dir else " (no RUN_DIR given and no committed default model)"
        raise ConfigError(f"{folder}: not a run folder: no config.yaml{hint}; train one with 'rlc train CONFIG'")
    from rlcontroller.files import active_holder

    holder = active_holder(folder)
    if holder is not None:
        typer.echo(f"note: {folder} is still in use by {holder}; reading its newest complete files", err=True)
    return folder


def run_check(
    folder: Path,
    model: str,
    standard: Path = SAFETY_STANDARD,
    scenarios: Path | None = None,
    progress: bool = False,
):
    """The safety check of a folder's saved policy: prints the verdict and writes MODEL_check.yaml
    there, or for a shipped model (whose files stay as shipped) in a new folder under results/."""
    from rlcontroller.config import display_path, load_safety_check, load_scenarios
    from rlcontroller.control.policy import read_policy
    from rlcontroller.evaluation.safety import judged_digests, safety_check, write_verdict
    from rlcontroller.physics.plant import Plant

    experiment = load_experiment(folder / "config.yaml", self_contained=True)
    plant = Plant(experiment)
    policy = read_policy(folder, model, plant)
    checking = load_safety_check(standard)
    typer.echo(
        f"checking {display_path(folder)}'s {model} policy: {checking.motions} generated motions, "
        f"{checking.rest_runs} runs at rest, closed-loop stability..."
    )
    named = load_scenarios(scenarios or standard_scenarios(experiment), experiment)
    with progress_bar(progress, "safety check", 3) as advance:
        try:
            verdict = safety_check(plant, policy, checking, named, on_criterion=lambda name: advance(1, f"{name} done"))
        except ConfigError as error:  # the standard asks for what this building has not
            raise ConfigError(f"{display_path(standard)}: {error}") from None
    verdict.judged = judged_digests(folder, model, checking)
    target = folder
    if folder.resolve().is_relative_to(MODELS.resolve()):
        target = output_folder(None, f"check-{folder.name}")
        target.mkdir(parents=True)
    other = "" if standard.resolve() == SAFETY_STANDARD.resolve() else standard.stem  # keeps the standard's verdict
    path = write_verdict(verdict, target, model, other)
    for line in verdict.lines():
        typer.echo(line)
    typer.echo(f"verdict in {path}")
    return verdict


def standard_scenarios(experiment: Experiment) -> Path:
    """The standard robustness scenarios, or with devices their own (no yielding stories; devices as built
    differing from their design; no actuator dynamics with semi-active dampers)."""
    if experiment.has_dampers:
        return DAMPER_SCENARIOS
    return DEVICE_SCENARIOS if experiment.devices else STANDARD_SCENARIOS


SCENARIOS_DEFAULT = "configs/scenarios/standard.yaml; devices.yaml with mass devices, dampers.yaml with dampers"


def verdict_state(folder: Path, model: str):
    """The verdict on a folder's policy under the project's standard, if it judged these files."""
    from rlcontroller.config import load_safety_check
    from rlcontroller.evaluation.safety import read_verdict

    return read_verdict(folder, model, load_safety_check(SAFETY_STANDARD))


def warn_unchecked(folder: Path, model: str) -> None:
    """One line on stderr when the policy failed the safety check or was never checked (as it is now)."""
    from rlcontroller.evaluation.safety import verdict_path

    state = verdict_state(folder, model)
    if state.passed is None:
        typer.echo(
            f"note: {folder}'s {model} policy counts as never safety-checked ({state.reason}); "
            f"run 'rlc check {folder}'",
            err=True,
        )
    elif not state.passed:
        typer.echo(
            f"warning: {folder}'s {model} policy FAILED the safety check (it can be worse than no control): "
            f"{verdict_path(folder, model)}",
            err=True,
        )


def show_progress(progress: bool | None) -> bool:
    """The progress bar is on by default when the output is a terminal."""
    return sys.stdout.isatty() if progress is None else progress


@contextmanager
def progress_bar(enabled: bool, description: str, total: int) -> Iterator[Callable[..., None]]:
    """A bar on stderr while a long step runs (what it does, done/total, elapsed, time left), gone
    when it ends; nothing when not `enabled`. Yields `advance(amount=1, label="")`."""
    if not enabled:
        yield lambda amount=1, label="": None
        return
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn())
    with Progress(
        *columns, TextColumn("left"), TimeRemainingColumn(), console=Console(stderr=True), transient=True
    ) as bar:
        task = bar.add_task(description, total=total)

        def advance(amount: int = 1, label: str = "") -> None:
            bar.update(task, advance=amount, description=f"{description}: {label}" if label else description)

        yield advance


def output_folder(out: Path | None, default_name: str) -> Path:
    """`out`, or a new folder results/NAME-TIME (never an existing one, never a tracked folder)."""
    if out is not None:
        return out
    base = Path("results") / f"{default_name}-{stamp()}"
    path, number = base, 1
    while path.exists():
        number += 1
        path = base.with_name(f"{base.name}-{number}")
    return path


def motion_suite(records: Path | None, scale_pga: float | None, plant=None):
    """The motions to evaluate on and their label; says so when it falls back to the synthetic suite.
    `records` may be a wind suite (a YAML file with kind: wind), generated on `plant`'s floors."""
    from rlcontroller.physics.records import RECORDS_VARIABLE, choose_motions

    if names_wind_suite(records):
        from rlcontroller.config import load_wind_suite
        from rlcontroller.physics.wind import suite_label, wind_suite

        suite = load_wind_suite(records)
        if plant is None:
            raise ConfigError(f"--records {records}: a wind suite is not taken by this command")
        if scale_pga is not None:
            raise ConfigError("--scale-pga: a wind suite has no ground acceleration to scale")
        check_loads_modelled(plant, records)
        return wind_suite(suite, plant.building), suite_label(suite, str(records))
    if records is None and not os.environ.get(RECORDS_VARIABLE):
        typer.echo(
            "no --records given: using the embedded synthetic suite (labelled SYNTHETIC in every output)", err=True
        )
    motions, label = choose_motions(records, scale_pga)
    if plant is not None and any(motion.floor_forces is not None for motion in motions):
        check_loads_modelled(plant, records)
    return motions, label


def check_loads_modelled(plant, records: Path | None) -> None:
    """Floor loads (wind, force records) need a linear plant: refused in one line otherwise."""
    if plant.nonlinear is not None:
        raise ConfigError(
            f"--records {records}: floor loads (wind) on a building with yielding stories or semi-active dampers "
            "are not modelled; use ground-motion records"
        )


def motions_text(count: int) -> str:
    return f"{count} motion{'s' if count != 1 else ''}"


def comparison(
    experiment: Experiment,
    run_dir: Path | None,
    model: str,
    records: Path | None,
    scale_pga: float | None,
    progress: bool = False,
):
    """The plant, the motions and the evaluation of every controller (the run's policy if given)."""
    from rlcontroller.control.policy import read_policy
    from rlcontroller.evaluation.evaluation import compare
    from rlcontroller.physics.plant import Plant

    plant = Plant(experiment)
    policy = read_policy(run_dir, model, plant) if run_dir is not None else None
    motions, label = motion_suite(records, scale_pga, plant)
    with progress_bar(progress, f"evaluating {motions_text(len(motions))}", len(motions)) as advance:
        return plant, motions, compare(plant, motions, label, policy, on_motions=advance)


def print_summary(evaluation, out: Path) -> None:
    from rlcontroller.evaluation.tables import LEGEND, improvement_table, j1_by_pga, markdown_table, summary_table

    typer.echo(f"# {evaluation.label}")
    for name, source in evaluation.sources.items():
        typer.echo(f"{name}: {source}")
    typer.echo(markdown_table(summary_table(evaluation)))
    typer.echo(LEGEND)
    improvement = improvement_table(evaluation)
    if improvement is not None:
        typer.echo(markdown_table(improvement, digits=1))
    typer.echo(markdown_table(j1_by_pga(evaluation)))
    count = len(evaluation.records)
    typer.echo(f"evaluated {motions_text(count)} in {evaluation.seconds:.1f} s; tables and plots in {out}")


@app.command(short_help="A controller against LQG and no control on records.")
@user_errors
def evaluate(
    run_dir: Annotated[
        Path | None, typer.Argument(help="Run folder (default: the default model, see rlc models).")
    ] = None,
    records: RecordsOption = None,
    out: OutOption = None,
    scale_pga: ScaleOption = None,
    model: ModelOption = "best",
    progress: ProgressOption = None,
) -> None:
    """Uncontrolled vs LQG vs the trained policy on the records: J1-J4 tables and the paper's plots."""
    from rlcontroller.evaluation.report import write_report

    folder = model_folder(run_dir)
    out = output_folder(out, f"evaluate-{folder.resolve().name}")
    check_new_folder(out)
    experiment = load_experiment(folder / "config.yaml", self_contained=True)
    warn_unchecked(folder, model)
    with drawing() as plots:  # matplotlib's import and the plots on the other core
        _, _, evaluation = comparison(experiment, folder, model, records, scale_pga, show_progress(progress))
        with new_folder(out) as staging:
            write_report(evaluation, staging, plots)
    print_summary(evaluation, out)


@contextmanager
def drawing() -> Iterator:
    """A drawing process for `write_report` where there is a second core to run it on (and fork), else None."""
    if (os.cpu_count() or 1) < 2 or not hasattr(os, "fork"):
        yield None
        return
    from rlcontroller.evaluation.report import Drawing

    with Drawing() as plots:
        yield plots


@app.command(short_help="Start here: train, evaluate and check a small controller.")
@user_errors
def demo(records: RecordsOption = None, progress: ProgressOption = None) -> None:
    """The main job end to end: learn a controller from nothing, with no model of the building
    (configs/experiments/demo.yaml, about 30 s), evaluate it against LQG and the uncontrolled building, and
    run the safety check on it."""
    from rlcontroller.evaluation.report import write_report
    from rlcontroller.learning.training import train as run_training
    from rlcontroller.physics.records import choose_motions

    choose_motions(records)  # a bad --records stops here, before training
    progress = show_progress(progress)
    summary = run_training(load_experiment(DEMO_CONFIG), progress_bar=progress)
    typer.echo(summary.line())
    typer.echo(learned_line(summary.run_dir))
    _, _, evaluation = comparison(
        load_experiment(summary.run_dir / "config.yaml", self_contained=True), summary.run_dir, "best", records, None
    )
    out = summary.run_dir / "evaluation"
    with new_folder(out) as staging:
        write_report(evaluation, staging)
    print_summary(evaluation, out)
    if not run_check(summary.run_dir, "best", progress=progress).passed:
        typer.echo("this run's controller failed the safety check: docs/safety_check.md says what that means")


def learned_line(run: Path) -> str:
    """What training changed, from the run's learning curve: validation J1 at the start and at the best
    model, beside the LQGs' on the same validation motions."""
    import csv

    with (run / "learning_curve.csv").open(newline="") as file:
        rows = list(csv.DictReader(file))
    start, best = rows[0], min(rows, key=lambda row: float(row["eval_J1"]))
    return (
        f"learned: validation J1 {float(start['eval_J1']):.3f} at step 0 -> {float(best['eval_J1']):.3f} at step "
        f"{int(best['steps']):,} ({float(best['wall_time_s']):.0f} s); LQG with the same cost and sensors, designed "
        f"on the building's matrices: {float(best['lqg_J1']):.3f} (LQG + ground model "
        f"{float(best['lqg_ground_model_J1']):.3f}), on the same generated validation motions"
    )


compare_app = typer.Typer(
    no_args_is_help=True,
    short_help="The classical answers: LQG, passive devices.",
    help="The classical answers: LQG with the same cost (rlc compare lqg), passive devices (rlc compare passive).",
)
app.add_typer(compare_app, name="compare")


@compare_app.command("lqg", short_help="LQG with the same cost: its J tables and trade-off curve.")
@user_errors
def compare_lqg(
    run_dir: Annotated[
        Path | None, typer.Argument(help="Run or model folder whose policy joins (default: the default model).")
    ] = None,
    config: Annotated[Path | None, typer.Option(help="Experiment YAML instead of a run: LQG only.")] = None,
    records: RecordsOption = None,
    out: OutOption = None,
    scale_pga: ScaleOption = None,
    sweep: Annotated[
        bool,
        typer.Option(
            help="Trace LQG's J1-J3 trade-off over force weights (dampers: passive levels and clipped-optimal weights)."
        ),
    ] = False,
    preview: Annotated[
        bool, typer.Option(help="Full-state LQR knowing the ground 0-1 s ahead: what prediction could buy.")
    ] = False,
    model: ModelOption = "best",
    progress: ProgressOption = None,
) -> None:
    """LQG (same cost) against the uncontrolled building, and against the RL policy of a run."""
    import numpy as np

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
    from rlcontroller.evaluation.report import write_damper_sweep, write_preview, write_report, write_sweep

    if config is not None and run_dir is not None:
        raise ConfigError("--config: either a run folder or --config, not both")
    if config is None:
        run_dir = model_folder(run_dir)
        experiment = load_experiment(run_dir / "config.yaml", self_contained=True)
    else:
        experiment = load_experiment(config)
    if not experiment.command_labels():
        raise ConfigError(f"{config}: nothing to command (no actuators, no active devices): try rlc compare passive")
    if experiment.has_dampers and preview:
        raise ConfigError("--preview: the preview bound needs a plant without semi-active dampers")
    out = output_folder(out, f"compare_lqg-{run_dir.resolve().name if run_dir else experiment.name}")
    check_new_folder(out)
    progress = show_progress(progress)
    plant, motions, evaluation = comparison(experiment, run_dir, model, records, scale_pga, progress)
    label = evaluation.label
    with new_folder(out) as staging:
        write_report(evaluation, staging)
        if sweep and experiment.has_dampers:
            levels, multipliers = DAMPER_LEVELS, np.logspace(-2, 2, 9)
            with progress_bar(progress, "dampers' trade-off", len(motions)) as advance:
                table = damper_sweep(plant, motions, label, levels, multipliers, advance)
            names = [name for name in evaluation.controllers if name not in ("uncontrolled",)]
            points = {n: tuple(mean_metric(evaluation, n, m) for m in ("J1", "J2", "J3")) for n in names}
            write_damper_sweep(table, staging, label, points)
        elif sweep:
            multipliers = np.logspace(-2, 2, 9)
            with progress_bar(progress, "LQG trade-off", multipliers.size) as advance:
                table = lqg_sweep(plant, motions, label, multipliers, on_point=lambda: advance())
            names = [name for name in ("RL", *LQG_VARIANTS[1:], OPTIMAL) if name in evaluation.controllers]
            points = {n: (mean_metric(evaluation, n, "J3"), mean_metric(evaluation, n, "J1")) for n in names}
            write_sweep(table, staging, label, points)
        if preview:
            names = [name for name in evaluation.controllers if name not in ("uncontrolled", OPTIMAL)]
            references = {n: (mean_metric(evaluation, n, "J1"), mean_metric(evaluation, n, "J2")) for n in names}
            with progress_bar(progress, "preview horizons", len(PREVIEW_SECONDS)) as advance:
                study = preview_study(plant, motions, on_horizon=lambda: advance())
            write_preview(study, staging, label, references)
    print_summary(evaluation, out)
    sweep_file = "damper_sweep.md" if experiment.has_dampers else "lqg_sweep.md"
    for name, wanted in ((sweep_file, sweep), ("preview.md", preview)):
        if wanted:
            typer.echo((out / name).read_text())


@compare_app.command("passive", short_help="The building with its mass devices passive, and without them.")
@user_errors
def compare_passive(
    config: Annotated[Path, typer.Argument(help="Experiment YAML with a devices part.")],
    records: RecordsOption = None,
    out: OutOption = None,
    scale_pga: ScaleOption = None,
    progress: ProgressOption = None,
) -> None:
    """The building without its devices (uncontrolled) and with them passive: tuned masses as tuned,
    active mass drivers as the tuned masses they are without a command; strokes and damper energy."""
    from rlcontroller.evaluation.evaluation import evaluate
    from rlcontroller.evaluation.report import write_report
    from rlcontroller.physics.plant import Plant

    experiment = load_experiment(config)
    if not experiment.devices:
        raise ConfigError(f"{config}: devices: none, so nothing passive to compare")
    out = output_folder(out, f"compare_passive-{experiment.name}")
    check_new_folder(out)
    plant = Plant(experiment)
    motions, label = motion_suite(records, scale_pga, plant)
    with progress_bar(show_progress(progress), f"evaluating {motions_text(len(motions))}", len(motions)) as advance:
        evaluation = evaluate(plant, motions, [], label, include_optimal=False, on_motions=advance)
    with new_folder(out) as staging:
        write_report(evaluation, staging)
    print_summary(evaluation, out)


@app.command(short_help="Every controller on plants that differ from the design.")
@user_errors
def robustness(
    run_dir: Annotated[
        Path | None, typer.Argument(help="Run folder (default: the default model, see rlc models).")
    ] = None,
    records: RecordsOption = None,
    scenarios: Annotated[
        Path | None,
        typer.Option(
            help="Scenario YAML: named plants that differ from the design model.", show_default=SCENARIOS_DEFAULT
        ),
    ] = None,
    out: OutOption = None,
    scale_pga: ScaleOption = None,
    model: ModelOption = "best",
    progress: ProgressOption = None,
) -> None:
    """Every controller on every scenario's plant and every record: how each copes with model error."""
    from rlcontroller.config import load_scenarios
    from rlcontroller.control.policy import read_policy
    from rlcontroller.evaluation.report import write_robustness
    from rlcontroller.evaluation.robustness import robustness as run_robustness
    from rlcontroller.evaluation.robustness import summary
    from rlcontroller.evaluation.tables import markdown_table
    from rlcontroller.physics.plant import Plant

    folder = model_folder(run_dir)
    experiment = load_experiment(folder / "config.yaml", self_contained=True)
    named = load_scenarios(scenarios or standard_scenarios(experiment), experiment)
    plant = Plant(experiment)
    policy = read_policy(folder, model, plant)
    out = output_folder(out, f"robustness-{folder.resolve().name}")
    check_new_folder(out)
    motions, label = motion_suite(records, scale_pga, plant)
    if any(motion.floor_forces is not None for motion in motions):
        linear = [scenario for scenario in named if scenario.plant is None or scenario.plant.hysteresis is None]
        if len(linear) < len(named):
            skipped = ", ".join(s.name for s in named if s not in linear)
            typer.echo(
                f"note: skipped under floor loads (yielding stories are not modelled with them): {skipped}", err=True
            )
        named = linear
    with progress_bar(show_progress(progress), f"{len(named)} scenarios", len(named)) as advance:
        table, seconds = run_robustness(experiment, named, motions, label, policy, lambda name: advance(1, name))
    with new_folder(out) as staging:
        write_robustness(table, named, staging, label, seconds)
    typer.echo(f"# {label}")
    typer.echo(markdown_table(summary(table)["J1"].unstack("controller").rename_axis("scenario (mean J1)")))
    typer.echo(f"{len(named)} scenarios evaluated in {seconds:.0f} s; tables and plot in {out}")


class Engine(str, Enum):
    local = "local"
    dask = "dask"


@app.command(short_help="Search hyperparameters with Optuna.")
@user_errors
def tune(
    config: Annotated[Path, typer.Argument(help="Experiment YAML whose algorithm part has a 'search' space.")],
    trials: Annotated[int, typer.Option(min=1, max=100_000, help="Trials of the study in all, over every worker.")],
    storage: Annotated[
        str | None,
        typer.Option(help="Optuna storage URL shared by workers on many machines (default: OUT/study.journal)."),
    ] = None,
    study: Annotated[str | None, typer.Option(help="Study name (default: the experiment's name).")] = None,
    jobs: Annotated[int, typer.Option(min=1, max=256, help="Worker processes on this machine.")] = 1,
    out: Annotated[
        Path | None, typer.Option(help="Folder of the study's files and trial runs (default: results/tune-NAME).")
    ] = None,
) -> None:
    """Search hyperparameters with Optuna (TPE, median pruning on the validation J1); run the same
    command on more machines with one --storage to share the study."""
    from rlcontroller.studies.tuning import tune as run_tuning

    experiment = load(config)
    name = study or experiment.name
    folder = out or Path("results") / f"tune-{name}"
    ran = run_tuning(experiment, trials, storage, name, folder, jobs)
    typer.echo(f"{ran} trials run here; study {name!r}: trials.csv, best.yaml and plots in {folder}")


@app.command(short_help="Train and evaluate seeds x settings, then aggregate.")
@user_errors
def sweep(
    config: Annotated[Path, typer.Argument(help="Experiment YAML.")],
    seeds: Annotated[str, typer.Option(help="Seeds: a range 0-9 or a list 0,3,5.")] = "0-2",
    set_: Annotated[
        list[str] | None,
        typer.Option(
            "--set", help="KEY=V1,V2: a setting and its values (repeatable), e.g. algorithm.kwargs.gamma=0.99,0.999."
        ),
    ] = None,
    engine: Annotated[Engine, typer.Option(help="local: processes here; dask: a Dask cluster.")] = Engine.local,
    address: Annotated[
        str | None, typer.Option(help="An existing Dask scheduler (tcp://HOST:8786); default: a local cluster.")
    ] = None,
    workers: Annotated[int, typer.Option(min=1, max=1024, help="Runs at once on a local engine or cluster.")] = 2,
    records: RecordsOption = None,
    out: Annotated[Path | None, typer.Option(help="Folder of the runs (default: results/sweep-NAME).")] = None,
) -> None:
    """Train and evaluate every combination of seeds and settings, then aggregate over seeds. Running
    the same command again redoes only what is missing."""
    from rlcontroller.studies.sweep import parse_seeds, parse_setting, plan
    from rlcontroller.studies.sweep import sweep as run_sweep

    experiment = load(config)
    if address is not None and engine != Engine.dask:
        raise ConfigError("--address: only with --engine dask")
    chosen_seeds, settings = parse_seeds(seeds), [parse_setting(text) for text in set_ or []]
    folder = out or Path("results") / f"sweep-{experiment.name}"
    plan(experiment, chosen_seeds, settings, folder)  # every combination checked before any work
    if names_wind_suite(records):  # so is --records
        from rlcontroller.physics.plant import Plant

        motion_suite(records, None, Plant(experiment))
    else:
        motion_suite(records, None)
    try:
        results, written = run_sweep(
            experiment,
            chosen_seeds,
            settings,
            folder,
            engine.value,
            workers,
            address,
            str(records.resolve()) if records else None,
            echo=typer.echo,
        )
    except KeyboardInterrupt:
        typer.echo("sweep stopped: the runs in progress saved a checkpoint; run the same command again to continue")
        raise typer.Exit(130) from None
    failed = [result for result in results if result.status == "failed"]
    if written:
        typer.echo((folder / "aggregate.md").read_text())
    typer.echo(
        f"{len(results) - len(failed)} runs done, {len(failed)} failed; runs, sweep.csv and aggregate in {folder}"
    )
    if failed:
        raise typer.Exit(1)


@app.command(short_help="Statistics over runs: mean, IQM, bootstrap intervals.")
@user_errors
def aggregate(
    runs: Annotated[list[Path], typer.Argument(help="Run folders (with evaluation/) or evaluation folders.")],
    out: Annotated[
        Path | None, typer.Option(help="New folder for aggregate.csv/.md/.png (default: print only).")
    ] = None,
    progress: ProgressOption = None,
) -> None:
    """Per controller and metric over runs: mean, std, interquartile mean, 95 % stratified-bootstrap intervals."""
    from rlcontroller.studies.aggregate import aggregate as statistics
    from rlcontroller.studies.aggregate import markdown, scores, write_aggregate

    if out is not None:
        check_new_folder(out)
    table = scores(runs)
    groups = table.groupby([c for c in ("group", "controller", "metric") if c in table.columns]).ngroups
    with progress_bar(show_progress(progress), "bootstrap intervals", groups) as advance:
        table = statistics(table, advance=advance)
    title = f"{len(runs)} runs: mean over records and stories, statistics over runs"
    if out is not None:
        with new_folder(out) as staging:
            write_aggregate(table, staging, title)
    typer.echo(markdown(table, title))
    if out is not None:
        typer.echo(f"aggregate.csv, aggregate.md and aggregate.png in {out}")


@app.command(short_help="The shipped controllers and their safety verdicts.")
@user_errors
def models() -> None:
    """The shipped controllers: learner, training steps, safety verdict; the default is marked."""
    import yaml

    typer.echo("models/ (card.md in each says what it is, what it observes and its numbers)")
    for folder in sorted(path for path in MODELS.iterdir() if (path / "best_policy.yaml").is_file()):
        policy = yaml.safe_load((folder / "best_policy.yaml").read_text())
        state = verdict_state(folder, "best")
        verdict = {True: "safety check passed", False: "safety check FAILED"}.get(state.passed)
        mark = " (default)" if folder == DEFAULT_MODEL else ""
        typer.echo(
            f"{folder.name}{mark}: {policy['algorithm']}, {policy['training_steps']:,} steps, "
            f"{verdict or f'never checked ({state.reason})'}"
        )


class ExportFormat(str, Enum):
    onnx = "onnx"


@app.command(short_help="The controller as one ONNX file.")
@user_errors
def export(
    run_dir: Annotated[
        Path | None, typer.Argument(help="Run folder (default: the default model, see rlc models).")
    ] = None,
    format: Annotated[ExportFormat, typer.Option("--format", help="File format.")] = ExportFormat.onnx,
    out: Annotated[
        Path | None,
        typer.Option(help="New output file (default: results/FOLDER_MODEL_controller.onnx); never overwritten."),
    ] = None,
    model: ModelOption = "best",
) -> None:
    """The trained controller as one file: sensor readings (SI) and its own state in, forces (N) out."""
    from rlcontroller.deployment.export import export_onnx

    folder = model_folder(run_dir)
    if out is None:
        Path("results").mkdir(exist_ok=True)
        out = Path("results") / f"{folder.resolve().name}_{model}_controller.{format.value}"
    if out.exists():
        raise ConfigError(f"--out {out}: exists; an export is never overwritten (choose another --out)")
    if not out.parent.is_dir():
        raise ConfigError(f"--out {out}: expected a file path in an existing folder")
    warn_unchecked(folder, model)
    export_onnx(folder, model, out)
    dampers = load_experiment(folder / "config.yaml", self_contained=True).has_dampers
    outputs = "forces (N) and damper commands" if dampers else "forces (N)"
    typer.echo(f"wrote {out}: readings (SI) and state in, {outputs} out; see docs/deployment.md")


@app.command(short_help="The safety check: never worse than no control.")
@user_errors
def check(
    run_dir: Annotated[
        Path | None, typer.Argument(help="Run or model folder (default: the default model, see rlc models).")
    ] = None,
    model: ModelOption = "best",
    standard: Annotated[
        Path,
        typer.Option(help="The check's standard: suite, seed, bounds.", show_default="configs/checks/standard.yaml"),
    ] = SAFETY_STANDARD,
    scenarios: Annotated[
        Path | None, typer.Option(help="Plants for the stability report.", show_default=SCENARIOS_DEFAULT)
    ] = None,
    progress: ProgressOption = None,
    show: Annotated[
        bool, typer.Option("--show", help="Print the folder's verdict and whether it judged these files; no check.")
    ] = False,
) -> None:
    """The safety check a controller passes before it is shipped: never worse than no control on a
    broad suite of generated motions, still at rest, a stable closed loop. Writes MODEL_check.yaml in
    the run folder (for a shipped model: in a new folder under results/); exit code 1 when it fails."""
    folder = model_folder(run_dir)
    if show:
        show_verdict(folder, model)
        return
    if not run_check(folder, model, standard, scenarios, show_progress(progress)).passed:
        raise typer.Exit(1)


def show_verdict(folder: Path, model: str) -> None:
    """`rlc check --show`: the verdict's lines when it judged the folder's files as they are; exit 1 otherwise
    or when it failed."""
    import yaml

    from rlcontroller.evaluation.safety import Verdict, verdict_path

    state = verdict_state(folder, model)
    if state.passed is None:
        typer.echo(f"{folder}'s {model} policy counts as never safety-checked: {state.reason}")
        raise typer.Exit(1)
    path = verdict_path(folder, model)
    for line in Verdict(**yaml.safe_load(path.read_text(encoding="utf-8"))).lines():
        typer.echo(line)
    typer.echo(f"verdict in {path}, judging these files (sha256 of policy, experiment and standard match)")
    if not state.passed:
        raise typer.Exit(1)


@app.command(short_help="Convert an old run's stable-baselines3 zips to policy data.")
@user_errors
def convert(
    run_dir: Annotated[Path, typer.Argument(help="Run folder with best_model.zip / final_model.zip.")],
    trust_pickle: Annotated[
        bool,
        typer.Option(
            "--trust-pickle",
            help="Required. Opening a stable-baselines3 zip or .pkl unpickles it, which runs any code its author "
            "put in it with your permissions: only for folders you made yourself or whose author you trust.",
        ),
    ] = False,
) -> None:
    """Write a run's stable-baselines3 models as policy data (best/final_policy.yaml + .npz), the files
    that evaluate, check and export read without unpickling. Runs trained by this rlc have them already."""
    from rlcontroller.learning.policy import convert as convert_models

    if not trust_pickle:
        raise ConfigError(
            f"{run_dir}: converting opens pickles, which can run their author's code; "
            "add --trust-pickle only if you trust whoever made this folder"
        )
    model_folder(run_dir)
    for path in convert_models(run_dir):
        typer.echo(f"wrote {path} and its .npz")


def main() -> None:
    app(prog_name="rlc")
