"""sbx-rl's learners (`algorithm.backend: sbx`): SAC, TQC and TD3 with their updates compiled by JAX.

sbx-rl (Stable Baselines Jax) keeps stable-baselines3's interface — the vector env, `learn`, callbacks, the
replay buffer — so training, validation and the progress bar are those of any run. What differs is kept here:
building the model, reading its deterministic actor as plain layers (`control.networks.Actor`), and the run
folder's files. sbx's own `save` pickles the whole policy; this backend never writes or reads a pickle:

    learner.npz        every array of the learner's JAX state (the actor's and critics' parameters, target
                       parameters, optimiser moments, the entropy coefficient, the random keys), in the order
                       of its pytree, which a fresh model of the same config rebuilds; counters in
    learner.json replay_buffer.npz the replay buffer's filled rows and its position vecnormalize.npz the
    observation and return statistics (with normalisation)

all read back with `allow_pickle=False`, and checked against the fresh model's shapes.
"""

from __future__ import annotations

import collections
import functools
import json
import warnings
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from rlcontroller.config import ConfigError, Experiment
from rlcontroller.control.networks import Actor, Layer

# JAX warns at every fork once its threads run. rlc forks after training (the check's fan-out, the report's
# drawing process); those children simulate in numpy and never call JAX, which is what the warning is about.
warnings.filterwarnings("ignore", message=r"os\.fork\(\) was called", category=RuntimeWarning)

LEARNER_FILE, LEARNER_COUNTERS = "learner.npz", "learner.json"
REPLAY_FILE, NORMALIZE_FILE = "replay_buffer.npz", "vecnormalize.npz"
REPLAY_ARRAYS = ("observations", "next_observations", "actions", "rewards", "dones", "timeouts")
COUNTERS = ("num_timesteps", "_n_updates", "_episode_num", "reset_idx")
FLAX_TO_NUMPY = {"relu": "ReLU", "tanh": "Tanh", "elu": "ELU", "leaky_relu": "LeakyReLU", "gelu": "GELU"}


def jax_algorithm_class(name: str) -> type:
    """sbx's learner called `name` (SAC, TQC, TD3); a one-line error when sbx-rl is not installed."""
    try:
        import sbx
    except ImportError:
        raise ConfigError(
            "algorithm.backend: sbx needs the sbx-rl package (pip install 'rlcontroller[fast]'), or use "
            "backend: sb3"
        ) from None
    return getattr(sbx, name)


def is_jax_model(model: Any) -> bool:
    return type(model).__module__.startswith("sbx.")


def jax_device() -> str:
    """Where JAX computes, as run.json records it (e.g. "cpu (JAX)")."""
    import jax

    return f"{jax.default_backend()} (JAX)"


def _activation(name: str):
    import flax.linen as nn

    # PyTorch's and the numpy actor's GELU are exact; flax's default is the tanh approximation
    if name == "gelu":
        return functools.partial(nn.gelu, approximate=False)
    return getattr(nn, name)


def jax_policy_kwargs(experiment: Experiment) -> dict[str, Any]:
    """sbx's policy arguments for the experiment's network, as `algorithms.build_model` builds
    stable-baselines3's."""
    policy = experiment.algorithm.policy
    net_arch: list[int] | dict[str, list[int]] = list(policy.net_arch)
    if policy.actor_arch is not None:
        net_arch = {"pi": list(policy.actor_arch), "qf": list(net_arch)}
    kwargs: dict[str, Any] = {"net_arch": net_arch, "activation_fn": _activation(policy.activation)}
    if policy.odd:
        from rlcontroller.learning.jax_odd_actor import OddSquashedGaussianActor

        kwargs["actor_class"] = OddSquashedGaussianActor
    return kwargs


