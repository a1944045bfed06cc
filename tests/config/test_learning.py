"""The learner's settings are checked when an experiment is loaded, against a table of each learner's
keyword arguments that must match the installed learners' signatures; loading imports no torch."""

import inspect
import subprocess
import sys

import pytest
from conftest import REPOSITORY

from rlcontroller.config import ConfigError, build_experiment
from rlcontroller.config.learning import JAX_LEARNER_KWARGS, LEARNER_KWARGS


@pytest.mark.parametrize(
    ("backend", "name"),
    [("sb3", name) for name in sorted(LEARNER_KWARGS)] + [("sbx", n) for n in JAX_LEARNER_KWARGS],
)
def test_the_table_of_keyword_arguments_is_the_learners_own(backend, name):
    from rlcontroller.learning.sb3_models import algorithm_class

    if backend == "sbx":
        pytest.importorskip("sbx")
    signature = set(inspect.signature(algorithm_class(name, backend).__init__).parameters) - {"self"}
    assert (JAX_LEARNER_KWARGS if backend == "sbx" else LEARNER_KWARGS)[name] == signature


@pytest.mark.parametrize(
    ("algorithm", "message"),
    [
        (
            {"name": "PPO", "kwargs": {"buffer_size": 10}},
            "algorithm.kwargs.buffer_size: not a keyword argument of PPO",
        ),
        (
            {"name": "PPO", "kwargs": {"gama": 0.9}},
            "algorithm.kwargs.gama: not a keyword argument of PPO; did you mean 'gamma'?",
        ),
        (
            {"name": "SAC", "kwargs": {"gamma": 1.5}},
            "algorithm.kwargs.gamma: expected a number in [0.0, 1.0]",
        ),
        ({"name": "SAC", "kwargs": {"seed": 3}}, "algorithm.kwargs.seed: set by rlc"),
        (
            {"name": "SAC", "policy": {"odd": True}},
            "algorithm.policy.odd: only for PPO, A2C, RandomSearch, and SAC or TQC with backend: sbx",
        ),
        (
            {"name": "SAC", "backend": "sbx", "kwargs": {"param_resets": "yes"}},
            "algorithm.kwargs.param_resets: expected a list of time steps (whole numbers >= 0), got 'yes'",
        ),
        (
            {"name": "SAC", "backend": "sbx", "kwargs": {"param_resets": [1000, True]}},
            "algorithm.kwargs.param_resets: expected a list of time steps",
        ),
        (
            {"name": "RandomSearch", "policy": {"actor_arch": [8], "odd": True}, "vec_env": "dummy"},
            "algorithm.vec_env: not for RandomSearch",
        ),
    ],
)
def test_what_a_learner_refuses_is_refused_at_loading(algorithm, message):
    with pytest.raises(ConfigError) as error:
        build_experiment({"algorithm": algorithm})
    assert str(error.value).startswith(f"<config>: {message}") and "\n" not in str(error.value)


def test_loading_and_checking_an_experiment_imports_no_torch():
    code = (
        "import sys\nfrom rlcontroller.config import load_experiment\n"
        f"load_experiment({str(REPOSITORY / 'configs' / 'five_story.yaml')!r})\n"
        "print(sorted(m for m in ('torch', 'stable_baselines3') if m in sys.modules))"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "[]"
