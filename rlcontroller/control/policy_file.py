"""A trained policy as data: its weights in `.npz`, everything else in YAML; read with numpy alone.

A run or model folder holds, for NAME = best or final, beside the experiment's `config.yaml`:

    NAME_policy.yaml   format and format_version, the learner and its training steps, the network
                       (each layer's activation, tanh squashing, odd symmetry), the observation's
                       size and normalisation (epsilon, clip), the residual prior (none,
                       lqg_ground, lqg_ground_model or lqg_wind_model), the actuators' force limits (N) and
                       the control step (s) it was trained with NAME_policy.npz layer{i}_weight (out, in) and
                       layer{i}_bias (float32); observation_mean and observation_var (normalised
                       observations); prior_feedback (m, estimate) and prior_feedforward (m,) on the scaled
                       observation (residual policies); an MPC law's mpc_phi, mpc_action_gain, mpc_cost_state,
                       mpc_cost_action, mpc_terminal, mpc_strokes

A classical controller is the same data (`kind: classical`, its `law` and how it was `designed`): a
network of one layer with zero weights whose bias is the action — zero for an LQG law, which is then
its prior alone (the LQG gains on the env's own Kalman estimate), the held command for a constant one
(passive-on, passive-off). MPC is LQG + ground model's file with the QP's model, cost and horizon beside
it (`control.mpc.MPCDesign`: `mpc: {horizon: N}` and the mpc_* arrays), solved on the env's Kalman estimate
with LQR's clipped action as its fallback. The reader checks that it is exactly that, so evaluate and check
treat it like a learned policy and it acts as its law; export refuses MPC (a QP is not an ONNX graph).

Reading never unpickles (`np.load(..., allow_pickle=False)`, `yaml.safe_load`) and imports neither
torch nor stable-baselines3: a controller from someone else is data, never code. The actor is the
deterministic one: PPO/A2C's Gaussian mean, SAC's tanh-squashed mean, TD3's output.
"""

from __future__ import annotations

import io
import zipfile
from pathlib import Path

import numpy as np
import yaml

from rlcontroller.config import ConfigError
from rlcontroller.control.classical import LAWS, MPC_ARRAYS, classical_law, mpc_from_file, prior_kind
from rlcontroller.control.controllers import LQGPrior
from rlcontroller.control.networks import ACTIVATIONS, Actor, Layer, Normalizer
from rlcontroller.control.policy_controller import PolicyController
from rlcontroller.files import atomic_write
from rlcontroller.physics.plant import Plant
from rlcontroller.untrusted import npz_headers, read_npz, safe_yaml

FORMAT = "rlcontroller-policy"
FORMAT_VERSION = 1
MODELS = ("best", "final")
PRIORS = ("none", "lqg_ground", "lqg_ground_model", "lqg_wind_model")


def policy_paths(folder: Path, model: str) -> tuple[Path, Path]:
    """The YAML and the weights of the saved `model` (best or final) of a run or model folder."""
    if model not in MODELS:
        raise ConfigError(f"--model: expected best or final, got {model!r}")
    return folder / f"{model}_policy.yaml", folder / f"{model}_policy.npz"


def write_policy(controller: PolicyController, plant: Plant, folder: Path, model: str) -> Path:
    """Save `controller` (trained on `plant`'s experiment) as `model`_policy.yaml/.npz in `folder`."""
    description, weights = policy_data(controller, plant)
    meta_path, weights_path = policy_paths(folder, model)
    buffer = io.BytesIO()
    np.savez(buffer, **weights)
    atomic_write(weights_path, buffer.getvalue())
    atomic_write(meta_path, yaml.safe_dump(description, sort_keys=False))
    return meta_path