def jax_actor(model) -> Actor:
    """The deterministic actor of an sbx SAC/TQC (tanh of the Gaussian's mean) or TD3 (its tanh output) as
    plain float32 layers: flax's Dense layers in order, the hidden ones followed by the policy's
    activation; odd for `jax_odd_actor.OddSquashedGaussianActor`."""
    policy = model.policy
    params = policy.actor_state.params["params"]
    dense = sorted((name for name in params if name.startswith("Dense_")), key=lambda n: int(n.split("_")[1]))
    hidden = len(policy.net_arch_pi)
    function = policy.activation_fn
    activation = FLAX_TO_NUMPY[getattr(getattr(function, "func", function), "__name__", "")]
    layers = []
    # SAC/TQC: the mean layer; the log-std one after it is noise
    for index, name in enumerate(dense[: hidden + 1]):
        weight = np.asarray(params[name]["kernel"], dtype=np.float32).T.copy()  # flax: (in, out)
        bias = np.asarray(params[name]["bias"], dtype=np.float32).copy()
        layers.append(Layer(weight, bias, activation if index < hidden else None))
    from rlcontroller.learning.jax_odd_actor import OddSquashedGaussianActor

    return Actor(tuple(layers), squash=True, odd=isinstance(policy.actor, OddSquashedGaussianActor))


def _states(model) -> dict[str, Any]:
    """The learner's JAX state by attribute: flax train states and random keys, of the model and its
    policy."""
    from flax.training.train_state import TrainState

    found = {}
    for owner_name, owner in (("model", model), ("policy", model.policy)):
        for name, value in sorted(vars(owner).items()):
            is_key = name in ("key", "noise_key") and hasattr(value, "shape")
            if isinstance(value, TrainState) or is_key:
                found[f"{owner_name}.{name}"] = value
    return found


def _array(leaf) -> np.ndarray:
    """A state's leaf as JAX holds it (a fresh state's step counter is a Python int: int32, as after an
    update)."""
    import jax.numpy as jnp

    return np.asarray(jnp.asarray(leaf))


def _open_npz(path: Path):
    """A .npz archive's arrays, never unpickled (numpy would take any other file for a pickle)."""
    if not zipfile.is_zipfile(path):
        raise ValueError("not a numpy .npz archive")
    return np.load(path, allow_pickle=False)


def save_jax_learner(model, folder: Path) -> None:
    """Write the learner's state, replay buffer and normalisation statistics into `folder` (no pickle)."""
    import jax

    leaves = jax.tree_util.tree_leaves(_states(model))
    np.savez(folder / LEARNER_FILE, *[_array(leaf) for leaf in leaves])
    counters = {name: int(getattr(model, name, 0)) for name in COUNTERS}
    episodes = [{key: float(value) for key, value in info.items()} for info in model.ep_info_buffer or []]
    (folder / LEARNER_COUNTERS).write_text(json.dumps({"counters": counters, "episodes": episodes}) + "\n")
    buffer = model.replay_buffer
    if buffer is not None:
        filled = buffer.buffer_size if buffer.full else buffer.pos
        arrays = {name: getattr(buffer, name)[:filled] for name in REPLAY_ARRAYS}
        np.savez(folder / REPLAY_FILE, pos=np.int64(buffer.pos), full=np.bool_(buffer.full), **arrays)
    normalize = model.get_vec_normalize_env()
    if normalize is not None:
        save_normalization(normalize, folder / NORMALIZE_FILE)


def _statistics(normalize) -> dict[str, Any]:
    """VecNormalize's running statistics by prefix: the observations' (kept only when it normalises them)
    and the returns'."""
    kept = {"ret": normalize.ret_rms}
    return {"obs": normalize.obs_rms} | kept if normalize.norm_obs else kept


def save_normalization(normalize, path: Path) -> None:
    """VecNormalize's running statistics as arrays."""
    arrays = {}
    for prefix, rms in _statistics(normalize).items():
        arrays |= {
            f"{prefix}_mean": rms.mean,
            f"{prefix}_var": rms.var,
            f"{prefix}_count": np.float64(rms.count),
        }
    np.savez(path, **arrays)


