"""The `rlc` application: its options shared by many commands, the one-line handling of every error, and
the `Report` that prints a command's lines, notes and progress bars. The command modules import the
library (`rlcontroller.api`) inside each command, so `rlc --help` loads none of it."""

from __future__ import annotations

import math
import os
import sys
import time
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

from rlcontroller.errors import ConfigError, ModelError, MotionError, RecordingError

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    rich_markup_mode=None,
    help="Reinforcement-learning active control of buildings under earthquakes. New here? Start with 'rlc "
    "demo'.",
)

# a design that cannot be made on a model is a ConfigError too
USER_ERRORS = (ConfigError, MotionError, ModelError, RecordingError)
INTERNAL_ERROR = 3  # exit code of a failure that is not the user's (user mistakes: 2, file system: 1)
DEBUG_VARIABLE = "RLC_DEBUG"  # set to 1: tracebacks on screen, as with --debug
debugging = False  # set for each invocation by the --debug option or the variable


def _version(value: bool) -> None:
    if value:
        import importlib.metadata

        typer.echo(f"rlc {importlib.metadata.version('rlcontroller')}")
        raise typer.Exit()


@app.callback()
def _commands(
    version: Annotated[
        bool, typer.Option("--version", callback=_version, is_eager=True, help="Print the version and exit.")
    ] = False,
    debug: Annotated[
        bool,
        typer.Option(
            "--debug", help=f"Show an internal error's traceback on screen (or set {DEBUG_VARIABLE}=1)."
        ),
    ] = False,
) -> None:
    """Reinforcement-learning active control of buildings under earthquakes."""
    global debugging
    debugging = debug or os.environ.get(DEBUG_VARIABLE, "") not in ("", "0")


def user_errors(command: Callable[..., Any]) -> Callable[..., Any]:
    """Print a user mistake as one line on stderr and exit with code 2 (1 for a file system
    error such as a full disk or a folder without write permission), without a traceback; any other
    failure as one line naming the file that keeps its traceback, exit code 3."""

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


def positive_finite(high: float) -> Callable[[float | None], float | None]:
    def check(value: float | None) -> float | None:
        if value is not None and not (math.isfinite(value) and 0.0 < value <= high):
            raise typer.BadParameter(f"expected a finite number in (0, {high:g}], got {value!r}")
        return value

    return check


RecordsOption = Annotated[
    Path | None,
    typer.Option(
        help="A folder of .AT2/.csv records (with an optional manifest.csv), one record file, or a wind "
        "suite (.yaml, kind: wind; configs/loads/) (default $RLC_RECORDS, else a synthetic suite)."
    ),
]
ScaleOption = Annotated[
    float | None, typer.Option(callback=positive_finite(10.0), help="Scale every record to this PGA (g).")
]
ModelOption = Annotated[str, typer.Option(help="Which saved model of the run: best or final.")]
CriteriaOption = Annotated[
    str,
    typer.Option(
        help="paper: J1-J4; benchmark: also the nonlinear benchmark's J1-J17 (Ohtori et al. 2004; member "
        "ends of an FE plant), benchmark_criteria.md"
    ),
]
RUN_HELP = (
    "Run or model folder, or an experiment YAML for the controller shipped for its building and devices "
    "(default: the default model; see rlc models)."
)
OutOption = Annotated[
    Path | None, typer.Option(help="Output folder, new or empty (default: a new folder under results/).")
]
ProgressOption = Annotated[
    bool | None,
    typer.Option(
        "--progress/--no-progress",
        show_default="on a terminal",
        help="Show a progress bar with steps/s and ETA.",
    ),
]
SCENARIOS_DEFAULT = (
    "configs/scenarios/standard.yaml; devices.yaml with mass devices, dampers.yaml with dampers"
)


class Engine(str, Enum):
    local = "local"
    dask = "dask"


EngineOption = Annotated[
    Engine,
    typer.Option(
        help="Where runs on a one-model-per-process plant (OpenSees) fan out: local processes, or Dask."
    ),
]
AddressOption = Annotated[
    str | None, typer.Option(help="An existing Dask scheduler (tcp://HOST:8786); default: a local cluster.")
]


def show_progress(progress: bool | None) -> bool:
    """The progress bar is on by default when the output is a terminal."""
    return sys.stdout.isatty() if progress is None else progress


def counted_lines(description: str, total: int) -> Callable[..., None]:
    """Progress as plain lines on stderr (done/total, seconds since the start): for `--progress` into a
    file."""
    started, done = time.monotonic(), 0

    def advance(amount: int = 1, label: str = "") -> None:
        nonlocal done
        done += amount
        what = f"{description}: {label}" if label else description
        typer.echo(f"{what}: {done}/{total}, {time.monotonic() - started:.0f} s", err=True)

    return advance


class Printed:
    """A command's `api.Report` on the terminal: its lines on stdout, notes on stderr, and (when `bars`) a
    progress bar on stderr while a long step runs (what it does, done/total, elapsed, time left), gone
    when it ends."""

    def __init__(self, progress: bool | None = False) -> None:
        self.bars = show_progress(progress)

    def line(self, text: str) -> None:
        typer.echo(text)

    def note(self, text: str) -> None:
        typer.echo(text, err=True)

    @contextmanager
    def progress(self, description: str, total: int) -> Iterator[Callable[..., None]]:
        if not self.bars:
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

        console = Console(stderr=True)
        if not console.is_terminal:  # a log (nohup): a live bar draws nothing there, so a line a step
            yield counted_lines(description, total)
            return
        columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn())
        with Progress(
            *columns, TextColumn("left"), TimeRemainingColumn(), console=console, transient=True
        ) as bar:
            task = bar.add_task(description, total=total)

            def advance(amount: int = 1, label: str = "") -> None:
                bar.update(
                    task, advance=amount, description=f"{description}: {label}" if label else description
                )

            yield advance
