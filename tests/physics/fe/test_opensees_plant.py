"""The OpenSees plant (`physics.fe.opensees`): the five-story model against rlc's own integration, the
nine-story frame against its published periods, the reduced model, non-convergence, and the trust boundary."""

import re
import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml

from rlcontroller import api
from rlcontroller.config import ConfigError, load_experiment, with_overrides
from rlcontroller.config.loading import UNTRUSTED_MODEL
from rlcontroller.errors import ModelError
from tests.conftest import OPENSEES_FAILURES, OPENSEES_MISSING

ops = pytest.importorskip("openseespy.opensees", reason=OPENSEES_MISSING, exc_type=OPENSEES_FAILURES)

from rlcontroller.physics.fe.build import fe_modes, reduced_building  # noqa: E402
from rlcontroller.physics.fe.opensees import NonConvergence  # noqa: E402
from rlcontroller.physics.motions.records import load_records  # noqa: E402
from rlcontroller.physics.plant import Plant  # noqa: E402
from rlcontroller.simulation.rollout import uncontrolled_responses  # noqa: E402

CONFIGS = Path(__file__).resolve().parents[3] / "configs"
FIVE_STORY = CONFIGS.parent / "studies" / "opensees" / "five_story_opensees.yaml"
FRAME_MODEL = CONFIGS / "opensees" / "nine_story_frame.py"
PUBLISHED_FREQUENCIES = np.array([0.443, 1.18, 2.05])  # Hz, Ohtori et al. (2004), the nine-story building


def _peaks(responses, quantity):
    return np.array([np.max(np.abs(getattr(r, quantity)), axis=0) for r in responses])


@pytest.mark.slow
def test_five_story_model_agrees_with_rlc_on_the_seven_records(records):
    fe, motions = Plant(load_experiment(FIVE_STORY)), load_records(records)[0]
    fe_runs, exact_runs = uncontrolled_responses(fe, motions), uncontrolled_responses(fe.design, motions)
    for quantity in ("drift", "absolute_acceleration", "story_shear"):
        error = np.abs(_peaks(fe_runs, quantity) / _peaks(exact_runs, quantity) - 1.0)
        assert error.max() <= 1e-3, quantity


@pytest.mark.slow
def test_actuator_forces_reach_the_model_as_rlc_applies_them(records):
    """A command held over a step pushes floor j by +f and floor j-1 by -f in both integrations."""
    from rlcontroller.control.controllers import ConstantCommand
    from rlcontroller.simulation.rollout import batch_rollout

    fe = Plant(load_experiment(FIVE_STORY).model_copy(update={"supervisor": None}))  # the command as given
    motion = load_records(records)[0][3]  # sampled at the control step
    push = ConstantCommand(np.array([0.5, -0.3, 0.2, 0.0, 1.0]), 5, "push")
    ((fe_run, _),) = batch_rollout(fe, [motion], [push])[0]
    ((exact_run, _),) = batch_rollout(fe.design, [motion], [push])[0]
    peaks = np.max(np.abs(fe_run.drift), axis=0) / np.max(np.abs(exact_run.drift), axis=0) - 1.0
    assert np.max(np.abs(peaks)) <= 1e-3
    rms = np.sqrt(np.mean((fe_run.drift - exact_run.drift) ** 2) / np.mean(exact_run.drift**2))
    assert rms <= 2e-3  # a wrong sign or floor for a force is tens of per cent (its static drift is 33 mm)


def test_condensed_stiffness_of_the_shear_model_is_its_stiffness_matrix():
    building = reduced_building(CONFIGS / "opensees" / "five_story_shear.py", "build_model")
    stiffness = np.array([5.0e6, 4.0e6, 4.0e6, 3.0e6, 3.0e6])  # N/m, story 1 first (the file's)
    drift = np.eye(5) - np.eye(5, k=-1)
    np.testing.assert_allclose(
        building["stiffness_matrix"], drift.T @ np.diag(stiffness) @ drift, rtol=1e-9, atol=1e-3
    )
    np.testing.assert_allclose(np.diag(building["mass_matrix"]), [25e3, 20e3, 20e3, 18e3, 15e3])
    assert building["modal_damping"][0] == pytest.approx(0.01) and building["modal_damping"][
        4
    ] == pytest.approx(0.05)