def policy_data(controller: PolicyController, plant: Plant) -> tuple[dict, dict[str, np.ndarray]]:
    """The YAML mapping and the arrays that describe `controller` completely."""
    actor, normalizer = controller.actor, controller.normalizer
    weights: dict[str, np.ndarray] = {}
    for index, layer in enumerate(actor.layers):
        weights[f"layer{index}_weight"] = layer.weight.astype(np.float32)
        weights[f"layer{index}_bias"] = layer.bias.astype(np.float32)
    description = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        **(
            {"kind": "classical", "law": controller.law, "designed": controller.designed}
            if controller.law
            else {}
        ),
        "algorithm": controller.algorithm,
        "training_steps": int(controller.steps),
        "network": {
            "activations": [layer.activation for layer in actor.layers],
            "squash": bool(actor.squash),
            "odd": bool(actor.odd),
        },
        "observation": {"size": int(plant.layout.size), "normalize": normalizer is not None},
        "prior": "none" if controller.prior is None else prior_kind(plant),
        "actions": int(plant.building.n_actuators),
        "force_limits_N": [float(f) for f in plant.force_limits],
        "control_dt_s": float(plant.control_dt),
    }
    if normalizer is not None:
        description["observation"] |= {"epsilon": float(normalizer.epsilon), "clip": float(normalizer.clip)}
        weights |= {
            "observation_mean": np.asarray(normalizer.mean),
            "observation_var": np.asarray(normalizer.var),
        }
    if controller.prior is not None:
        weights |= {
            "prior_feedback": controller.prior.feedback,
            "prior_feedforward": controller.prior.feedforward,
        }
    if controller.mpc is not None:
        design = controller.mpc.design
        description["mpc"] = {"horizon": design.horizon}
        weights |= {f"mpc_{key}": np.asarray(getattr(design, key), dtype=float) for key in MPC_ARRAYS}
    return description, weights


def read_policy(folder: Path, model: str, plant: Plant, name: str = "RL") -> PolicyController:
    """The saved `model` of `folder` as a controller for `plant` (the folder's experiment), checked
    against it; a missing, damaged or mismatched file is a one-line `ConfigError`."""
    meta_path, weights_path = policy_paths(folder, model)
    if not meta_path.is_file():
        zipped = folder / f"{model}_model.zip"
        hint = (
            f"; {zipped.name} is a stable-baselines3 file, which can run its author's code when opened: "
            f"if you trust who made it, convert it once with 'rlc convert {folder} --trust-pickle'"
            if zipped.is_file()
            else "; expected a run folder written by 'rlc train' or a model folder"
        )
        raise ConfigError(f"{folder}: no {meta_path.name}{hint}")
    description = _read_yaml(meta_path)
    try:
        weights = _read_npz(weights_path, description, plant)
        controller = _controller(description, weights, plant, name)
        if controller.law is not None and name == "RL":  # beside the evaluation's own classical rows
            controller.name = f"{LAWS[controller.law]} ({folder.resolve().name})"
    except ConfigError:  # names the weights file
        raise
    except KeyError as error:
        raise ConfigError(f"{meta_path}: not a valid policy (missing {error.args[0]!r})") from None
    except TypeError as error:
        raise ConfigError(f"{meta_path}: not a valid policy (a value of the wrong kind: {error})") from None
    except ValueError as error:
        raise ConfigError(f"{meta_path}: not a valid policy ({error})") from None
    controller.source = str(meta_path)
    return controller


KEYS = {
    "": {
        "format",
        "format_version",
        "algorithm",
        "training_steps",
        "network",
        "observation",
        "prior",
        "actions",
        "force_limits_N",
        "control_dt_s",
        "kind",
        "law",
        "designed",
        "mpc",
    },
    "network": {"activations", "squash", "odd"},
    "mpc": {"horizon"},
    "observation": {"size", "normalize", "epsilon", "clip"},
}


