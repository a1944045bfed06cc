"""Commands over many runs: `rlc tune`, `sweep`, `aggregate`."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rlcontroller.cli.app import (
    AddressOption,
    Engine,
    Printed,
    ProgressOption,
    RecordsOption,
    app,
    user_errors,
)


@app.command(short_help="Search hyperparameters with Optuna.")
@user_errors
def tune(
    *,
    config: Annotated[
        Path, typer.Argument(help="Experiment YAML whose algorithm part has a 'search' space.")
    ],
    trials: Annotated[
        int, typer.Option(min=1, max=100_000, help="Trials of the study in all, over every worker.")
    ],
    storage: Annotated[
        str | None,
        typer.Option(
            help="Optuna storage URL shared by workers on many machines (default: OUT/study.journal)."
        ),
    ] = None,
    study: Annotated[str | None, typer.Option(help="Study name (default: the experiment's name).")] = None,
    jobs: Annotated[int, typer.Option(min=1, max=256, help="Worker processes on this machine.")] = 1,
    out: Annotated[
        Path | None,
        typer.Option(help="Folder of the study's files and trial runs (default: results/tune-NAME)."),
    ] = None,
) -> None:
    """Search hyperparameters with Optuna (TPE, median pruning on the validation J1); run the same
    command on more machines with one --storage to share the study."""
    from rlcontroller import api

    ran, name, folder = api.tune(config, trials, storage=storage, study=study, jobs=jobs, out=out)
    typer.echo(f"{ran} trials run here; study {name!r}: trials.csv, best.yaml and plots in {folder}")


@app.command(short_help="Train and evaluate seeds x settings, then aggregate.")
@user_errors
def sweep(
    *,
    config: Annotated[Path, typer.Argument(help="Experiment YAML.")],
    seeds: Annotated[str, typer.Option(help="Seeds: a range 0-9 or a list 0,3,5.")] = "0-2",
    set_: Annotated[
        list[str] | None,
        typer.Option(
            "--set",
            help="KEY=V1,V2: a setting and its values (repeatable), e.g. algorithm.kwargs.gamma=0.99,0.999.",
        ),
    ] = None,
    engine: Annotated[
        Engine, typer.Option(help="local: processes here; dask: a Dask cluster.")
    ] = Engine.local,
    address: AddressOption = None,
    workers: Annotated[
        int, typer.Option(min=1, max=1024, help="Runs at once on a local engine or cluster.")
    ] = 2,
    records: RecordsOption = None,
    out: Annotated[
        Path | None, typer.Option(help="Folder of the runs (default: results/sweep-NAME).")
    ] = None,
) -> None:
    """Train and evaluate every combination of seeds and settings, then aggregate over seeds. Running
    the same command again redoes only what is missing."""
    from rlcontroller import api

    try:
        results, written, folder = api.sweep(
            config,
            seeds=seeds,
            settings=set_,
            engine=engine.value,
            address=address,
            workers=workers,
            records=records,
            out=out,
            report=Printed(),
        )
    except KeyboardInterrupt:
        typer.echo(
            "sweep stopped: the runs in progress saved a checkpoint; run the same command again to continue"
        )
        raise typer.Exit(130) from None
    failed = [result for result in results if result.status == "failed"]
    if written:
        typer.echo((folder / "aggregate.md").read_text())
    typer.echo(
        f"{len(results) - len(failed)} runs done, {len(failed)} failed; runs, sweep.csv and aggregate in "
        f"{folder}"
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
    """Per controller and metric over runs: mean, std, interquartile mean, 95 % stratified-bootstrap
    intervals."""
    from rlcontroller import api

    typer.echo(api.aggregate(runs, out, Printed(progress)))
    if out is not None:
        typer.echo(f"aggregate.csv, aggregate.md and aggregate.png in {out}")