def test_nine_story_frame_reproduces_its_published_periods():
    periods, ratios = fe_modes(FRAME_MODEL, "build_model", 3)
    np.testing.assert_allclose(periods, 1.0 / PUBLISHED_FREQUENCIES, rtol=0.05)
    assert ratios[:2] == pytest.approx([0.02, 0.02])


def test_frame_experiment_is_designed_on_the_reduced_model_of_the_frame():
    """Loaded as the commands load it (`api.load` hands config the FE reduction; config imports no
    physics)."""
    with pytest.raises(ConfigError, match="opensees: no building: its design model is reduced"):
        load_experiment(CONFIGS / "experiments" / "nine_story_frame.yaml")
    experiment = api.load(CONFIGS / "experiments" / "nine_story_frame.yaml")
    design = Plant(experiment).design.building
    periods, _ = fe_modes(FRAME_MODEL, "build_model", 9)
    assert design.n_dofs == 9
    # floor masses only: condensation is exact
    np.testing.assert_allclose(design.periods(), periods, rtol=1e-6)


def test_a_run_folder_never_runs_a_model_file(tmp_path):
    experiment = load_experiment(FIVE_STORY)
    kept = experiment.to_yaml()
    assert kept.startswith("# plant: the OpenSees model") and yaml.safe_load(kept)["plant"] is None
    (tmp_path / "config.yaml").write_text(kept.split("\n", 1)[1].replace("plant: null", ""))
    assert load_experiment(tmp_path / "config.yaml", self_contained=True).plant is None
    forged = kept.split("\n", 1)[1].replace(
        "plant: null", f"plant:\n  opensees:\n    model: {CONFIGS / 'opensees' / 'five_story_shear.py'}"
    )
    (tmp_path / "config.yaml").write_text(forged)
    with pytest.raises(ConfigError, match="a run or model folder never runs one"):
        load_experiment(tmp_path / "config.yaml", self_contained=True)
    assert "--config" in UNTRUSTED_MODEL


def test_an_fe_plant_takes_no_factors_of_rlc_plant(tmp_path):
    experiment = load_experiment(FIVE_STORY)
    with pytest.raises(ConfigError, match="an FE model is the plant as it is"):
        with_overrides(experiment, {"plant.stiffness": 0.9}, "--set")


def test_a_model_that_does_not_converge_names_the_record(tmp_path, records):
    model = tmp_path / "loose.py"
    model.write_text(
        "def build_model(ops):\n"
        "    ops.model('basic', '-ndm', 1, '-ndf', 1)\n"
        "    ops.node(0, 0.0); ops.fix(0, 1)\n"
        "    ops.node(1, 1.0); ops.mass(1, 1.0e4)\n    ops.node(2, "
        "2.0)\n"  # not a floor, massless and held by nothing: the first step's system is singular
        "    ops.uniaxialMaterial('Elastic', 1, 1.0e6)\n"
        "    ops.element('truss', 1, 0, 1, 1.0, 1)\n"
        "    return {'floors': [[1]], 'direction': 1, 'story_heights': [3.0], 'modal_damping': [0.02]}\n"
    )
    experiment = load_experiment(FIVE_STORY)
    part = {"opensees": {"model": str(model), "analysis_dt": 0.005}}
    raw = experiment.model_dump(mode="json") | {"plant": part}
    raw["building"] = {
        "masses": [1.0e4],
        "stiffnesses": [1.0e6],
        "story_heights": [3.0],
        "damping": {"matrix": [[500.0]]},
    }
    raw["actuators"] = [{"story": 1, "force_limit": 1.0e4}]
    from rlcontroller.config.loading import build_experiment

    plant, motion = Plant(build_experiment(raw)), load_records(records)[0][0]
    with pytest.raises(NonConvergence, match=motion.name) as raised:
        uncontrolled_responses(plant, [motion])
    assert isinstance(raised.value, ModelError)