def _read_yaml(path: Path) -> dict:
    try:
        description = safe_yaml(path.read_text(encoding="utf-8"))
    except (yaml.YAMLError, UnicodeDecodeError) as error:
        detail = str(error) if "aliases" in str(error) else type(error).__name__
        raise ConfigError(f"{path}: not readable YAML ({detail})") from None
    if not isinstance(description, dict) or description.get("format") != FORMAT:
        raise ConfigError(f"{path}: not an rlcontroller policy (expected 'format: {FORMAT}')")
    if description.get("format_version") != FORMAT_VERSION:
        raise ConfigError(
            f"{path}: format_version {description.get('format_version')!r}; this rlc reads version "
            f"{FORMAT_VERSION}"
        )
    for section, known in KEYS.items():
        mapping = description.get(section) if section else description
        unknown = sorted(map(str, set(mapping) - known)) if isinstance(mapping, dict) else []
        if unknown:
            where = f"{section}." if section else ""
            raise ConfigError(
                f"{path}: unknown key {where}{unknown[0]} (expected {', '.join(sorted(known))})"
            )
    return description


def _read_npz(path: Path, description: dict, plant: Plant) -> dict[str, np.ndarray]:
    """The weights, once every array's shape and dtype, read from its header, is what `description`
    declares for `plant` (ValueError naming the array otherwise; nothing unknown, nothing larger)."""
    if not path.is_file():
        raise ConfigError(f"{path}: missing (the policy's weights)")
    try:
        headers = npz_headers(path)
    except (OSError, EOFError, zipfile.BadZipFile) as error:
        detail = (str(error).splitlines() or [""])[0][:120] or type(error).__name__
        raise ConfigError(f"{path}: not readable weights ({detail})") from None
    except ValueError as error:
        raise ConfigError(f"{path}: {error}") from None
    expected = _declared_arrays(headers, description, plant)
    unknown = sorted(set(headers) - set(expected))
    if unknown:
        raise ConfigError(f"{path}: unknown array {unknown[0]} (the policy declares {', '.join(expected)})")
    for key, shape in expected.items():
        if key not in headers:
            raise ConfigError(f"{path}: no array {key} (the policy declares it)")
        if headers[key][0] != shape or headers[key][1].kind != "f":
            found = f"{headers[key][0]} of {headers[key][1]}"
            raise ConfigError(
                f"{path}: {key} is {found}, the policy declares {shape} of floating-point numbers"
            )
    try:
        weights = read_npz(path)
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as error:
        detail = (str(error).splitlines() or [""])[0][:120] or type(error).__name__
        raise ConfigError(f"{path}: not readable weights ({detail})") from None
    for key, array in weights.items():
        if not np.all(np.isfinite(array)):
            raise ConfigError(f"{path}: {key}: expected finite floating-point numbers")
    return weights


def _declared_arrays(
    headers: dict[str, tuple[tuple[int, ...], np.dtype]], description: dict, plant: Plant
) -> dict[str, tuple[int, ...]]:
    """The arrays `description` declares and their shapes for `plant`: the layers chained from the
    observation to the actions (hidden widths as the weights' headers give them), the normalisation, the
    prior."""
    activations = description["network"]["activations"]
    if not isinstance(activations, list) or not activations:
        raise ValueError("network.activations: expected a list, one activation per layer")
    size, m = plant.layout.size, plant.building.n_actuators
    estimate = plant.layout.estimate.stop - plant.layout.estimate.start

    def leading(key: str) -> int:
        """The first dimension of array `key` as its header gives it (0 if absent or of rank 0): a count the
        file itself sets (hidden widths, cost rows); a wrong rank fails the comparison below."""
        shape = headers.get(key, ((), None))[0]
        return shape[0] if shape else 0

    expected, width = {}, size
    for index in range(len(activations)):
        outputs = leading(f"layer{index}_weight")
        expected |= {f"layer{index}_weight": (outputs, width), f"layer{index}_bias": (outputs,)}
        width = outputs
    if width != m:
        raise ValueError(f"the network gives {width} actions, expected {m}")
    if description["observation"]["normalize"]:
        expected |= {"observation_mean": (size,), "observation_var": (size,)}
    if description["prior"] != "none":
        expected |= {"prior_feedback": (m, estimate), "prior_feedforward": (m,)}
    if description.get("mpc") is not None:
        costs, strokes = leading("mpc_cost_state"), leading("mpc_strokes")
        if not 1 <= costs <= 10 * (estimate + m) or strokes > m:
            raise ValueError(
                f"mpc: {costs} cost rows and {strokes} stroke rows; expected 1 to "
                f"{10 * (estimate + m)} and at most {m}"
            )
        expected |= {
            "mpc_phi": (estimate, estimate),
            "mpc_action_gain": (estimate, m),
            "mpc_cost_state": (costs, estimate),
            "mpc_cost_action": (costs, m),
            "mpc_terminal": (estimate, estimate),
            "mpc_strokes": (strokes, estimate),
        }
    return expected


