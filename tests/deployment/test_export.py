"""The exported ONNX controller, run by onnxruntime in the loop, gives the Python controller's forces
on whole records: the committed residual policy (Kalman estimate, LQG prior) and a SAC policy with an
observation normaliser, a sensor history and the last two actions."""

import hashlib
import subprocess
import sys

import numpy as np
import onnx
import pytest
from conftest import NETWORK_POLICY, REPOSITORY
from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

from rlcontroller.cli import DEFAULT_MODEL
from rlcontroller.config import ConfigError, Experiment, load_experiment
from rlcontroller.control.policy_file import read_policy
from rlcontroller.deployment.export import controller_graph, export_onnx
from rlcontroller.deployment.runtime import OnnxController, graph_deviation
from rlcontroller.learning.env import BuildingEnv, rollout
from rlcontroller.learning.sb3_models import algorithm_class, policy_controller
from rlcontroller.physics.motions.excitation import Load
from rlcontroller.physics.motions.records import synthetic_suite
from rlcontroller.physics.plant import Plant

COMMITTED = NETWORK_POLICY


def onnx_rollout(plant: Plant, path, motion, seed: int) -> np.ndarray:
    """Forces (N) held over each step when the exported controller drives the env."""
    env = BuildingEnv(plant)
    layout = plant.layout
    controller = OnnxController(path)
    observation, info = env.reset(seed=seed, options={"motion": motion})
    forces = [np.zeros(plant.building.n_actuators)]
    for _ in range(info["steps"]):
        readings = observation[layout.readings].astype(float) * layout.reading_scale
        ground = np.array([[float(observation[layout.ground]) * layout.ground_scale]])
        force = controller.step(readings[None], ground)[0]
        observation, *_ = env.step(force / plant.force_limits)
        forces.append(env.command)
    return np.array(forces)


def assert_same_forces(plant, python_controller, path, motions):
    """The env supervises the Python controller; the exported graph carries its own supervisor, so it
    drives the same building without one."""
    env = BuildingEnv(plant)
    unsupervised = Plant(plant.experiment.model_copy(update={"supervisor": None}))
    for seed, motion in enumerate(motions):
        expected, _ = rollout(env, motion, python_controller, seed=seed)
        actual = onnx_rollout(unsupervised, path, motion, seed)
        scale = np.abs(expected.force).max()
        assert scale > 1e3  # the controller acts
        np.testing.assert_allclose(actual, expected.force, rtol=0.0, atol=1e-4 * scale)


@pytest.mark.slow
def test_the_committed_policy_exported_gives_the_python_forces(tmp_path):
    path = export_onnx(COMMITTED, "best", tmp_path / "controller.onnx")
    plant = Plant(load_experiment(COMMITTED / "config.yaml"))
    assert_same_forces(plant, read_policy(COMMITTED, "best", plant), path, synthetic_suite(count=2))
    metadata = {prop.key: prop.value for prop in onnx.load(path).metadata_props}
    assert metadata["control_dt_s"] == "0.02" and metadata["actuator_stories"] == "1, 3, 5"
    assert metadata["readings"].startswith("absolute_acceleration floor 1 (m/s^2)")
    digest = hashlib.sha256((COMMITTED / "best_policy.npz").read_bytes()).hexdigest()
    assert metadata["source"] == f"retired_five_story/best_policy.npz (sha256 {digest})"
    assert str(REPOSITORY) not in onnx.load(path).SerializeToString().decode("latin-1")  # no local path


def with_supervisor(tmp_path, supervisor: dict):
    """A copy of the default model behind another supervisor (its LQG law does not depend on it)."""
    import shutil

    import yaml

    folder = tmp_path / "model"
    shutil.copytree(DEFAULT_MODEL, folder)
    config = yaml.safe_load((folder / "config.yaml").read_text())
    (folder / "config.yaml").write_text(yaml.safe_dump(config | {"supervisor": supervisor}))
    return folder