def test_a_missing_openseespy_is_one_line_naming_the_system_libraries(monkeypatch):
    import sys

    from rlcontroller.physics.fe import opensees

    monkeypatch.setitem(sys.modules, "openseespy.opensees", None)
    with pytest.raises(ConfigError, match="libblas3 liblapack3"):
        opensees.opensees()


@pytest.mark.slow
def test_the_default_judged_on_the_fe_plant_scores_as_on_rlc_plant(records, tmp_path):
    """`rlc evaluate MODEL --config EXPERIMENT`: the shipped default on the five-story OpenSees model."""
    from rlcontroller import api
    from rlcontroller.assets import DEFAULT_MODEL

    on_fe, _ = api.evaluate(
        run_dir=DEFAULT_MODEL, judging=api.Judging(records), out=tmp_path / "fe", config=FIVE_STORY
    )
    on_rlc, _ = api.evaluate(run_dir=DEFAULT_MODEL, judging=api.Judging(records), out=tmp_path / "rlc")
    fe, exact = on_fe.summary(), on_rlc.summary()
    name = "RL"  # the default model, the learned MPC
    assert fe.loc[name, "J1"] == pytest.approx(exact.loc[name, "J1"], rel=0.02)
    assert fe.loc[name, "J2"] == pytest.approx(exact.loc[name, "J2"], rel=0.02)


def _learning_on_fe_model(tmp_path: Path) -> Path:
    """The five-story OpenSees experiment learning on the FE model itself: SAC, a few hundred steps on short
    motions."""
    raw = yaml.safe_load(FIVE_STORY.read_text())
    smoke = yaml.safe_load((CONFIGS / "testing" / "smoke.yaml").read_text())
    for part in ("building", "actuators", "sensors", "reward", "excitation", "supervisor"):
        if isinstance(raw[part], str):
            raw[part] = str((FIVE_STORY.parent / raw[part]).resolve())
    raw["plant"]["opensees"] |= {"model": str(CONFIGS / "opensees" / "five_story_shear.py"), "train_on": "fe"}
    raw["excitation"] = smoke["excitation"]
    raw["algorithm"] = smoke["algorithm"] | {"total_steps": 300, "checkpoint_every": 300, "eval_every": 300}
    raw["algorithm"]["kwargs"] |= {"learning_starts": 100}
    path = tmp_path / "learning_on_fe.yaml"
    path.write_text(yaml.safe_dump(raw))
    return path


@pytest.mark.slow
def test_train_on_fe_learns_on_the_fe_model_and_resumes_only_with_it_named(tmp_path, monkeypatch):
    from rlcontroller import api
    from rlcontroller.api.training import _fe_experiment_of
    from rlcontroller.learning.training import train
    from rlcontroller.physics.fe.integrator import OpenSeesIntegrator

    steps = []
    original = OpenSeesIntegrator.step
    monkeypatch.setattr(
        OpenSeesIntegrator, "step", lambda self, *args: steps.append(1) or original(self, *args)
    )
    config = _learning_on_fe_model(tmp_path)
    summary = train(experiment=load_experiment(config), run_dir=tmp_path / "run")
    assert summary.steps == 300 and len(steps) >= 300  # the training env stepped the FE model here
    with pytest.raises(ConfigError, match="learned on an OpenSees model, which a run folder never runs"):
        api.train(resume=summary.run_dir)
    resumed = _fe_experiment_of(summary.run_dir, config)
    assert resumed.plant.opensees.train_on == "fe" and resumed.algorithm.total_steps == 300
    other = tmp_path / "other.yaml"
    other.write_text(config.read_text().replace("five_story_shear.py", "nine_story_frame.py"))
    with pytest.raises(ConfigError, match="does not name the OpenSees model"):
        _fe_experiment_of(summary.run_dir, other)


def test_learning_on_fe_model_takes_one_model_per_process(tmp_path):
    experiment = load_experiment(_learning_on_fe_model(tmp_path))
    with pytest.raises(ConfigError, match="one model per process: vec_env: subproc, or n_envs: 1"):
        with_overrides(experiment, {"algorithm.n_envs": 4}, "--set")
    assert with_overrides(experiment, {"algorithm.n_envs": 4, "algorithm.vec_env": "subproc"}, "--set")


