"""Sweeps: seeds and settings parsed and planned, runs on a Dask cluster of two workers and on local
processes, a failed run reported while the others go on, a re-run that redoes nothing done, and a
killed sweep whose worker checkpoints and stops."""

import contextlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml
from conftest import REPOSITORY

from rlcontroller.config import ConfigError, Experiment
from rlcontroller.multirun.sweep import parse_seeds, parse_setting, plan, sweep

# a run of a few seconds
TINY = yaml.safe_load((REPOSITORY / "configs" / "testing" / "tiny.yaml").read_text())


def test_seeds_and_settings_parse_as_a_user_writes_them():
    assert (
        parse_seeds("0-3") == [0, 1, 2, 3] and parse_seeds("5,7,9") == [5, 7, 9] and parse_seeds("4") == [4]
    )
    assert parse_setting("algorithm.kwargs.gamma=0.99,0.999") == ("algorithm.kwargs.gamma", [0.99, 0.999])
    assert parse_setting("algorithm.policy.net_arch=[64,64],[128]") == (
        "algorithm.policy.net_arch",
        [[64, 64], [128]],
    )
    for bad in ("3-1", "a-b", "1,1", "-2"):
        with pytest.raises(ConfigError, match="--seeds"):
            parse_seeds(bad)
    for bad in ("gamma", "=1", "algorithm.kwargs.gamma=", "algorithm.kwargs.gamma=0.9,,0.99"):
        with pytest.raises(ConfigError, match="--set"):
            parse_setting(bad)


def test_the_plan_is_the_cartesian_product_and_checks_every_run_first(tmp_path):
    experiment = Experiment.model_validate(TINY)
    settings = [("algorithm.kwargs.gamma", [0.9, 0.99]), ("algorithm.policy.net_arch", [[16], [8, 8]])]
    runs = plan(experiment, [0, 1, 2], settings, tmp_path)
    assert len(runs) == 12 and len({run.folder for run in runs}) == 12
    assert runs[0].folder == tmp_path / "gamma=0.9,net_arch=_16_" / "seed0"  # no brackets in paths
    assert runs[0].group == "gamma=0.9,net_arch=[16]"
    assert yaml.safe_load(runs[-1].config)["algorithm"]["policy"]["net_arch"] == [8, 8]
    with pytest.raises(ConfigError, match="algorithm.n_envs"):
        plan(experiment, [0], [("algorithm.n_envs", [2, 0])], tmp_path)
    with pytest.raises(ConfigError, match="no setting 'gama'"):
        plan(experiment, [0], [("algorithm.kwargs.gama.x", [1])], tmp_path)


@pytest.mark.slow
def test_a_sweep_on_a_dask_cluster_of_two_workers_reports_failures_and_resumes(tmp_path):
    pytest.importorskip("distributed", reason="the distributed extra: pip install -e '.[distributed]'")
    experiment = Experiment.model_validate(TINY)
    # 1: the configuration allows it (a whole number >= 1); PPO refuses it when it starts (its advantages are
    # normalised per minibatch)
    settings = [("algorithm.kwargs.batch_size", [64, 1])]
    lines = []
    results, written = sweep(
        experiment, [0, 1], settings, tmp_path, engine="dask", workers=2, echo=lines.append
    )
    by_status = sorted(
        (result.run.settings["algorithm.kwargs.batch_size"], result.status) for result in results
    )
    assert by_status == [(1, "failed"), (1, "failed"), (64, "trained"), (64, "trained")]
    failed = [result.error for result in results if result.status == "failed"]
    assert all("batch_size` must be greater than 1" in error for error in failed), failed
    assert {path.name for path in written} == {"aggregate.csv", "aggregate.md", "aggregate.png"}
    assert "| batch_size=64 | RL | 2 |" in (tmp_path / "aggregate.md").read_text()
    model = tmp_path / "batch_size=64" / "seed0" / "final_model.zip"
    stamp = model.stat().st_mtime_ns
    again, _ = sweep(experiment, [0, 1], settings, tmp_path, engine="dask", workers=2, echo=lines.append)
    assert sorted(result.status for result in again) == [
        "failed",
        "failed",
        "finished before",
        "finished before",
    ]
    assert model.stat().st_mtime_ns == stamp  # nothing retrained
    assert "sweep.csv" in {path.name for path in tmp_path.iterdir()}