@pytest.mark.slow
def test_a_supervised_policy_exports_with_its_supervisor(tmp_path):
    """Behind the standard trigger and the hard dissipative rule the graph applies both (same forces as
    the supervised env, zero at rest), and its metadata says so."""
    folder = with_supervisor(tmp_path, {"trigger": [0.25, 1.0], "dissipative": True})
    plant = Plant(load_experiment(folder / "config.yaml"))
    path = export_onnx(folder, "best", tmp_path / "controller.onnx")
    assert_same_forces(plant, read_policy(folder, "best", plant), path, synthetic_suite(count=2))
    still = Load("at rest", plant.control_dt, np.zeros(1001), synthetic=True)
    forces = onnx_rollout(Plant(plant.experiment.model_copy(update={"supervisor": None})), path, still, 0)
    assert np.all(forces == 0.0)
    metadata = {prop.key: prop.value for prop in onnx.load(path).metadata_props}
    assert (
        metadata["supervisor"] == "trigger 0.25-1 m/s^2 on the peak ground reading; dissipative forces only"
    )


def test_the_default_exports_with_its_faded_supervisor(tmp_path):
    """The graph fades a force that feeds energy in as the env's supervisor does: fed the readings the
    supervised env gave the Python controller, it gives that step's force. The graph's filter reads the
    float32 readings the observation holds, so its estimate differs from the env's by about 1e-5 m/s;
    the fade (force / 0.1 m/s per m/s) turns that into up to 1e-4 of the force (a missing or misscaled
    fade differs by up to the whole force). In the closed loop such differences grow over a record, where
    the hard rule masks them."""
    plant = Plant(load_experiment(DEFAULT_MODEL / "config.yaml"))
    assert plant.experiment.supervisor.fade_velocity == 0.1
    path = export_onnx(DEFAULT_MODEL, "best", tmp_path / "controller.onnx")
    env, layout, graph = BuildingEnv(plant), plant.layout, OnnxController(path)
    controller = read_policy(DEFAULT_MODEL, "best", plant)
    observation, info = env.reset(seed=0, options={"motion": synthetic_suite(count=1)[0]})
    python, onnx_forces, faded = [], [], 0
    for _ in range(info["steps"]):
        readings = observation[layout.readings].astype(float) * layout.reading_scale
        ground = np.array([[float(observation[layout.ground]) * layout.ground_scale]])
        onnx_forces.append(graph.step(readings[None], ground)[0])
        action = controller.act(observation)
        observation, *_ = env.step(action)
        python.append(env.command)
        faded += np.sum((np.abs(env.command) > 1.0) & (np.abs(env.command) < 0.99 * np.abs(action) * 1e5))
    python, onnx_forces = np.array(python), np.array(onnx_forces)
    assert faded > 10  # forces the supervisor scaled (trigger or fade), not cut
    np.testing.assert_allclose(onnx_forces, python, rtol=0.0, atol=3e-4 * np.abs(python).max())
    metadata = {prop.key: prop.value for prop in onnx.load(path).metadata_props}
    assert metadata["supervisor"] == (
        "trigger 0.15-0.6 m/s^2 on the peak ground reading; "
        "forces feeding energy in faded out by 0.1 m/s of stroke velocity"
    )


def lockstep(plant: Plant, path, controller, motions, watch) -> tuple[np.ndarray, np.ndarray, list]:
    """The supervised env's forces, the graph's fed the same readings, and `watch(env)` after each step."""
    env, layout, graph = BuildingEnv(plant), plant.layout, OnnxController(path)
    python, onnx_forces, watched = [], [], []
    for seed, motion in enumerate(motions):
        observation, info = env.reset(seed=seed, options={"motion": motion})
        controller.reset()
        graph.reset()
        for _ in range(info["steps"]):
            readings = observation[layout.readings].astype(float) * layout.reading_scale
            ground = np.array([[float(observation[layout.ground]) * layout.ground_scale]])
            onnx_forces.append(graph.step(readings[None], ground)[0])
            observation, *_ = env.step(controller.act(observation))
            python.append(env.command)
            watched.append(watch(env))
    return np.array(python), np.array(onnx_forces), watched