def one_story_model(folder: Path, returned: str) -> Path:
    """A one-story OpenSees model file whose function returns `returned` (floors, direction and any solver
    options) with a story height and damping."""
    model = folder / "one_story.py"
    model.write_text(
        "def build_model(ops):\n"
        "    ops.model('basic', '-ndm', 1, '-ndf', 1)\n"
        "    ops.node(0, 0.0); ops.fix(0, 1)\n"
        "    ops.node(1, 1.0); ops.mass(1, 1.0e4)\n"
        "    ops.uniaxialMaterial('Elastic', 1, 1.0e6)\n"
        "    ops.element('truss', 1, 0, 1, 1.0, 1)\n"
        f"    return {{{returned}, 'story_heights': [3.0], 'modal_damping': [0.02]}}\n"
    )
    return model


@pytest.mark.parametrize(
    ("given", "message"),
    [
        ("'system': ['Foo']", "system ['Foo']: OpenSees does not take it"),
        ("'test': 'NormUnbalance'", "test: expected"),
    ],
)
def test_a_model_files_solver_options_are_checked(tmp_path, given, message):
    from rlcontroller.physics.fe.integrator import OpenSeesIntegrator

    model = one_story_model(tmp_path, f"'floors': [[1]], 'direction': 1, {given}")
    with pytest.raises(ModelError, match=re.escape(message)):
        OpenSeesIntegrator(model, "build_model", 0.005, np.eye(1), np.ones(1)).reset()


@pytest.mark.parametrize(
    ("returned", "message"),
    [
        ("'floors': [[7]], 'direction': 1", "floors: floor 1 names node 7, which the model does not have"),
        (
            "'floors': [[1]], 'direction': 2",
            "direction 2: expected a degree of freedom of the floor nodes, 1 to 1",
        ),
    ],
)
def test_a_description_the_model_does_not_match_is_one_line(tmp_path, returned, message):
    """What the model function says of its model is checked against the domain it built (OpenSees itself
    would stop later with "OpenSeesError: See stderr output")."""
    from rlcontroller.physics.fe.build import build_model

    model = one_story_model(tmp_path, returned)
    with pytest.raises(ModelError, match=re.escape(f"{model}: build_model: {message}")):
        build_model(model, "build_model")


def test_a_model_that_calls_exit_is_one_line_and_rlc_goes_on(tmp_path):
    from rlcontroller.physics.fe.build import build_model

    model = one_story_model(tmp_path, "'floors': [[1]], 'direction': 1")
    model.write_text(model.read_text().replace("    return", "    raise SystemExit(0)\n    return"))
    with pytest.raises(
        ModelError, match=re.escape(f"{model}: build_model: the model calls exit; return its")
    ):
        build_model(model, "build_model")


def test_a_model_without_elements_is_one_line_without_numpy_warnings(tmp_path):
    from rlcontroller.physics.fe.build import reduced_building

    model = one_story_model(tmp_path, "'floors': [[1]], 'direction': 1")
    model.write_text(model.read_text().replace("    ops.element('truss', 1, 0, 1, 1.0, 1)\n", ""))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a numpy RuntimeWarning (a period of 2 pi / 0) fails the test
        with pytest.raises(ModelError, match=re.escape(f"{model}: the eigen analysis finds 0 of 1 modes")):
            reduced_building(model, "build_model")


def test_a_model_with_other_floors_than_the_building_is_one_line(tmp_path):
    from rlcontroller.physics.fe.integrator import OpenSeesIntegrator

    model = one_story_model(tmp_path, "'floors': [[1]], 'direction': 1")
    with pytest.raises(
        ModelError, match=re.escape(f"{model}: the model has 1 floors, the experiment's building 5")
    ):
        OpenSeesIntegrator(model, "build_model", 0.005, np.ones((5, 1)), np.ones(1)).reset()


