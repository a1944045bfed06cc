"""A building given as a state-space model: the same building as M, K, C and as A, B, C, D gives the same
evaluation, a discrete model the same to rounding, and a response it does not declare is unavailable."""

import numpy as np
import pytest
import scipy.signal
import yaml
from conftest import REPOSITORY, SAME_PHYSICS

from rlcontroller.api import Judging, evaluate
from rlcontroller.assets import DEFAULT_MODEL
from rlcontroller.config import Experiment, load_experiment
from rlcontroller.evaluation.evaluation import classical_controllers
from rlcontroller.evaluation.evaluation import evaluate as run_evaluation
from rlcontroller.physics.dynamics import state_space_arrays
from rlcontroller.physics.motions.loads import generate_suite
from rlcontroller.physics.plant import Plant
from rlcontroller.physics.state_space import continuous, state_space_outputs


def as_state_space(experiment: Experiment, folder, arrays=None, outputs=None, **part) -> Experiment:
    """`experiment` with its building replaced by its own state-space model (an .npz in `folder`)."""
    arrays = arrays if arrays is not None else state_space_arrays(Plant(experiment).building)
    np.savez(folder / "model.npz", **arrays)
    m = len(experiment.actuators)
    raw = experiment.model_dump(mode="json")
    raw["building"] = {
        "state_space": "model.npz",
        "state": "physical",
        "inputs": {"actuators": list(range(m)), "ground": m},
        "outputs": outputs or state_space_outputs(experiment.building.n_floors),
        **part,
    }
    (folder / "experiment.yaml").write_text(yaml.safe_dump(raw))
    return load_experiment(folder / "experiment.yaml")


@pytest.mark.slow
def test_the_default_model_evaluates_bit_for_bit_on_its_state_space_building(tmp_path, records):
    """The shipped default controller, LQG, LQG + ground, LQG + ground model and the clairvoyant optimum on
    the seven records: every number of every table identical with the building given as A, B, C, D."""
    experiment = load_experiment(DEFAULT_MODEL / "config.yaml")
    as_state_space(experiment, tmp_path)
    reference, _ = evaluate(judging=Judging(records), out=tmp_path / "mkc")
    model, _ = evaluate(judging=Judging(records), out=tmp_path / "ss", config=tmp_path / "experiment.yaml")
    assert model.metrics.equals(reference.metrics)
    assert model.summary().equals(reference.summary())


def test_a_discrete_model_evaluates_as_its_continuous_building(tmp_path):
    """The five-story building discretised (zero-order hold, 5 ms) and given with its sample time: the
    continuous model recovered from it steps the same uncontrolled responses to 1e-9 of their peaks, and
    the LQGs designed on it the same closed loops to rounding (`SAME_PHYSICS`)."""
    experiment = Experiment()
    arrays = state_space_arrays(Plant(experiment).building)
    a, b, *_ = scipy.signal.cont2discrete((arrays["A"], arrays["B"], arrays["C"], arrays["D"]), 0.005)
    discrete = as_state_space(experiment, tmp_path, arrays=arrays | {"A": a, "B": b, "dt": 0.005})
    np.testing.assert_allclose(continuous(a, b, 0.005)[0], arrays["A"], atol=1e-9 * np.abs(arrays["A"]).max())
    motions = generate_suite(experiment.excitation.generator, 4, 7, Plant(experiment).building)
    results = []
    for case in (experiment, discrete):
        plant = Plant(case)
        results.append(
            run_evaluation(plant, motions, classical_controllers(plant), "case", include_optimal=False)
        )
    reference, model = (result.responses for result in results)
    assert reference.keys() == model.keys() and len(reference) == 4 * 4  # uncontrolled and three LQGs
    for key, response in reference.items():
        for name in ("drift", "absolute_acceleration", "story_shear", "force"):
            peak = np.abs(response.quantity(name)).max()
            tolerance = 1e-9 if key[0] == "uncontrolled" else SAME_PHYSICS
            np.testing.assert_allclose(
                model[key].quantity(name), response.quantity(name), atol=tolerance * peak
            )


def test_an_undeclared_response_is_unavailable_not_invented(tmp_path):
    """Without story shears in the model, J4 (and J3, over the base shear's energy) are NaN; J1 and J2
    are the M, K, C building's."""
    experiment = Experiment().model_copy(
        update={"reward": Experiment().reward.model_copy(update={"terms": Experiment().reward.terms[::2]})}
    )
    assert {term.quantity for term in experiment.reward.terms} == {"drift", "force"}
    outputs = state_space_outputs(5)
    del outputs["story_shear"]
    model = as_state_space(experiment, tmp_path, outputs=outputs)
    motions = generate_suite(experiment.excitation.generator, 2, 3, Plant(experiment).building)
    tables = []
    for case in (experiment, model):
        plant = Plant(case)
        tables.append(
            run_evaluation(
                plant, motions, classical_controllers(plant)[:1], "case", include_optimal=False
            ).summary()
        )
    reference, table = tables
    assert table[["J3", "J4"]].isna().all().all() and not reference[["J3", "J4"]].isna().any().any()
    np.testing.assert_allclose(table[["J1", "J2"]], reference[["J1", "J2"]], rtol=1e-12)


def test_the_model_reports_the_buildings_modes(tmp_path):
    """Periods and damping ratios of the state-space building are the M, K, C building's (design.md:
    1.444, 0.549, 0.351, 0.281, 0.242 s; Rayleigh 1 % in mode 1, 5 % in mode 5)."""
    experiment = Experiment()
    building = Plant(experiment).building
    model = Plant(as_state_space(experiment, tmp_path)).building
    np.testing.assert_allclose(model.periods(), building.periods(), rtol=1e-9)
    np.testing.assert_allclose(model.periods(), [1.444, 0.549, 0.351, 0.281, 0.242], atol=6e-4)
    np.testing.assert_allclose(model.modal_damping_ratios()[[0, 4]], [0.01, 0.05], rtol=1e-9)


@pytest.mark.slow
def test_a_learner_trains_on_the_state_space_building_as_on_its_matrices(tmp_path):
    """The smoke experiment's learner, same seed, on the building as M, K, C and as its state-space model:
    the same validation numbers at every validation (the env steps the same maps)."""
    from rlcontroller.learning.training import train

    experiment = load_experiment(REPOSITORY / "configs" / "testing" / "smoke.yaml")
    short = {"total_steps": 400, "checkpoint_every": 200, "eval_every": 200}
    experiment = experiment.model_copy(update={"algorithm": experiment.algorithm.model_copy(update=short)})
    model = as_state_space(experiment, tmp_path)
    curves = []
    for case, name in ((experiment, "mkc"), (model, "ss")):
        train(experiment=case, run_dir=tmp_path / name)
        curves.append((tmp_path / name / "learning_curve.csv").read_text().splitlines())
    columns = curves[0][0].split(",")
    wall = columns.index("wall_time_s")
    for left, right in zip(*curves, strict=True):
        assert [v for i, v in enumerate(left.split(",")) if i != wall] == [
            v for i, v in enumerate(right.split(",")) if i != wall
        ]
    assert len(curves[0]) > 2
