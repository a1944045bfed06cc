"""Hyperparameter search with Optuna: `rlc tune CONFIG --trials N [--storage URL] [--study NAME] [--jobs J]`.

The search space is the algorithm's `search` part (dotted paths into the experiment and their
ranges). Each trial is a normal training run (OUT/trials/trial_NNNN) of the experiment with the
sampled values; its objective is the validation J1 of its best model (generated motions only, never
the records), and Optuna's median pruner stops a trial whose validation J1 at a step is worse than
the median of earlier trials at that step. TPE sampler, minimised.

Storage: by default a journal file OUT/study.journal (Optuna's recommendation for several processes
on one machine; SQLite locks under concurrent writes); with `--storage URL` any database Optuna
takes (postgresql://..., mysql://...) so that workers on many machines share one study by running the
same command. The study stops at N trials in all: each worker asks for trials until N are complete,
pruned or running. A trial whose worker died is marked failed: by the trial's worker host and
process id for the journal file (checked whenever a worker starts a trial), by Optuna's heartbeat
for a database. Outputs, rewritten by each worker as trials end: trials.csv, best.yaml (the best
trial's experiment, ready for `rlc train`), optimization_history.png and param_importances.png.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import socket
import sys
import warnings
from pathlib import Path
from typing import Any

from rlcontroller.config import ConfigError, Experiment, SearchRange, with_overrides
from rlcontroller.files import atomic_savefig, atomic_write

HEARTBEAT_S = 60  # database storages: a running trial's worker reports this often
GRACE_S = 180  # ... and its trial is failed after this long without a report


def storage(url: str | None, out: Path):
    """The Optuna storage: the journal file OUT/study.journal, or the database at `url`."""
    import optuna
    from optuna.storages.journal import JournalFileBackend, JournalStorage

    if url is None:
        out.mkdir(parents=True, exist_ok=True)
        return JournalStorage(JournalFileBackend(str(out / "study.journal")))
    try:
        with warnings.catch_warnings():
            # the heartbeat is "experimental"
            warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
            return optuna.storages.RDBStorage(url, heartbeat_interval=HEARTBEAT_S, grace_period=GRACE_S)
    except Exception as error:  # a bad URL, a missing driver, an unreachable server
        raise ConfigError(
            f"--storage {url}: {type(error).__name__}: {str(error).splitlines()[0][:200]}"
        ) from None


def suggest(trial, space: dict[str, SearchRange]) -> dict[str, Any]:
    """The trial's value of every searched setting."""
    values = {}
    for path, spec in space.items():
        if spec.choices is not None:
            encoded = [json.dumps(choice) for choice in spec.choices]
            values[path] = json.loads(trial.suggest_categorical(path, encoded))
        elif spec.integer:
            values[path] = trial.suggest_int(path, int(spec.low), int(spec.high), log=spec.log)
        else:
            values[path] = trial.suggest_float(path, spec.low, spec.high, log=spec.log)
    return values


def fail_dead_trials(study) -> list[int]:
    """Mark failed the running trials of this host whose worker process is gone; their numbers."""
    import optuna

    failed = []
    host = socket.gethostname()
    for trial in study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.RUNNING,)):
        attributes = trial.user_attrs
        if attributes.get("host") == host and not _alive(int(attributes.get("pid", -1))):
            study._storage.set_trial_state_values(trial._trial_id, optuna.trial.TrialState.FAIL)
            failed.append(trial.number)
    return failed


def _alive(pid: int) -> bool:
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


FAILURES_IN_A_ROW = 5  # a worker whose trials keep failing stops and says why


def counted(study) -> int:
    """Trials that count towards the total: complete, pruned or running (not failed, not surplus)."""
    from optuna.trial import TrialState

    states = (TrialState.COMPLETE, TrialState.PRUNED, TrialState.RUNNING)
    return sum(1 for t in study.get_trials(deepcopy=False, states=states) if not t.user_attrs.get("surplus"))