@pytest.mark.slow
def test_the_frame_reports_ductility_and_residual_drift_where_it_yields():
    """`evaluate` on the FE frame: per story the ductility demand (peak drift over the pushover's yield
    drift) and the residual drift after the settling tail. A weak motion leaves every story elastic and no
    residual drift beyond the free vibration the tail leaves (under 10 % of the peak at 2 % damping); a
    strong one yields stories (ductility above 1.5) and leaves them leaning (above 0.1 % of a story)."""
    from rlcontroller.evaluation.evaluation import evaluate
    from rlcontroller.physics.motions.excitation import Load

    plant = Plant(api.load(CONFIGS / "experiments" / "nine_story_frame.yaml"))
    time = np.arange(0.0, 8.0, 0.01)
    pulse = np.sin(2 * np.pi * time / 2.2) * np.exp(-(((time - 3.0) / 1.5) ** 2))  # near the first period
    motions = [Load("weak", 0.01, 0.15 * pulse), Load("strong", 0.01, 9.0 * pulse)]
    result = evaluate(plant, motions, [], "FE", include_optimal=False)
    frame = result.metrics.set_index(["record", "metric", "index"])["value"]
    weak, strong = frame.loc["weak"], frame.loc["strong"]
    height = np.array([5.49] + [3.96] * 8)
    weak_peak = np.max(np.abs(result.responses["uncontrolled", "weak"].drift), axis=0)
    assert weak.loc["ductility"].max() < 0.5 and np.all(weak.loc["residual_drift_m"] < 0.1 * weak_peak)
    assert strong.loc["ductility"].max() > 1.5 and np.max(strong.loc["residual_drift_m"] / height) > 1e-3
    peak_drift = np.max(np.abs(result.responses["uncontrolled", "strong"].drift), axis=0)
    np.testing.assert_allclose(strong.loc["ductility"], peak_drift / plant.yield_drift, rtol=1e-12)


@pytest.mark.slow
def test_what_the_model_prints_during_its_runs_goes_to_a_log_in_the_output_folder(
    tmp_path, capfd, monkeypatch
):
    """A model that prints (as OpenSees' FAILURE lines do, from C, on descriptor 2) in every run: the terminal
    gets one line counting them, the output folder the lines themselves (opensees.log)."""
    import os

    folder = tmp_path / "model"
    folder.mkdir()
    source = (CONFIGS / "opensees" / "five_story_shear.py").read_text()
    noisy = source.replace(
        '    ops.model("basic", "-ndm", 1, "-ndf", 1)',
        '    import os\n    if os.getpid() != int(os.environ["RLC_TEST_PARENT"]):\n'
        '        os.write(2, b"WARNING the model speaks in a run\\n")\n'
        '    ops.model("basic", "-ndm", 1, "-ndf", 1)',
    )
    (folder / "five_story_shear.py").write_text(noisy)
    text = FIVE_STORY.read_text().replace("../../configs/opensees/", f"{folder}/")
    (tmp_path / "experiment.yaml").write_text(text.replace("../../configs/", f"{CONFIGS}/"))
    monkeypatch.setenv("RLC_TEST_PARENT", str(os.getpid()))
    monkeypatch.setenv("RLC_CACHE", str(tmp_path / "cache"))
    time = np.arange(0.0, 2.0, 0.01)
    records = tmp_path / "records"
    records.mkdir()
    for i in range(3):
        rows = "\n".join(f"{t:.2f},{0.5 * np.sin(2 * np.pi * (1 + i) * t):.6f}" for t in time)
        (records / f"r{i}.csv").write_text("time [s],acceleration [m/s2]\n" + rows + "\n")
    from rlcontroller.api.common import Report

    lines: list[str] = []

    class Listening(Report):
        def note(self, text: str) -> None:
            lines.append(text)

    experiment = tmp_path / "experiment.yaml"
    _, out = api.evaluate(
        config=experiment, judging=api.Judging(records), out=tmp_path / "out", report=Listening()
    )
    log = out / "opensees.log"
    assert log.is_file() and log.read_text().count("the model speaks in a run") >= 3  # once per run at least
    assert "the model speaks" not in capfd.readouterr().err  # not on the terminal
    assert any("the FE model printed" in line and "opensees.log" in line for line in lines)