def _controller(
    description: dict, weights: dict[str, np.ndarray], plant: Plant, name: str
) -> PolicyController:
    network, observation = description["network"], description["observation"]
    size, m = plant.layout.size, plant.building.n_actuators
    if observation["size"] != size or description["actions"] != m:
        raise ValueError(
            f"observation size {observation['size']} and {description['actions']} actions; "
            f"the folder's config.yaml gives {size} and {m}"
        )
    if not np.allclose(description["force_limits_N"], plant.force_limits, rtol=1e-12, atol=0.0):
        raise ValueError("force_limits_N differ from the folder's config.yaml")
    if not np.isclose(float(description["control_dt_s"]), plant.control_dt, rtol=1e-9, atol=0.0):
        raise ValueError(
            f"control_dt_s {description['control_dt_s']!r}: the folder's config.yaml steps every "
            f"{plant.control_dt:g} s"
        )
    layers = []
    for index, activation in enumerate(network["activations"]):
        if activation is not None and activation not in ACTIVATIONS:
            raise ValueError(f"network.activations: unknown {activation!r}")
        weight, bias = weights[f"layer{index}_weight"], weights[f"layer{index}_bias"]  # shapes checked
        layers.append(Layer(weight.astype(np.float32), bias.astype(np.float32), activation))
    actor = Actor(tuple(layers), bool(network["squash"]), bool(network["odd"]))
    normalizer = None
    if observation["normalize"]:
        mean, var = weights["observation_mean"], weights["observation_var"]
        if np.any(var < 0):
            raise ValueError("observation_var: expected values >= 0")
        epsilon, clip = float(observation["epsilon"]), float(observation["clip"])
        if not (np.isfinite(epsilon) and np.isfinite(clip) and epsilon > 0.0 and clip > 0.0):
            raise ValueError(
                f"observation epsilon {epsilon!r} and clip {clip!r}: expected finite positive numbers"
            )
        normalizer = Normalizer(mean, var, epsilon, clip)
    prior = None
    if description["prior"] not in PRIORS:
        raise ValueError(f"prior: expected one of {', '.join(PRIORS)}")
    if description["prior"] != "none":
        if not plant.experiment.sensors.state_estimate or description["prior"] != prior_kind(plant):
            raise ValueError(
                f"prior {description['prior']!r} does not match the folder's config.yaml sensors"
            )
        feedback, feedforward = weights["prior_feedback"], weights["prior_feedforward"]
        prior = LQGPrior(feedback, feedforward, plant.layout)
    steps = description["training_steps"]
    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 0:
        raise ValueError(f"training_steps {steps!r}: expected a whole number of steps, 0 or more")
    law = classical_law(description, actor, normalizer, prior)
    mpc = None if law != "mpc" else mpc_from_file(description["mpc"], weights, plant, prior)
    return PolicyController(
        actor,
        normalizer,
        prior,
        name,
        steps=steps,
        algorithm=str(description["algorithm"]),
        law=law,
        designed=str(description.get("designed", "")),
        mpc=mpc,
    )