def test_runtime_assurance_exports_with_its_twin(tmp_path):
    """Behind runtime assurance the graph carries the fail-safe twin and the switch: fed the readings the
    supervised env gave the Python controller, it gives that step's force, through hand-overs both ways."""
    supervisor = {
        "trigger": [0.1, 0.3],
        "dissipative": True,
        "fade_velocity": 0.1,
        "assurance": {"engage": 0.95},
    }
    folder = with_supervisor(tmp_path, supervisor)
    plant = Plant(load_experiment(folder / "config.yaml"))
    path = export_onnx(folder, "best", tmp_path / "controller.onnx")
    controller = read_policy(folder, "best", plant)
    python, onnx_forces, engaged = lockstep(
        plant, path, controller, synthetic_suite(count=2), lambda env: env.supervisor.assurance.engaged[0]
    )
    assert 0.02 < 1.0 - np.mean(engaged) < 0.98  # the switch handed the devices back and forth
    np.testing.assert_allclose(onnx_forces, python, rtol=0.0, atol=3e-4 * np.abs(python).max())
    metadata = {prop.key: prop.value for prop in onnx.load(path).metadata_props}
    assert "runtime assurance against the fail-safe twin (release 1, engage 0.95)" in metadata["supervisor"]


def test_the_dampers_fallback_exports_with_its_measured_velocities(tmp_path):
    """Behind the measured dissipative rule and the dampers' fallback the graph integrates the stroke
    velocities and latches as the env's supervisor does: fed the same readings, the same force each step,
    before and after the hand-over."""
    fallback = {"drift": 0.01, "damping": [3.0e5, 3.0e5, 1.5e5, 1.0e5, 0.5e5], "deadband": 0.01}
    folder = with_supervisor(
        tmp_path,
        {"trigger": [0.25, 1.0], "dissipative": "measured", "fade_velocity": 0.1, "fallback": fallback},
    )
    plant = Plant(load_experiment(folder / "config.yaml"))
    path = export_onnx(folder, "best", tmp_path / "controller.onnx")
    controller = read_policy(folder, "best", plant)
    python, onnx_forces, latched = lockstep(
        plant, path, controller, synthetic_suite(count=1), lambda env: env.supervisor.fallback.latched[0]
    )
    assert 0.05 < np.mean(latched) < 0.95  # both the controller and the dampers acted
    np.testing.assert_allclose(onnx_forces, python, rtol=0.0, atol=3e-4 * np.abs(python).max())
    metadata = {prop.key: prop.value for prop in onnx.load(path).metadata_props}
    assert (
        "past 0.01 m of estimated story drift, dampers on measured stroke velocity" in metadata["supervisor"]
    )


@pytest.mark.slow
def test_the_76_story_damper_controller_exports_and_acts_as_in_python(tmp_path):
    """The 76-story building's LQG + wind model with loop transfer recovery (the design that passed the wind
    standard alone, docs/wind.md) exports; under a generated wind load its graph gives the forces the Python
    controller commands in the env, within 1e-3 of their peak (the check `export_onnx` makes itself, here over
    a whole minute of wind and another seed). CI runs it under two BLAS kernels."""
    from rlcontroller import api

    config = REPOSITORY / "studies" / "safety_check" / "seventy_six_story_atmd_stroke_weighted.yaml"
    folder = api.design(config, "lqg_wind_model", tmp_path / "atmd")
    plant = Plant(load_experiment(folder / "config.yaml", self_contained=True))
    path = export_onnx(folder, "best", tmp_path / "controller.onnx")
    deviation, peak = graph_deviation(
        plant, read_policy(folder, "best", plant), path.read_bytes(), seed=1, steps=600
    )
    assert peak > 1e4 and deviation <= 1e-3  # the driver works (N), and as in Python


