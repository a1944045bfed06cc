"""Classical controllers as controller files (control/policy_controller.py): written by `rlc design`, read
back as exactly their law — an LQG on the env's estimate acts as the evaluation's own LQG, a passive damper
setting as the constant command, MPC as the comparisons' MPC — and a file that claims a law it does not hold
is refused."""

import numpy as np
import pytest
import yaml
from conftest import REPOSITORY

from rlcontroller import api
from rlcontroller.config import ConfigError, load_experiment
from rlcontroller.control.controllers import ConstantCommand, LQGController
from rlcontroller.control.lqg import design_lqg_ground_model
from rlcontroller.control.mpc import DEFAULT_HORIZON
from rlcontroller.control.mpc_controllers import MPCController
from rlcontroller.control.policy_file import read_policy
from rlcontroller.physics.motions.records import synthetic_suite
from rlcontroller.physics.plant import Plant
from rlcontroller.simulation.linearised import closed_loop_matrix
from rlcontroller.simulation.rollout import batch_rollout

EXPERIMENTS = REPOSITORY / "configs" / "experiments"


def test_a_designed_lqg_file_acts_as_the_evaluation_s_lqg(tmp_path):
    folder = api.design(EXPERIMENTS / "five_story_every_story.yaml", "lqg_ground_model", tmp_path / "lqg")
    plant = Plant(load_experiment(folder / "config.yaml"))
    from_file = read_policy(folder, "best", plant)
    assert from_file.name == "LQG + ground model (lqg)" and from_file.law == "lqg_ground_model"
    built = LQGController(design_lqg_ground_model(plant.design), plant.design, "LQG + ground model")
    motions = synthetic_suite(count=2)
    # on the driver's linear plant: past its stops, an impact makes the last digits of the two plans diverge
    runs = batch_rollout(plant.elastic, motions, [from_file, built])
    for (file_run, _), (built_run, _) in zip(*runs, strict=True):
        scale = np.abs(built_run.force).max()
        assert scale > 1e3
        # the file's law reads the float32 estimate the observation holds, the built LQG its own float64 one:
        # 1e-8 apart, grown by the faded supervisor over a record to below 1e-4 of the force
        np.testing.assert_allclose(file_run.force, built_run.force, rtol=0.0, atol=1e-4 * scale)


@pytest.mark.parametrize(("law", "value"), [("passive-on", 1.0), ("passive-off", -1.0)])
def test_a_passive_damper_file_holds_its_command(tmp_path, law, value):
    folder = api.design(EXPERIMENTS / "five_story_mr.yaml", law, tmp_path / law)
    plant = Plant(load_experiment(folder / "config.yaml"))
    controller = read_policy(folder, "best", plant)
    observations = np.random.default_rng(0).normal(size=(4, plant.layout.size))
    expected = ConstantCommand(value, 3, law).act(observations)
    np.testing.assert_array_equal(controller.act(observations), expected)


def test_a_classical_file_whose_weights_are_not_zero_is_refused(tmp_path):
    folder = api.design(EXPERIMENTS / "five_story_every_story.yaml", "lqg_ground_model", tmp_path / "lqg")
    plant = Plant(load_experiment(folder / "config.yaml"))
    weights = dict(np.load(folder / "best_policy.npz"))
    weights["layer0_weight"][0, 0] = 0.5  # a network hidden under a classical label
    np.savez(folder / "best_policy.npz", **weights)
    with pytest.raises(ConfigError, match="a classical lqg_ground_model law has one layer of zero weights"):
        read_policy(folder, "best", plant)


def test_design_refuses_a_law_the_experiment_cannot_hold_and_an_existing_folder(tmp_path):
    with pytest.raises(
        ConfigError, match="law lqg_ground: this experiment's LQG on its estimate is lqg_ground_model"
    ):
        api.design(EXPERIMENTS / "five_story_every_story.yaml", "lqg_ground", tmp_path / "a")
    with pytest.raises(ConfigError, match="--law lqr: expected one of"):
        api.design(EXPERIMENTS / "five_story_every_story.yaml", "lqr", tmp_path / "b")
    (tmp_path / "c").mkdir()
    with pytest.raises(ConfigError, match="exists; a controller folder is never overwritten"):
        api.design(EXPERIMENTS / "five_story_every_story.yaml", "lqg_ground_model", tmp_path / "c")


