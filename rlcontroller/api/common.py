"""What every command needs: its experiment, its run or model folder, a new output folder, and the
`Report` a caller passes in to hear how the work goes (the command line prints it; `QUIET` says nothing)."""

from __future__ import annotations

import datetime as dt
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from rlcontroller.assets import (
    DEFAULT_MODEL,
    MODELS,
)
from rlcontroller.config import ConfigError, Experiment, load_experiment

Advance = Callable[..., None]
"""`advance(amount=1, label="")`: a long step moved on."""


class Report:
    """How a command's work goes, told as it happens: `line` (what the command reports: the command
    line's stdout), `note` (a remark beside it: stderr) and `progress(description, total)` (a context
    yielding `advance` while a long step runs). This one says nothing; the command line's prints."""

    def line(self, text: str) -> None:
        """A line of the command's report."""

    def note(self, text: str) -> None:
        """A remark: a fallback taken, a file still being written, a policy never checked."""

    @contextmanager
    def progress(self, description: str, total: int) -> Iterator[Advance]:
        yield lambda amount=1, label="": None


QUIET = Report()


@dataclass(frozen=True)
class Judging:
    """What a judging command (`evaluate`, `compare_lqg`) runs the controllers on and writes: the `records` (a
    folder or a loads YAML; None: the embedded synthetic suite), their PGA scaled to `scale_pga` (g; None: as
    recorded), the run's `model` policy ("best" or "final") and the `criteria` ("paper": J1-J4; "benchmark":
    the nonlinear benchmark's J1-J17 too, `evaluation.benchmark`)."""

    records: Path | None = None
    scale_pga: float | None = None  # g
    model: str = "best"
    criteria: str = "paper"


DEFAULT_JUDGING = Judging()  # the embedded suite, as recorded, the best policy, J1-J4


def load(config: Path | None) -> Experiment:
    """The experiment of `config`, or of the default model; an OpenSees plant without a building of its own
    gets its reduced model as its design model (`physics.fe.build.reduced_building`: the file runs, named)."""
    from rlcontroller.physics.fe.build import reduced_building

    return load_experiment(
        DEFAULT_MODEL / "config.yaml" if config is None else config, reduce=reduced_building
    )


def folder_experiment(folder: Path) -> Experiment:
    """The experiment a run or model folder was made with (its config.yaml, self-contained)."""
    return load_experiment(folder / "config.yaml", self_contained=True)


def shipped_folders() -> list[Path]:
    """The shipped controller folders under models/, by name."""
    return sorted(path for path in MODELS.iterdir() if (path / "best_policy.yaml").is_file())


def shipped_for(experiment: Experiment) -> Path | None:
    """The shipped controller made for `experiment`'s building, actuators, devices and load
    (`Experiment.hardware`): the default when it is one of them, else the first by name; None when none is."""
    made_for = experiment.hardware()
    matching = [folder for folder in shipped_folders() if folder_experiment(folder).hardware() == made_for]
    return DEFAULT_MODEL if DEFAULT_MODEL in matching else next(iter(matching), None)


def model_folder(run_dir: Path | None, report: Report = QUIET) -> Path:
    """The run folder given; for an experiment YAML, the controller shipped for its building and devices
    (`shipped_for`); with neither, the committed default model. Says when another process still writes it."""
    folder = run_dir or DEFAULT_MODEL
    if folder.is_file() and folder.suffix in (".yaml", ".yml"):
        folder = _shipped_for_config(folder, report)
    if not (folder / "config.yaml").is_file():
        hint = "" if run_dir else " (no RUN_DIR given and no committed default model)"
        raise ConfigError(
            f"{folder}: not a run folder: no config.yaml{hint}; train one with 'rlc train CONFIG'"
        )
    from rlcontroller.files import active_holder

    holder = active_holder(folder)
    if holder is not None:
        report.note(f"note: {folder} is still in use by {holder}; reading its newest complete files")
    return folder


def _shipped_for_config(config: Path, report: Report) -> Path:
    from rlcontroller.api.describe import hardware_label

    experiment = load(config)
    folder = shipped_for(experiment)
    if folder is None:
        raise ConfigError(
            f"{config}: no shipped controller for its {hardware_label(experiment)} (rlc models): train one "
            f"('rlc train {config}'), design one ('rlc design {config} --out FOLDER'), or compare LQG on it "
            f"('rlc compare lqg --config {config}')"
        )
    report.note(f"{config}: using {folder}, the shipped controller for its {hardware_label(experiment)}")
    return folder


def stamp() -> str:
    return dt.datetime.now().strftime("%Y%m%d-%H%M%S")


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


def motions_text(count: int) -> str:
    return f"{count} motion{'s' if count != 1 else ''}"


def keep_model_messages(messages, folder: Path, report: Report) -> None:
    """What the model printed during the runs (`simulation.fanout.model_messages`), kept in the command's
    output `folder` and counted in one line; nothing when it printed nothing."""
    count = messages.lines
    kept = messages.keep(folder)
    if kept is not None:
        report.note(f"note: the FE model printed {count} lines during the runs (OpenSees' own words): {kept}")