@pytest.mark.slow
def test_the_shipped_wind_controller_exports_with_its_floor_trigger(tmp_path, monkeypatch):
    """Named by its experiment from another folder, the five-story wind controller (the learned MPC on LQG +
    wind and ground model's estimate, behind a trigger on the floors' accelerations) exports; its graph gives
    the env's forces under a generated wind load, within 1e-3 of their peak, and the metadata names what the
    trigger watches."""
    from rlcontroller import api

    monkeypatch.chdir(tmp_path)
    folder = api.model_folder(REPOSITORY / "configs" / "experiments" / "five_story_wind.yaml")
    assert folder.name == "five_story_wind"
    plant = Plant(load_experiment(folder / "config.yaml", self_contained=True))
    path = export_onnx(folder, "best", tmp_path / "controller.onnx")
    deviation, peak = graph_deviation(
        plant, read_policy(folder, "best", plant), path.read_bytes(), seed=2, steps=600
    )
    assert peak > 1e4 and deviation <= 1e-3
    metadata = {prop.key: prop.value for prop in onnx.load(path).metadata_props}
    assert metadata["supervisor"] == "trigger 0.3-1 m/s^2 on the peak floor acceleration readings"


def test_an_export_that_would_not_act_as_in_python_is_refused_in_one_line(tmp_path, monkeypatch):
    from rlcontroller.deployment import export

    monkeypatch.setattr(export, "FAITHFUL", -1.0)  # every graph deviates by more
    with pytest.raises(
        ConfigError, match=r"its ONNX graph's forces differ from the Python controller's by"
    ) as error:
        export_onnx(DEFAULT_MODEL, "best", tmp_path / "controller.onnx")
    assert "\n" not in str(error.value) and not (tmp_path / "controller.onnx").exists()


@pytest.mark.slow
def test_a_normalised_sac_policy_with_a_history_exports_too(tmp_path):
    import torch

    experiment = Experiment.model_validate(
        {"sensors": {"history": 3, "action_history": 2}, "algorithm": {"name": "SAC"}}
    )
    plant = Plant(experiment)
    model = algorithm_class("SAC")(
        "MlpPolicy", BuildingEnv(plant), policy_kwargs={"net_arch": [64, 64]}, seed=0
    )
    with torch.no_grad():  # a policy that acts strongly, so that forces are worth comparing
        model.policy.actor.mu.weight.mul_(30.0)
    normalize = VecNormalize(DummyVecEnv([lambda: BuildingEnv(plant)]), norm_reward=False)
    rng = np.random.default_rng(0)
    normalize.obs_rms.mean = rng.normal(0.0, 0.1, plant.layout.size)
    normalize.obs_rms.var = rng.uniform(0.2, 3.0, plant.layout.size)
    normalize.training = False
    assert_same_forces_open_loop(plant, policy_controller(model, None, normalize), tmp_path / "sac.onnx")


@pytest.mark.slow
def test_a_model_free_policy_on_integrated_readings_exports_too(tmp_path):
    """The integration filter runs in the graph as the env runs it."""
    import torch

    from rlcontroller.learning.algorithms import build_model, make_vec_env

    experiment = Experiment.model_validate(
        {"sensors": {"integration_cutoff": 0.1}, "algorithm": {"name": "PPO", "policy": {"odd": True}}}
    )
    plant = Plant(experiment)
    model = build_model(experiment, make_vec_env(plant, seed=0), seed=0, device="cpu", tensorboard=None)
    with torch.no_grad():
        model.policy.action_net.weight.mul_(30.0)
    assert_same_forces_open_loop(plant, policy_controller(model, None), tmp_path / "model_free.onnx")


