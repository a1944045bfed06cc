"""Tuning: two workers share one study and together run exactly the trials asked, a killed worker's
trial is marked failed and the study still reaches its count, and the outputs are written."""

import os
import re
import signal
import subprocess
import sys
import time

import optuna
import pytest
import yaml
from conftest import REPOSITORY
from optuna.trial import TrialState

from rlcontroller.config import Experiment, SearchRange
from rlcontroller.multirun.tuning import storage, suggest

# a run of a few seconds
TINY = yaml.safe_load((REPOSITORY / "configs" / "testing" / "tiny.yaml").read_text())
SEARCH = {
    "algorithm.kwargs.learning_rate": {"low": 1.0e-5, "high": 1.0e-2, "log": True},
    "algorithm.kwargs.gamma": {"low": 0.9, "high": 0.999},
    "algorithm.policy.net_arch": {"choices": [[16], [8, 8]]},
}
TUNED = TINY | {"name": "tuned", "algorithm": TINY["algorithm"] | {"search": SEARCH}}


def tune_command(config, out, trials):
    return [
        sys.executable,
        "-m",
        "rlcontroller",
        "tune",
        str(config),
        "--trials",
        str(trials),
        "--out",
        str(out),
    ]


def study_trials(out):
    try:
        study = optuna.load_study(study_name="tuned", storage=storage(None, out))
    except KeyError:  # the journal exists, the study not yet
        return []
    return [t for t in study.get_trials(deepcopy=False) if not t.user_attrs.get("surplus")]


def test_the_search_space_is_checked_and_sampled():
    with pytest.raises(ValueError, match="low < high"):
        SearchRange(low=1.0, high=1.0)
    with pytest.raises(ValueError, match="log range needs low > 0"):
        SearchRange(low=0.0, high=1.0, log=True)
    with pytest.raises(ValueError, match="either choices or low and high"):
        SearchRange(low=0.0, high=1.0, choices=[1])
    space = Experiment.model_validate(TUNED).algorithm.search
    trial = optuna.create_study().ask()
    values = suggest(trial, space)
    assert 1e-5 <= values["algorithm.kwargs.learning_rate"] <= 1e-2 and values[
        "algorithm.policy.net_arch"
    ] in (
        [16],
        [8, 8],
    )


@pytest.mark.slow
def test_two_workers_on_one_study_run_exactly_the_trials_asked(tmp_path):
    config = tmp_path / "tuned.yaml"
    config.write_text(yaml.safe_dump(TUNED))
    out = tmp_path / "study"
    workers = [
        subprocess.Popen(
            tune_command(config, out, 6), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        )
        for _ in range(2)
    ]
    outputs = [worker.communicate(timeout=600) for worker in workers]
    assert [worker.returncode for worker in workers] == [0, 0], outputs
    assert all(re.search(r"trial \d+: .*; \d+ of 6 trials done", stderr) for _, stderr in outputs)  # progress
    trials = study_trials(out)
    finished = [t for t in trials if t.state in (TrialState.COMPLETE, TrialState.PRUNED)]
    assert len(finished) == 6 and not [t for t in trials if t.state == TrialState.RUNNING]
    assert len({t.number for t in finished}) == 6 and len({t.user_attrs["run_dir"] for t in finished}) == 6
    ran = sum(int(stdout.split()[0]) for stdout, _ in outputs)
    assert ran >= 6
    best = yaml.safe_load((out / "best.yaml").read_text())
    assert (
        best["algorithm"]["kwargs"]["learning_rate"]
        == min((t for t in finished if t.state == TrialState.COMPLETE), key=lambda t: t.value).params[
            "algorithm.kwargs.learning_rate"
        ]
    )
    assert {"trials.csv", "best.yaml", "optimization_history.png", "param_importances.png"} <= {
        p.name for p in out.iterdir()
    }


@pytest.mark.slow
def test_a_killed_worker_s_trial_is_marked_failed_and_the_study_still_completes(tmp_path):
    slow = TUNED | {"algorithm": TUNED["algorithm"] | {"total_steps": 100_000, "eval_every": 100_000}}
    config = tmp_path / "tuned.yaml"
    config.write_text(yaml.safe_dump(slow))
    out = tmp_path / "study"
    victim = subprocess.Popen(
        tune_command(config, out, 2), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        if (out / "study.journal").exists() and any(t.state == TrialState.RUNNING for t in study_trials(out)):
            break
        time.sleep(0.5)
    else:
        victim.kill()
        pytest.fail("no trial started within two minutes")
    os.kill(victim.pid, signal.SIGKILL)
    victim.wait()
    quick = tmp_path / "quick.yaml"
    quick.write_text(yaml.safe_dump(TUNED))  # same study, short trials from now on
    done = subprocess.run(tune_command(quick, out, 2), capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    trials = study_trials(out)
    assert trials[0].state == TrialState.FAIL  # the killed worker's trial, not left running
    assert sum(t.state in (TrialState.COMPLETE, TrialState.PRUNED) for t in trials) == 2
    assert not [t for t in trials if t.state == TrialState.RUNNING]


@pytest.mark.slow
def test_a_config_without_a_search_space_is_refused(tmp_path):
    config = tmp_path / "plain.yaml"
    config.write_text(yaml.safe_dump({k: v for k, v in TUNED.items() if k != "algorithm"}))
    done = subprocess.run(tune_command(config, tmp_path / "out", 2), capture_output=True, text=True)
    assert done.returncode == 2 and "search: empty" in done.stderr and "Traceback" not in done.stderr
