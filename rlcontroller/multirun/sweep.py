"""Multi-seed, multi-setting studies: every combination of seeds and settings trained and evaluated.

`rlc sweep CONFIG --seeds 0-9 --set key=v1,v2 ...` plans the cartesian product of the seeds and the
settings' values; each combination is a normal run folder, OUT/GROUP/seedS (OUT/seedS without
settings), trained (or resumed, or skipped when finished) and evaluated on the records (or a wind suite) into
RUN/evaluation/. Runs go to an engine: `local` (processes on this machine) or `dask` (a Dask
distributed cluster: a local one of `workers` processes, or an existing one at `address`). A run that
fails is reported and the others go on; running the same command again redoes only what is missing.
At the end, one aggregate table over seeds per group (`multirun.aggregate`) in OUT.
"""

from __future__ import annotations

import itertools
import multiprocessing
import os
import signal
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures import as_completed as local_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from rlcontroller.config import (
    ConfigError,
    Experiment,
    build_experiment,
    check_seed,
    with_overrides,
)
from rlcontroller.simulation.fanout import dask_client


@dataclass(frozen=True)
class SweepRun:
    """One combination: its run folder, seed, settings and the group (settings without the seed)."""

    folder: Path
    seed: int
    settings: dict[str, Any]
    group: str
    config: str = field(repr=False)  # the resolved experiment as YAML (sent to the workers)


@dataclass
class RunResult:
    run: SweepRun
    status: str  # trained, resumed, finished before, failed
    seconds: float
    error: str = ""


def parse_seeds(text: str) -> list[int]:
    """'0-9', '0,3,5' or '2' -> the seeds, each checked."""
    seeds: list[int] = []
    for part in text.split(","):
        bounds = part.strip().split("-")
        if len(bounds) > 2 or not all(b.strip().isdigit() for b in bounds):
            raise ConfigError(f"--seeds {text!r}: expected a range like 0-9 or a list like 0,3,5")
        low, high = int(bounds[0]), int(bounds[-1])
        if high < low:
            raise ConfigError(f"--seeds {text!r}: the range {part.strip()} runs backwards")
        seeds.extend(check_seed(seed, "--seeds") for seed in range(low, high + 1))
    if len(set(seeds)) != len(seeds):
        raise ConfigError(f"--seeds {text!r}: a seed is listed twice")
    if len(seeds) > 1000:
        raise ConfigError(f"--seeds {text!r}: {len(seeds)} seeds; expected at most 1000")
    return seeds


def parse_setting(text: str) -> tuple[str, list[Any]]:
    """'algorithm.kwargs.gamma=0.99,0.999' -> the path and its values (YAML scalars or lists; commas
    inside brackets belong to a value: 'algorithm.policy.net_arch=[64,64],[128,128]')."""
    key, equals, values = text.partition("=")
    if not equals or not key.strip() or not values.strip():
        raise ConfigError(f"--set {text!r}: expected KEY=VALUE[,VALUE ...]")
    parts, depth, current = [], 0, ""
    for character in values:
        depth += {"[": 1, "{": 1, "]": -1, "}": -1}.get(character, 0)
        if character == "," and depth == 0:
            parts.append(current)
            current = ""
        else:
            current += character
    parts.append(current)
    try:
        parsed = [yaml.safe_load(part) for part in parts]
    except yaml.YAMLError as error:
        raise ConfigError(f"--set {text!r}: a value is not YAML ({str(error).splitlines()[0]})") from None
    if any(part.strip() == "" for part in parts):
        raise ConfigError(f"--set {text!r}: an empty value")
    return key.strip(), parsed