@pytest.mark.slow
def test_a_policy_that_sees_the_fail_safe_twin_exports_with_it(tmp_path):
    """The graph builds the twin's block of the observation (`sensors.twin`) as the env does: fed the same
    readings and the applied actions, its state holds the env's twin estimate and running peaks each step
    (within float32 storage), and the policy reading them gives the same forces."""
    import torch

    from rlcontroller.learning.algorithms import build_model, make_vec_env

    sensors = {"state_estimate": True, "ground_model": True, "twin": True}
    experiment = Experiment.model_validate({"sensors": sensors, "algorithm": {"name": "PPO"}})
    plant = Plant(experiment)
    model = build_model(experiment, make_vec_env(plant, seed=0), seed=0, device="cpu", tensorboard=None)
    with torch.no_grad():
        model.policy.action_net.weight.mul_(30.0)
    controller, layout = policy_controller(model, None), plant.layout
    path = tmp_path / "twin.onnx"
    assert_same_forces_open_loop(plant, controller, path)
    env, exported = BuildingEnv(plant), OnnxController(path)
    observation, info = env.reset(seed=1, options={"motion": synthetic_suite(count=1)[0]})
    graph_twin, env_twin = [], []
    for _ in range(info["steps"]):
        readings = observation[layout.readings].astype(float) * layout.reading_scale
        exported.step(readings[None], np.array([[float(observation[layout.ground]) * layout.ground_scale]]))
        graph_twin.append(exported.state[0, layout.twin].copy())
        env_twin.append(observation[layout.twin].astype(float))
        action = controller.act(observation)
        exported.state[0, layout.action] = action  # the held action is the one applied
        observation, *_ = env.step(action)
    graph_twin, env_twin = np.array(graph_twin), np.array(env_twin)
    assert np.abs(env_twin).max() > 0.1
    scale = np.abs(env_twin).max(axis=0)
    np.testing.assert_array_less(np.abs(graph_twin - env_twin).max(axis=0), 1e-5 * scale + 1e-9)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["five_story_amd", "five_story_mr"])
def test_policies_for_devices_export_too(tmp_path, name):
    """An active mass driver's force (N) and MR dampers' commands in [-1, 1] come out of the graph as
    the Python policy gives them."""
    import torch

    from rlcontroller.learning.algorithms import build_model, make_vec_env

    experiment = load_experiment(REPOSITORY / "configs" / "experiments" / f"{name}.yaml")
    experiment = experiment.model_copy(
        update={"algorithm": Experiment().algorithm.model_copy(update={"name": "PPO"})}
    )
    plant = Plant(experiment)
    model = build_model(experiment, make_vec_env(plant, seed=0), seed=0, device="cpu", tensorboard=None)
    with torch.no_grad():
        model.policy.action_net.weight.mul_(3000.0)  # near the end of a record the building is quiet
    assert_same_forces_open_loop(plant, policy_controller(model, None), tmp_path / f"{name}.onnx")


def assert_same_forces_open_loop(plant, controller, path):
    """These random policies are bang-bang controllers; in a closed loop float32 rounding would be
    amplified, so the Python controller drives the building and both read the same sensors. Within 1e-3 of the
    force limit (the export's own standard): weights multiplied by 3000 carry float32's rounding, which the
    BLAS kernel orders differently (1.3e-4 of the limit with OPENBLAS_CORETYPE=Prescott)."""
    path.write_bytes(controller_graph(plant, controller).SerializeToString())
    env, layout, exported = BuildingEnv(plant), plant.layout, OnnxController(path)
    observation, info = env.reset(seed=0, options={"motion": synthetic_suite(count=1)[0]})
    for _ in range(info["steps"]):
        action = controller.act(observation)
        readings = observation[layout.readings].astype(float) * layout.reading_scale
        force = exported.step(
            readings[None], np.array([[float(observation[layout.ground]) * layout.ground_scale]])
        )
        assert np.all(np.abs(force[0] - action * plant.force_limits) <= 1e-3 * plant.force_limits)
        exported.state[0, layout.action] = action  # the held action is the one applied
        observation, *_ = env.step(action)
    assert np.abs(action).max() > 0.1


def test_a_batch_of_buildings_runs_as_one_each(tmp_path):
    path = export_onnx(COMMITTED, "best", tmp_path / "controller.onnx")
    rng = np.random.default_rng(2)
    readings, ground = rng.normal(0.0, 2.0, (20, 4, 5)), rng.normal(0.0, 2.0, (20, 4, 1))
    batch, singles = OnnxController(path, batch=4), [OnnxController(path) for _ in range(4)]
    for k in range(20):
        together = batch.step(readings[k], ground[k])
        for i, single in enumerate(singles):
            alone = single.step(readings[k, i : i + 1], ground[k, i : i + 1])[0]
            np.testing.assert_allclose(together[i], alone, rtol=1e-9, atol=1e-6)