def load_normalization(normalize, path: Path) -> None:
    with _open_npz(path) as saved:
        for prefix, rms in _statistics(normalize).items():
            mean, var = saved[f"{prefix}_mean"], saved[f"{prefix}_var"]
            if mean.shape != np.shape(rms.mean) or var.shape != np.shape(rms.var):
                raise ValueError(f"{prefix} statistics of shape {mean.shape}, expected {np.shape(rms.mean)}")
            rms.mean, rms.var = mean.astype(np.float64), var.astype(np.float64)
            rms.count = float(saved[f"{prefix}_count"])


class UnreadableFile(Exception):
    """A checkpoint file that does not load into the fresh model: `path` and the `error` it raised."""

    def __init__(self, path: Path, error: Exception) -> None:
        super().__init__(f"{path}: {error}")
        self.path, self.error = path, error


def load_jax_learner(model, folder: Path) -> None:
    """Restore into `model` (a fresh learner of the same config) what `save_jax_learner` wrote into `folder`;
    a missing file, or one that does not fit the model, is an `UnreadableFile` naming it."""
    files = [(LEARNER_FILE, _load_states), (LEARNER_COUNTERS, _load_counters)]
    if model.replay_buffer is not None:
        files.append((REPLAY_FILE, _load_replay_buffer))
    if model.get_vec_normalize_env() is not None:
        files.append(
            (NORMALIZE_FILE, lambda model, path: load_normalization(model.get_vec_normalize_env(), path))
        )
    for name, load in files:
        try:
            load(model, folder / name)
        except Exception as error:  # a damaged file: zip, json or shape errors of any kind
            raise UnreadableFile(folder / name, error) from None


def _load_states(model, path: Path) -> None:
    import jax
    import jax.numpy as jnp

    leaves, structure = jax.tree_util.tree_flatten(_states(model))
    with _open_npz(path) as saved:
        arrays = [saved[f"arr_{index}"] for index in range(len(saved.files))]
    if len(arrays) != len(leaves):
        raise ValueError(
            f"{len(arrays)} arrays, expected {len(leaves)} for this config's {type(model).__name__}"
        )
    for index, (array, leaf) in enumerate(zip(arrays, leaves, strict=True)):
        expected = _array(leaf)
        if array.shape != expected.shape or array.dtype != expected.dtype:
            raise ValueError(
                f"array {index} is {array.dtype}{list(array.shape)}, expected {expected.dtype}"
                f"{list(expected.shape)}"
            )
    restored = jax.tree_util.tree_unflatten(structure, [jnp.asarray(array) for array in arrays])
    for attribute, value in restored.items():
        owner_name, name = attribute.split(".", 1)
        setattr(model if owner_name == "model" else model.policy, name, value)


def _load_counters(model, path: Path) -> None:
    saved = json.loads(path.read_text())
    for name in COUNTERS:
        setattr(model, name, int(saved["counters"][name]))
    if model.ep_info_buffer is None:  # kept by a learn() that goes on (reset_num_timesteps=False)
        model.ep_info_buffer = collections.deque(maxlen=model._stats_window_size)
        model.ep_success_buffer = collections.deque(maxlen=model._stats_window_size)
    model.ep_info_buffer.extend(dict(info) for info in saved["episodes"])


def _load_replay_buffer(model, path: Path) -> None:
    buffer = model.replay_buffer
    with _open_npz(path) as saved:
        pos, full = int(saved["pos"]), bool(saved["full"])
        for name in REPLAY_ARRAYS:
            target, rows = getattr(buffer, name), saved[name]
            if rows.shape[1:] != target.shape[1:] or len(rows) > len(target):
                raise ValueError(
                    f"replay buffer {name} of shape {rows.shape}, expected at most {target.shape}"
                )
            target[: len(rows)] = rows
    buffer.pos, buffer.full = pos, full