def plan(
    experiment: Experiment, seeds: list[int], settings: list[tuple[str, list[Any]]], out: Path
) -> list[SweepRun]:
    """Every combination of settings' values and seeds, each checked as a whole experiment now."""
    keys = [key for key, _ in settings]
    if len(set(keys)) != len(keys):
        raise ConfigError("--set: a key is set twice; give all its values in one --set KEY=V1,V2")
    if "seed" in keys:
        raise ConfigError("--set seed: the seeds of a sweep are given by --seeds")
    runs = []
    for values in itertools.product(*(values for _, values in settings)):
        chosen = dict(zip(keys, values, strict=True))
        group = ",".join(f"{key.split('.')[-1]}={_short(value)}" for key, value in chosen.items())
        for seed in seeds:
            overrides = chosen | {"seed": seed}
            given = ",".join(f"{key}={_short(value)}" for key, value in chosen.items())
            resolved = with_overrides(experiment, overrides, f"--set {given}" if given else "--seeds")
            folder = (out / _folder_name(group) if group else out) / f"seed{seed}"
            runs.append(SweepRun(folder, seed, chosen, group or experiment.name, resolved.to_yaml()))
    return runs


def _short(value: Any) -> str:
    return yaml.safe_dump(value, default_flow_style=True).strip().removesuffix("...").strip().replace(" ", "")


def _folder_name(group: str) -> str:
    return "".join(c if c.isalnum() or c in "=.,_+-" else "_" for c in group)[:120]


def run_one(run: SweepRun, records: str | None) -> RunResult:
    """Train (new, resumed or already finished) and evaluate one run; never raises."""
    start = time.perf_counter()
    try:
        status = _train(run)
        _evaluate(run, records)
        return RunResult(run, status, time.perf_counter() - start)
    except Exception as error:  # reported with the others; a sweep goes on
        message = (str(error).strip().splitlines() or [""])[-1]
        return RunResult(
            run, "failed", time.perf_counter() - start, f"{type(error).__name__}: {message}"[:300]
        )


def _train(run: SweepRun) -> str:
    from rlcontroller.learning.training import train

    experiment = build_experiment(yaml.safe_load(run.config), {}, str(run.folder / "config.yaml"))
    if (run.folder / "final_policy.yaml").is_file():
        return "finished before"
    if (run.folder / "config.yaml").is_file():
        stored, planned = yaml.safe_load((run.folder / "config.yaml").read_text()), yaml.safe_load(run.config)
        for config in (stored, planned):
            config.get("algorithm", {}).pop("search", None)  # rlc tune's space: training ignores it
        if stored != planned:
            raise ConfigError(
                f"{run.folder}: holds a run of another configuration; move it or choose another --out"
            )
        summary = train(resume=run.folder)
        status = "resumed"
    else:
        summary = train(experiment=experiment, run_dir=run.folder)
        status = "trained"
    if summary.interrupted:
        _signalled.set()
    if summary.interrupted or summary.time_limit_reached:
        raise RuntimeError(f"{run.folder}: training stopped before the end")
    return status


def _evaluate(run: SweepRun, records: str | None) -> None:
    from rlcontroller.control.policy_file import read_policy
    from rlcontroller.evaluation.evaluation import compare
    from rlcontroller.evaluation.report import write_report
    from rlcontroller.files import new_folder
    from rlcontroller.physics.motions.loads import load_suite
    from rlcontroller.physics.plant import Plant

    out = run.folder / "evaluation"
    if (out / "metrics.csv").is_file():
        return
    experiment = build_experiment(yaml.safe_load(run.config), {}, str(run.folder / "config.yaml"))
    plant = Plant(experiment)
    motions, label = load_suite(records, None, plant)
    evaluation = compare(plant, motions, label, policy=read_policy(run.folder, "best", plant))
    with new_folder(out) as staging:
        write_report(evaluation, staging)


def execute(
    runs: list[SweepRun], records: str | None, engine: str, workers: int, *, address: str | None
) -> Iterator[RunResult]:
    """Each run's result as it finishes, from the chosen engine."""
    if engine == "dask":
        yield from _dask(runs, records, workers, address)
        return
    yield from _local(runs, records, workers)


WORKER_LOSSES = 5  # times a run's worker may die (killed, out of memory) before the run is reported failed


