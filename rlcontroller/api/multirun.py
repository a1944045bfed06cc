"""Many runs at once: `rlc tune` (Optuna), `rlc sweep` (seeds x settings on an engine) and `rlc aggregate`
(statistics over runs) as functions."""

from __future__ import annotations

from pathlib import Path

from rlcontroller.api.common import QUIET, Report, load
from rlcontroller.config import ConfigError


def tune(
    config: Path,
    trials: int,
    *,
    storage: str | None = None,
    study: str | None = None,
    jobs: int = 1,
    out: Path | None = None,
) -> tuple[int, str, Path]:
    """Search the hyperparameters of `config`'s algorithm `search` space with Optuna (TPE, median pruning
    on the validation J1): the trials run here, the study's name and its folder."""
    from rlcontroller.multirun.tuning import tune as run_tuning

    experiment = load(config)
    name = study or experiment.name
    folder = out or Path("results") / f"tune-{name}"
    return run_tuning(experiment, trials, storage, name, out=folder, jobs=jobs), name, folder


def sweep(
    config: Path,
    *,
    seeds: str = "0-2",
    settings: list[str] | None = None,
    engine: str = "local",
    address: str | None = None,
    workers: int = 2,
    records: Path | None = None,
    out: Path | None = None,
    report: Report = QUIET,
):
    """Train and evaluate every combination of `seeds` ("0-9" or "0,3,5") and `settings` ("KEY=V1,V2")
    on the engine, then aggregate over seeds: the runs' results, the aggregate files and the folder."""
    from rlcontroller.multirun.sweep import parse_seeds, parse_setting
    from rlcontroller.multirun.sweep import sweep as run_sweep

    if address is not None and engine != "dask":
        raise ConfigError("--address: only with --engine dask")
    experiment = load(config)
    folder = out or Path("results") / f"sweep-{experiment.name}"
    chosen, parsed = parse_seeds(seeds), [parse_setting(text) for text in settings or []]
    results, written = run_sweep(
        experiment,
        chosen,
        parsed,
        folder,
        engine=engine,
        workers=workers,
        address=address,
        records=records,
        echo=report.line,
    )
    return results, written, folder


def aggregate(runs: list[Path], out: Path | None = None, report: Report = QUIET) -> str:
    """Per controller and metric over runs: mean, std, interquartile mean, 95 % stratified-bootstrap
    intervals, as Markdown; with `out` (a new folder) also aggregate.csv/.md/.png."""
    from rlcontroller.files import check_new_folder, new_folder
    from rlcontroller.multirun.aggregate import aggregate as statistics
    from rlcontroller.multirun.aggregate import markdown, scores, write_aggregate

    if out is not None:
        check_new_folder(out)
    table = scores(runs)
    groups = table.groupby([c for c in ("group", "controller", "metric") if c in table.columns]).ngroups
    with report.progress("bootstrap intervals", groups) as advance:
        table = statistics(table, advance=advance)
    title = f"{len(runs)} runs: mean over records and stories, statistics over runs"
    if out is not None:
        with new_folder(out) as staging:
            write_aggregate(table, staging, title)
    return markdown(table, title)