def worker(
    experiment: Experiment, trials: int, *, storage_url: str | None, study_name: str, out: Path
) -> int:
    """Run trials of the study until `trials` count in all (from every worker); the number run here."""
    import optuna
    from optuna.trial import TrialState

    from rlcontroller.learning.training import train

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.create_study(
        storage=storage(storage_url, out),
        study_name=study_name,
        direction="minimize",
        sampler=optuna.samplers.TPESampler(),
        pruner=optuna.pruners.MedianPruner(n_startup_trials=3, n_warmup_steps=0),
        load_if_exists=True,
    )
    mine: list[int] = []

    def objective(trial) -> float:
        trial.set_user_attr("host", socket.gethostname())
        trial.set_user_attr("pid", os.getpid())
        mine.append(trial.number)
        ahead = [t for t in study.get_trials(deepcopy=False) if t.number < trial.number]
        if sum(1 for t in ahead if t.state != TrialState.FAIL and not t.user_attrs.get("surplus")) >= trials:
            trial.set_user_attr("surplus", True)  # another worker took the last trial meanwhile
            study.stop()
            raise optuna.TrialPruned("the study already has its trials")
        folder = out / "trials" / f"trial_{trial.number:04d}"
        trial.set_user_attr("run_dir", str(folder))

        def report(row: dict[str, float]) -> bool:
            trial.report(row["eval_J1"], int(row["steps"]))
            return not trial.should_prune()

        try:
            resolved = with_overrides(
                experiment, suggest(trial, experiment.algorithm.search), f"trial {trial.number}"
            )
            summary = train(experiment=resolved, run_dir=folder, on_validation=report)
        except Exception as error:  # a failed trial, recorded with its reason; the worker goes on
            trial.set_user_attr("error", f"{type(error).__name__}: {error}"[:300])
            raise
        if summary.stopped_by_validation:
            raise optuna.TrialPruned()
        return summary.best["eval_J1"]

    def after_trial(study, trial) -> None:
        fail_dead_trials(study)
        write_outputs(study, experiment, out)
        result = f"validation J1 {trial.value:.3f}" if trial.value is not None else trial.state.name.lower()
        print(
            f"trial {trial.number}: {result}; {counted(study)} of {trials} trials done",
            file=sys.stderr,
            flush=True,
        )
        recent = [t.state for t in study.get_trials(deepcopy=False) if t.number in mine[-FAILURES_IN_A_ROW:]]
        if counted(study) >= trials or (
            len(recent) == FAILURES_IN_A_ROW and set(recent) == {TrialState.FAIL}
        ):
            study.stop()

    fail_dead_trials(study)
    if counted(study) < trials:
        study.optimize(objective, callbacks=[after_trial], catch=(Exception,))
    write_outputs(study, experiment, out)
    states = [t.state for t in study.get_trials(deepcopy=False) if t.number in mine[-FAILURES_IN_A_ROW:]]
    if len(states) == FAILURES_IN_A_ROW and set(states) == {TrialState.FAIL}:
        raise ConfigError(
            f"{FAILURES_IN_A_ROW} trials in a row failed; see the error column of {out / 'trials.csv'}"
        )
    return len(mine)


def write_outputs(study, experiment: Experiment, out: Path) -> list[Path]:
    """trials.csv, best.yaml and the two plots, from the study as it stands."""
    import optuna

    frame = study.trials_dataframe(attrs=("number", "state", "value", "duration", "params", "user_attrs"))
    if "user_attrs_surplus" in frame.columns:
        frame = frame[frame["user_attrs_surplus"] != True]  # noqa: E712 (NaN or True)
    written = [atomic_write(out / "trials.csv", frame.to_csv(index=False))]
    complete = study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))
    if not complete:
        return written
    best = min(complete, key=lambda trial: trial.value)
    values = {
        path: json.loads(value) if isinstance(value, str) else value for path, value in best.params.items()
    }
    resolved = with_overrides(experiment, values, f"trial {best.number}")
    header = (
        f"# rlc tune: best of {len(complete)} complete trials of study {study.study_name!r}: trial "
        f"{best.number}, validation J1 {best.value:.4f} (run folder {best.user_attrs.get('run_dir', '?')}).\n"
    )
    written.append(atomic_write(out / "best.yaml", header + resolved.to_yaml()))
    written += _plots(study, out, len(complete))
    return written


def _plots(study, out: Path, complete: int) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator
    from optuna.visualization import matplotlib as optuna_plots

    written = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # Optuna marks its matplotlib plots experimental
        axes = optuna_plots.plot_optimization_history(study, target_name="validation J1")
        axes.xaxis.set_major_locator(MaxNLocator(integer=True))  # trial numbers, never 1.5
        written.append(atomic_savefig(axes.figure, out / "optimization_history.png"))
        plt.close(axes.figure)
        if complete >= 2 and study.best_trial.params:
            try:
                axes = optuna_plots.plot_param_importances(study)
            except (RuntimeError, ValueError):  # too few distinct trials for importances
                return written
            axes.figure.set_size_inches(9, 1.5 + 0.45 * len(study.best_trial.params))
            axes.figure.tight_layout()  # room for the dotted parameter names on the left
            written.append(atomic_savefig(axes.figure, out / "param_importances.png"))
            plt.close(axes.figure)
    return written


def tune(
    experiment: Experiment, trials: int, storage_url: str | None, study_name: str, *, out: Path, jobs: int
) -> int:
    """`jobs` worker processes (or this process for one) on the study; the number of trials run here."""
    if not experiment.algorithm.search:
        file, prefix = experiment.origin("algorithm")
        raise ConfigError(
            f"{file}: {prefix + '.' if prefix else ''}search: empty; declare the settings to tune"
        )
    with_overrides(experiment, {}, "rlc tune")
    storage(storage_url, out)  # a bad URL stops here, before any worker starts
    if jobs == 1:
        return worker(experiment, trials, storage_url=storage_url, study_name=study_name, out=out)
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(max_workers=jobs, mp_context=multiprocessing.get_context("spawn")) as pool:
        futures = [pool.submit(worker, experiment, trials, storage_url, study_name, out) for _ in range(jobs)]
        return sum(future.result() for future in futures)