def _local(runs: list[SweepRun], records: str | None, workers: int) -> Iterator[RunResult]:
    """Local worker processes. A worker that dies breaks the whole pool: the runs it and its siblings
    had not finished go to a new pool, where they resume from their last checkpoints (the dead
    holder's lock is stale and taken over). A run whose own worker died (its lock left behind, each
    dead holder counted once: the lock stays while the run waits in the queue) more than
    WORKER_LOSSES times is reported failed."""

    from rlcontroller.files import lock_pid

    context = multiprocessing.get_context("spawn")
    stop = context.Event()  # set at Ctrl-C: each worker stops its run as Ctrl-C would and exits
    pending = list(runs)
    dead_holders: dict[Path, set[int]] = {run.folder: set() for run in runs}
    while pending:
        lost = []
        with ProcessPoolExecutor(
            workers, context, initializer=stop_with_parent, initargs=(os.getpid(), stop)
        ) as pool:
            futures = {pool.submit(_run_local, run, records): run for run in pending}
            try:
                for future in local_completed(futures):
                    run = futures[future]
                    try:
                        yield future.result()
                    # a run still queued, or stopped by its sibling's death, is not to blame
                    except BrokenProcessPool:
                        holder = lock_pid(run.folder)
                        if holder is not None:
                            dead_holders[run.folder].add(holder)
                        if len(dead_holders[run.folder]) > WORKER_LOSSES:
                            yield RunResult(
                                run, "failed", 0.0, f"worker lost {len(dead_holders[run.folder])} times"
                            )
                        else:
                            lost.append(run)
                    except Exception as error:
                        yield RunResult(
                            run, "failed", 0.0, f"worker lost: {type(error).__name__}: {error}"[:300]
                        )
            # the pool's exit then waits for the workers' checkpoints, starts nothing
            except KeyboardInterrupt:
                stop.set()
                pool.shutdown(wait=True, cancel_futures=True)
                raise
        pending = lost


_sweep_gone = threading.Event()  # in a local worker: the sweep's process has died or asked it to stop
_running = threading.Event()  # in a local worker: a run is in progress
_signalled = threading.Event()  # in a local worker: a run stopped at a signal (Ctrl-C, or the pool's SIGTERM)


def stop_with_parent(parent: int, stop) -> None:
    """Worker initializer: once the sweep's process is gone (killed, say by a job's time limit) or has
    set `stop` (at its Ctrl-C or SIGINT), stop the run in progress as Ctrl-C would (it checkpoints and
    resumes later) and exit, instead of training on as an orphan beside a sweep started again. The
    worker leaves the terminal's process group, so that one Ctrl-C reaches it once, through the sweep
    (a second one would abort without a checkpoint). A SIGTERM outside training (whose own handler
    checkpoints), as a broken pool sends its other workers, exits through the run's `finally` blocks:
    its lock is released, and its run is not charged with a worker loss that was not its own."""
    os.setpgrp()

    def exit_cleanly(number: int, frame: object) -> None:
        _signalled.set()
        raise SystemExit(1)

    signal.signal(signal.SIGTERM, exit_cleanly)

    def watch() -> None:
        while os.getppid() == parent and not stop.is_set():
            time.sleep(0.5)
        _sweep_gone.set()
        if not _running.is_set():
            os._exit(1)
        os.kill(os.getpid(), signal.SIGTERM)  # `_run_local` exits once the run has stopped

    threading.Thread(target=watch, name="stop-with-parent", daemon=True).start()


def _run_local(run: SweepRun, records: str | None) -> RunResult:
    """`run_one` in a local worker, which exits after it if the sweep has died meanwhile or the run
    was stopped by a signal: a pool whose sibling worker died sends its other workers SIGTERM, and
    a worker that went on to the runs still queued would leave the sweep one worker short."""
    _running.set()
    try:
        return run_one(run, records)
    finally:
        _running.clear()
        if _sweep_gone.is_set() or _signalled.is_set():
            os._exit(1)