@pytest.mark.parametrize("experiment", ["five_story_every_story", "five_story_amd"])
def test_a_designed_mpc_file_acts_as_the_comparisons_mpc(tmp_path, experiment):
    """MPC from its file (the QP's model, cost and horizon as data, on the env's estimate) gives the forces of
    `rlc compare lqg --mpc 20`'s MPC (its own filter), the driver's stroke constraint included."""
    folder = api.design(EXPERIMENTS / f"{experiment}.yaml", "mpc", tmp_path / "mpc")
    plant = Plant(load_experiment(folder / "config.yaml"))
    from_file = read_policy(folder, "best", plant)
    assert from_file.law == "mpc" and from_file.mpc.design.horizon == DEFAULT_HORIZON
    built = MPCController(plant.design, DEFAULT_HORIZON)
    motions = synthetic_suite(count=2)
    # on the driver's linear plant: past its stops, an impact makes the last digits of the two plans diverge
    runs = batch_rollout(plant.elastic, motions, [from_file, built])
    for (file_run, _), (built_run, _) in zip(*runs, strict=True):
        scale = np.abs(built_run.force).max()
        assert scale > 1e3
        # the float32 estimate against the built filter's float64 one: equal plans to the solver's tolerance
        # but at the odd step where the driver's stroke binds and a solve stops short (its fallback)
        difference = np.abs(file_run.force - built_run.force)
        assert np.mean(difference > 1e-3 * scale) < 0.02 and np.mean(difference) < 1e-3 * scale
        peaks = [np.abs(run.drift).max() for run in (file_run, built_run)]
        assert peaks[0] == pytest.approx(peaks[1], rel=1e-4)


def test_at_rest_an_mpc_file_is_its_lqg(tmp_path):
    """Linearised at rest no limit binds and MPC's first move is LQR's: the safety check's closed loop of the
    MPC file is the LQG file's (its spectral radius to the solver's tolerance)."""
    path = EXPERIMENTS / "five_story_every_story.yaml"
    plant = Plant(load_experiment(path))
    mpc = read_policy(api.design(path, "mpc", tmp_path / "mpc"), "best", plant)
    lqg = read_policy(api.design(path, "lqg_ground_model", tmp_path / "lqg"), "best", plant)
    np.testing.assert_allclose(
        closed_loop_matrix(plant, mpc), closed_loop_matrix(plant, lqg), rtol=0, atol=1e-3
    )


@pytest.mark.parametrize(
    ("forge", "message"),
    [
        (
            lambda yaml, npz: npz.__setitem__("mpc_terminal", -npz["mpc_terminal"]),
            "mpc_terminal: expected a symm",
        ),
        (
            lambda yaml, npz: yaml["mpc"].__setitem__("horizon", 100000),
            r"mpc.horizon 100000: expected a whole",
        ),
        (
            lambda yaml, npz: yaml.__setitem__("law", "lqg_ground_model"),
            "mpc: a classical mpc law has an mpc sec",
        ),
        (
            lambda yaml, npz: npz.__setitem__("mpc_strokes", np.zeros((9, 12))),
            "mpc: 1 cost rows|mpc: .* 9 stroke",
        ),
        # a model other than the folder's design model never reaches the QP solver (x 1e6: OSQP "non-convex")
        (
            lambda yaml, npz: npz.__setitem__("mpc_phi", 1e6 * npz["mpc_phi"]),
            "mpc_phi: not the control-step map",
        ),
        (
            lambda yaml, npz: npz.__setitem__("mpc_action_gain", 1.001 * npz["mpc_action_gain"]),
            "mpc_action_gain: not",
        ),
        (
            lambda yaml, npz: npz.__setitem__("mpc_cost_state", 1e200 * npz["mpc_cost_state"]),
            "their QP overflows",
        ),
    ],
)
def test_a_forged_mpc_file_is_refused_in_one_line(tmp_path, forge, message):
    folder = api.design(EXPERIMENTS / "five_story_every_story.yaml", "mpc", tmp_path / "mpc")
    description = yaml.safe_load((folder / "best_policy.yaml").read_text())
    weights = dict(np.load(folder / "best_policy.npz"))
    forge(description, weights)
    (folder / "best_policy.yaml").write_text(yaml.safe_dump(description))
    np.savez(folder / "best_policy.npz", **weights)
    with pytest.raises(ConfigError, match=message) as error:
        read_policy(folder, "best", Plant(load_experiment(folder / "config.yaml")))
    assert "\n" not in str(error.value)


def test_mpc_files_refuse_dampers_and_export(tmp_path):
    with pytest.raises(
        ConfigError, match="law mpc: MPC as a controller file runs on the env's Kalman estimate"
    ):
        api.design(EXPERIMENTS / "five_story_mr.yaml", "mpc", tmp_path / "mr")
    folder = api.design(EXPERIMENTS / "five_story_every_story.yaml", "mpc", tmp_path / "mpc")
    with pytest.raises(ConfigError, match="an MPC controller solves a quadratic program every step"):
        api.export(folder, tmp_path / "mpc.onnx")