@pytest.mark.slow
def test_rlc_sweep_on_local_processes(tmp_path):
    config = tmp_path / "tiny.yaml"
    config.write_text(yaml.safe_dump(TINY))
    out = tmp_path / "sweep"
    command = [
        sys.executable,
        "-m",
        "rlcontroller",
        "sweep",
        str(config),
        "--seeds",
        "0-1",
        "--out",
        str(out),
    ]
    done = subprocess.run(command, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "2 runs done, 0 failed" in done.stdout and (out / "seed1" / "evaluation" / "metrics.csv").is_file()
    refused = subprocess.run([*command, "--address", "tcp://nowhere:1"], capture_output=True, text=True)
    assert refused.returncode == 2 and "--address: only with --engine dask" in refused.stderr


@pytest.mark.slow
def test_a_sweep_evaluates_its_runs_on_a_wind_suite_as_rlc_evaluate_does(tmp_path):
    config = tmp_path / "tiny.yaml"
    config.write_text(yaml.safe_dump(TINY))
    suite = yaml.safe_load((REPOSITORY / "configs" / "loads" / "wind.yaml").read_text())
    wind = tmp_path / "wind.yaml"
    wind.write_text(yaml.safe_dump(suite | {"speeds": [30.0], "records_per_speed": 1, "duration": 30.0}))
    out = tmp_path / "sweep"
    command = [sys.executable, "-m", "rlcontroller", "sweep", str(config), "--seeds", "0", "--out", str(out)]
    done = subprocess.run([*command, "--records", str(wind)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    summary = (out / "seed0" / "evaluation" / "summary.md").read_text()
    evaluated = subprocess.run(
        [sys.executable, "-m", "rlcontroller", "evaluate", str(out / "seed0"), "--records", str(wind)],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert "1 generated wind records of 30 s" in summary and "rms_acceleration_top" in summary
    rl_row = next(line for line in summary.splitlines() if line.startswith("| RL |"))
    assert rl_row in evaluated.stdout  # the same numbers as rlc evaluate on the same suite


@pytest.mark.slow
def test_a_killed_sweep_leaves_no_worker_training_and_its_run_resumable(tmp_path):
    """SIGKILL to `rlc sweep`: its worker checkpoints and exits instead of training on as an orphan."""
    sweep_process, out, workers = long_sweep_training(tmp_path, "0")
    assert len(workers) == 1
    sweep_process.kill()
    sweep_process.wait()
    deadline = time.time() + 60
    while alive(workers[0]):
        assert time.time() < deadline, "the worker kept training after its sweep was killed"
        time.sleep(0.2)
    newest = sorted((out / "seed0" / "checkpoints").glob("step_*"))[-1]
    assert (newest / "state.json").is_file() and not (out / "seed0" / "final_model.zip").exists()


def long_sweep_training(tmp_path: Path, seeds: str) -> tuple[subprocess.Popen, Path, list[int]]:
    """`rlc sweep` of a long run per seed on one local worker, once seed 0 has its first checkpoint:
    the sweep's process, its folder and its worker processes."""
    config = dict(TINY, algorithm=dict(TINY["algorithm"], total_steps=10_000_000, checkpoint_every=256))
    (tmp_path / "long.yaml").write_text(yaml.safe_dump(config))
    out = tmp_path / "sweep"
    command = [sys.executable, "-m", "rlcontroller", "sweep", str(tmp_path / "long.yaml"), "--seeds", seeds]
    # background (CI) ignore SIGINT, and a child that inherits that ignores it too, as the shell intends
    sweep_process = subprocess.Popen(
        [*command, "--workers", "1", "--out", str(out)],
        stdout=subprocess.DEVNULL,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),  # as at a terminal: tests run in the
    )
    deadline = time.time() + 120
    while not list((out / "seed0" / "checkpoints").glob("step_*")):
        assert sweep_process.poll() is None and time.time() < deadline
        time.sleep(0.2)
    workers = [
        pid
        for pid in children(sweep_process.pid)
        if b"spawn_main" in Path(f"/proc/{pid}/cmdline").read_bytes()
    ]
    return sweep_process, out, workers


def children(pid: int) -> list[int]:
    """Process ids whose parent is `pid` (Linux /proc)."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            found.append(int(stat.parent.name))
    return found


def alive(pid: int) -> bool:
    """Running (not gone, not a zombie)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def test_a_second_sweep_into_the_same_folder_and_a_train_of_its_run_are_refused(tmp_path):
    """While a sweep holds its folder (and a run of it trains), a second sweep there, or a train
    --resume of that run, refuses in one line naming the holder; nothing is started."""
    import json
    import socket

    from rlcontroller.files import LOCK
    from rlcontroller.learning.training import train

    holder = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        lock = {"host": socket.gethostname(), "pid": holder.pid, "what": "rlc sweep", "started": "now"}
        (tmp_path / LOCK).write_text(json.dumps(lock))
        with pytest.raises(ConfigError, match=f"in use by rlc sweep on .* \\(pid {holder.pid}"):
            sweep(
                Experiment.model_validate(TINY),
                [0],
                [],
                tmp_path,
                engine="local",
                workers=1,
                echo=lambda _: None,
            )
        assert sorted(p.name for p in tmp_path.iterdir()) == [LOCK]  # no run folder, no sweep.csv
        run = tmp_path / "seed0"
        run.mkdir()
        (run / "config.yaml").write_text(Experiment.model_validate(TINY).to_yaml())
        (run / LOCK).write_text(json.dumps(lock | {"what": "rlc train"}))
        with pytest.raises(ConfigError, match=f"in use by rlc train on .* \\(pid {holder.pid}"):
            train(resume=run)
    finally:
        holder.kill()
        holder.wait()


@pytest.mark.slow
def test_a_local_sweep_whose_worker_is_killed_finishes_every_run(tmp_path):
    """SIGKILL to the worker training seed 0: its pool breaks, the unfinished runs go to a new pool
    and resume from their checkpoints (the dead worker's lock is taken over); every run finishes, none
    is duplicated. The sibling worker, stopped by the broken pool, does not go on to the queued run
    (which would leave the sweep one worker short until it finished)."""
    import json

    config = dict(
        TINY, algorithm=dict(TINY["algorithm"], total_steps=6144, checkpoint_every=256, eval_every=1024)
    )
    (tmp_path / "long.yaml").write_text(yaml.safe_dump(config))
    out = tmp_path / "sweep"
    command = [sys.executable, "-m", "rlcontroller", "sweep", str(tmp_path / "long.yaml"), "--seeds", "0-2"]
    process = subprocess.Popen(
        [*command, "--workers", "2", "--out", str(out)], stdout=subprocess.PIPE, text=True
    )
    lock, sibling_lock, deadline = out / "seed0" / ".lock", out / "seed1" / ".lock", time.time() + 180

    def holder(path: Path) -> int | None:
        """The pid a lock names, or None while it is absent or still being written (created empty first)."""
        try:
            return json.loads(path.read_text())["pid"]
        except (OSError, ValueError):
            return None

    while not (
        holder(lock) and holder(sibling_lock) and list((out / "seed0" / "checkpoints").glob("step_*"))
    ):
        assert process.poll() is None and time.time() < deadline, process.communicate()[0]
        time.sleep(0.1)
    worker, sibling = holder(lock), holder(sibling_lock)
    subprocess.run(["kill", "-9", str(worker)], check=True)
    holders_of_seed2 = set()
    while process.poll() is None:
        with contextlib.suppress(OSError, ValueError):
            holders_of_seed2.add(json.loads((out / "seed2" / ".lock").read_text())["pid"])
        time.sleep(0.02)
    output, _ = process.communicate(timeout=600)
    assert process.returncode == 0, output
    assert "3 runs done, 0 failed" in output, output
    assert holders_of_seed2 and sibling not in holders_of_seed2, (sibling, holders_of_seed2)
    rows = (out / "sweep.csv").read_text().splitlines()[1:]
    assert len(rows) == 3 and any(",resumed," in row and "seed0" in row for row in rows), rows
    for seed in (0, 1, 2):
        run = out / f"seed{seed}"
        assert (run / "final_model.zip").is_file() and (run / "evaluation" / "metrics.csv").is_file()
        assert not (run / ".lock").exists() and not list(run.glob(".*incomplete*"))
        steps = [
            int(line.split(",")[0]) for line in (run / "learning_curve.csv").read_text().splitlines()[1:]
        ]
        assert steps == sorted(set(steps)), steps  # no row logged twice
    assert sorted(p.name for p in out.iterdir() if p.is_dir()) == ["seed0", "seed1", "seed2"]


@pytest.mark.slow
def test_a_worker_stopped_by_sigterm_before_training_leaves_no_lock(tmp_path):
    """A broken pool SIGTERMs its other workers; one still setting its run up (before training's own
    handler) must release its run's lock on the way out, or the sweep charges that run with the death
    (the soak under load saw every run "worker lost 6 times")."""
    code = (
        "import os, sys, threading, time\n"
        "from pathlib import Path\n"
        "from rlcontroller.files import folder_lock\n"
        "from rlcontroller.multirun.sweep import stop_with_parent\n"
        "stop_with_parent(os.getppid(), threading.Event())\n"
        "with folder_lock(Path(sys.argv[1]), 'rlc train'):\n"
        "    print('locked', flush=True)\n"
        "    time.sleep(60)\n"
    )
    worker = subprocess.Popen([sys.executable, "-c", code, str(tmp_path)], stdout=subprocess.PIPE, text=True)
    assert worker.stdout.readline().strip() == "locked"
    assert (tmp_path / ".lock").is_file()
    worker.terminate()
    assert worker.wait(timeout=30) == 1  # exited, not killed by the signal
    assert not (tmp_path / ".lock").exists()


def test_a_run_waiting_behind_its_dead_worker_s_lock_counts_that_death_once(tmp_path, monkeypatch):
    """A run whose worker died keeps the dead holder's lock while it waits in the queue; pools that
    break meanwhile (other workers dying) must not count that one death again (the soak found runs
    reported "worker lost 6 times" after one death of their own)."""
    import json
    import socket
    from concurrent.futures import Future
    from concurrent.futures.process import BrokenProcessPool

    from rlcontroller.multirun import sweep as sweeping

    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    run = sweeping.SweepRun(tmp_path / "seed0", 0, {}, "tiny", "")
    run.folder.mkdir()
    lock = {
        "host": socket.gethostname(),
        "pid": dead.pid,
        "what": "rlc train",
        "started": "2026-01-01T00:00:00",
    }
    (run.folder / ".lock").write_text(json.dumps(lock))
    pools = []

    class BreakingPool:  # the first 8 pools break before the run starts; the 9th runs it
        def __init__(self, *args, **kwargs):
            pools.append(self)

        def __enter__(self):
            return self

        def __exit__(self, *exception):
            return False

        def submit(self, function, run, records):
            future = Future()
            if len(pools) <= 8:
                future.set_exception(BrokenProcessPool("a worker died"))
            else:
                future.set_result(sweeping.RunResult(run, "resumed", 1.0))
            return future

    monkeypatch.setattr(sweeping, "ProcessPoolExecutor", BreakingPool)
    results = list(sweeping._local([run], None, 2))
    assert [result.status for result in results] == ["resumed"] and len(pools) == 9


@pytest.mark.slow
def test_a_dask_sweep_whose_worker_is_killed_finishes_every_run(tmp_path):
    """SIGKILL to the Dask worker training seed 0: the scheduler gives the run to a worker again, where
    it resumes from its last checkpoint; every run finishes."""
    import json

    pytest.importorskip("distributed")
    config = dict(
        TINY, algorithm=dict(TINY["algorithm"], total_steps=6144, checkpoint_every=256, eval_every=1024)
    )
    (tmp_path / "long.yaml").write_text(yaml.safe_dump(config))
    out = tmp_path / "sweep"
    command = [sys.executable, "-m", "rlcontroller", "sweep", str(tmp_path / "long.yaml"), "--seeds", "0-1"]
    command += ["--engine", "dask", "--workers", "2", "--out", str(out)]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    lock, deadline = out / "seed0" / ".lock", time.time() + 180
    while not (lock.is_file() and list((out / "seed0" / "checkpoints").glob("step_*"))):
        assert process.poll() is None and time.time() < deadline, process.communicate()[0]
        time.sleep(0.1)
    subprocess.run(["kill", "-9", str(json.loads(lock.read_text())["pid"])], check=True)
    output, _ = process.communicate(timeout=600)
    assert process.returncode == 0 and "2 runs done, 0 failed" in output, output
    rows = (out / "sweep.csv").read_text().splitlines()[1:]
    assert any(",resumed," in row and "seed0" in row for row in rows), rows
    for seed in (0, 1):
        assert (out / f"seed{seed}" / "final_model.zip").is_file() and not (
            out / f"seed{seed}" / ".lock"
        ).exists()


@pytest.mark.slow
def test_a_sweep_whose_dask_scheduler_dies_says_so_in_one_line_and_continues_when_run_again(tmp_path):
    """A scheduler of its own (`--address`) killed mid-run: one line, exit 2; the same sweep run again
    (on a local cluster: the worker killed with it left a stale lock) resumes the run."""
    import socket

    pytest.importorskip("distributed")
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    dask = [sys.executable, "-m", "distributed.cli.dask_scheduler"]
    scheduler = subprocess.Popen(
        [*dask, "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    worker_command = [sys.executable, "-m", "distributed.cli.dask_worker", address, "--nthreads", "1"]
    worker = subprocess.Popen(
        [*worker_command, "--no-dashboard"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    config = dict(
        TINY, algorithm=dict(TINY["algorithm"], total_steps=8192, checkpoint_every=256, eval_every=2048)
    )
    (tmp_path / "long.yaml").write_text(yaml.safe_dump(config))
    out = tmp_path / "sweep"
    command = [sys.executable, "-m", "rlcontroller", "sweep", str(tmp_path / "long.yaml"), "--seeds", "0"]
    command += ["--engine", "dask", "--address", address, "--out", str(out)]
    try:
        process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        deadline = time.time() + 180
        while not list((out / "seed0" / "checkpoints").glob("step_*")):
            assert process.poll() is None and time.time() < deadline, process.communicate()
            time.sleep(0.1)
        scheduler.kill()
        _, error = process.communicate(timeout=300)
        lines = [line for line in error.strip().splitlines() if not line.startswith("no --records given")]
        assert process.returncode == 2 and len(lines) == 1 and "lost the Dask scheduler" in lines[0], error
        assert not (out / ".lock").exists()
    finally:
        scheduler.kill()
        worker.kill()
        worker.wait()
    again = subprocess.run(
        command[: command.index("--address")] + ["--out", str(out)], capture_output=True, text=True
    )
    assert again.returncode == 0 and "1 runs done, 0 failed" in again.stdout, again.stderr
    assert ",resumed," in (out / "sweep.csv").read_text()


@pytest.mark.slow
def test_sigint_to_the_sweep_alone_stops_its_worker_with_a_checkpoint_and_starts_nothing_more(tmp_path):
    """`kill -INT` on `rlc sweep` (a job scheduler's stop, not a terminal's Ctrl-C, which reaches every
    process of the group): the worker stops its run as Ctrl-C would, the queued run never starts, and
    the sweep exits instead of training the whole queue first."""
    from rlcontroller.files import lock_pid

    sweep_process, out, workers = long_sweep_training(tmp_path, "0,1")
    os.kill(sweep_process.pid, signal.SIGINT)
    try:
        assert sweep_process.wait(timeout=90) == 130
    finally:  # a sweep that did not stop must not train on after the test (its workers follow it)
        sweep_process.kill()
    assert not any(alive(pid) for pid in workers)
    newest = sorted((out / "seed0" / "checkpoints").glob("step_*"))[-1]
    assert (newest / "state.json").is_file() and lock_pid(out / "seed0") is None
    assert not (out / "seed1" / "checkpoints").exists() and not (out / "seed0" / "final_model.zip").exists()