@pytest.mark.slow
def test_rlc_export_writes_the_file_and_refuses_bad_paths(tmp_path):
    out = tmp_path / "deployed.onnx"
    done = subprocess.run(
        [sys.executable, "-m", "rlcontroller", "export", str(COMMITTED), "--out", str(out)],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0 and out.is_file() and str(out) in done.stdout
    refused = subprocess.run(
        [sys.executable, "-m", "rlcontroller", "export", "--out", str(tmp_path / "missing" / "x.onnx")],
        capture_output=True,
        text=True,
    )
    assert refused.returncode == 2 and "expected a file path in an existing folder" in refused.stderr
    assert "Traceback" not in refused.stderr
    again = subprocess.run(
        [sys.executable, "-m", "rlcontroller", "export", str(COMMITTED), "--out", str(out)],
        capture_output=True,
        text=True,
    )
    assert again.returncode == 2 and "never overwritten" in again.stderr


@pytest.mark.slow
def test_rlc_export_writes_by_default_under_results_never_into_the_model_folder(tmp_path, monkeypatch):
    from rlcontroller.cli import DEFAULT_MODEL

    monkeypatch.chdir(tmp_path)
    before = sorted(path.name for path in DEFAULT_MODEL.iterdir())
    done = subprocess.run([sys.executable, "-m", "rlcontroller", "export"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "results" / f"{DEFAULT_MODEL.name}_best_controller.onnx").is_file()
    assert sorted(path.name for path in DEFAULT_MODEL.iterdir()) == before
    again = subprocess.run([sys.executable, "-m", "rlcontroller", "export"], capture_output=True, text=True)
    assert again.returncode == 2 and "never overwritten" in again.stderr


@pytest.mark.slow
def test_rlc_export_refuses_unknown_formats():
    command = [sys.executable, "-m", "rlcontroller", "export", "--format", "tflite"]
    done = subprocess.run(command, capture_output=True, text=True)
    assert done.returncode == 2 and "--format" in done.stderr


@pytest.mark.parametrize(("actor_arch", "squash"), [(None, False), ([], False), (None, True)])
def test_an_odd_policy_exports_with_its_symmetry(tmp_path, actor_arch, squash):
    from rlcontroller.control.networks import Actor, Layer
    from rlcontroller.control.policy_controller import PolicyController
    from rlcontroller.learning.algorithms import build_model, make_vec_env

    policy = {"net_arch": [32, 32], "actor_arch": actor_arch, "odd": True, "log_std_init": -1.0}
    experiment = Experiment.model_validate({"algorithm": {"name": "PPO", "policy": policy}})
    plant = Plant(experiment)
    model = build_model(experiment, make_vec_env(plant, seed=0), seed=0, device="cpu", tensorboard=None)
    controller = policy_controller(model, None)
    if squash:  # sbx's odd SAC: tanh of the half difference; biases the difference must cancel
        layers = [Layer(x.weight, np.full_like(x.bias, 0.3), x.activation) for x in controller.actor.layers]
        controller = PolicyController(Actor(tuple(layers), squash=True, odd=True), None)
    path = tmp_path / "odd.onnx"
    path.write_bytes(controller_graph(plant, controller).SerializeToString())
    exported = OnnxController(path)
    zero = exported.step(np.zeros((1, 5)), np.zeros((1, 1)))
    assert np.all(zero == 0.0)  # no readings, no force
    readings, ground = np.random.default_rng(3).normal(0.0, 2.0, (1, 5)), np.array([[1.5]])
    exported.reset()
    force = exported.step(readings, ground)
    layout, observation = plant.layout, np.zeros(plant.layout.size, dtype=np.float32)
    observation[layout.readings] = readings[0] / layout.reading_scale
    observation[layout.ground] = ground[0, 0] / layout.ground_scale
    np.testing.assert_allclose(
        force[0], controller.act(observation) * plant.force_limits, rtol=1e-5, atol=1e-2
    )