def _dask(
    runs: list[SweepRun], records: str | None, workers: int, address: str | None
) -> Iterator[RunResult]:
    from distributed import as_completed

    with dask_client(workers, address) as client:
        futures = {
            client.submit(run_one, run, records, pure=False, key=f"run-{i}-{run.folder.name}"): run
            for i, run in enumerate(runs)
        }
        for result in _as_completed(futures, as_completed):
            if result.status == "failed" and client.status != "running":  # the scheduler is gone, not a run
                raise ConfigError(
                    f"--address {address or 'local cluster'}: lost the Dask scheduler; the runs keep their "
                    "checkpoints: run the same command again (with a scheduler) to continue"
                )
            yield result


def _as_completed(futures: dict, completed: Callable) -> Iterator[RunResult]:
    for future in completed(futures):
        try:
            yield future.result()
        except Exception as error:  # the worker itself died (killed, out of memory)
            yield RunResult(
                futures[future], "failed", 0.0, f"worker lost: {type(error).__name__}: {error}"[:300]
            )


def sweep(
    experiment: Experiment,
    seeds: list[int],
    settings: list[tuple[str, list[Any]]],
    out: Path,
    *,
    engine: str = "local",
    workers: int = 2,
    address: str | None = None,
    records: Path | str | None = None,
    echo: Callable[[str], None] = print,
) -> tuple[list[RunResult], list[Path]]:
    """Plan, run on the engine (reporting each run as it ends), then aggregate over seeds per group:
    the results and the aggregate files written in `out` (none when no run was evaluated). Every
    combination and the `records` suite are checked before any work. `out` is locked for the sweep: a
    second sweep into it refuses in one line naming this one."""
    from rlcontroller.files import folder_lock
    from rlcontroller.physics.motions.loads import load_suite
    from rlcontroller.physics.plant import Plant

    runs = plan(experiment, seeds, settings, out)
    load_suite(records, None, Plant(experiment), echo)
    records = str(Path(records).resolve()) if records else None
    out.mkdir(parents=True, exist_ok=True)
    with folder_lock(out, "rlc sweep"):
        return _sweep(experiment, seeds, runs, out, engine, workers, address, records, echo)


def _sweep(
    experiment: Experiment,
    seeds: list[int],
    runs: list[SweepRun],
    out: Path,
    engine: str,
    workers: int,
    address: str | None,
    records: str | None,
    echo: Callable[[str], None],
) -> tuple[list[RunResult], list[Path]]:
    from rlcontroller.files import atomic_write
    from rlcontroller.multirun.aggregate import aggregate, scores, write_aggregate

    combinations = len(runs) // len(seeds)
    echo(f"{len(runs)} run(s): {len(seeds)} seed(s) x {combinations} setting(s), on the {engine} engine")
    results = []
    for number, result in enumerate(execute(runs, records, engine, workers, address=address), start=1):
        results.append(result)
        detail = f": {result.error}" if result.error else ""
        echo(f"[{number}/{len(runs)}] {result.status} {result.run.folder} ({result.seconds:.0f} s){detail}")
    lines = ["folder,group,seed,status,seconds,error"]
    for result in sorted(results, key=lambda r: str(r.run.folder)):
        error = result.error.replace('"', "'")
        lines.append(
            f'{result.run.folder},"{result.run.group}",{result.run.seed},{result.status},{result.seconds:.1f},"{error}"'
        )
    atomic_write(out / "sweep.csv", "\n".join(lines) + "\n")
    evaluated = [run for run in runs if (run.folder / "evaluation" / "metrics.csv").is_file()]
    if not evaluated:
        return results, []
    table = scores([run.folder for run in evaluated])
    groups = {str(run.folder): run.group for run in evaluated}
    table["group"] = table["run"].map(groups)
    runs = f"{len(evaluated)} run{'s' * (len(evaluated) != 1)}"
    title = f"{experiment.name}: {runs}, aggregated over seeds per setting"
    return results, write_aggregate(aggregate(table), out, title)
