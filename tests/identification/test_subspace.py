"""Identification recovers a known building: on a simulated 10-minute test of the five-story building
(sensor noise on) its frequencies within 1 %, damping ratios within 20 % and mode shapes, and LQG designed on
the model it gives controls the true building as LQG on the true matrices does; what cannot be identified is
refused in one line."""

from pathlib import Path

import numpy as np
import pytest
import yaml

from rlcontroller.api import identify
from rlcontroller.config import Experiment, load_experiment
from rlcontroller.errors import RecordingError
from rlcontroller.evaluation.evaluation import classical_controllers
from rlcontroller.evaluation.evaluation import evaluate as run_evaluation
from rlcontroller.identification.recording import ambient_ground, simulate_test
from rlcontroller.identification.subspace import identify as identify_model
from rlcontroller.physics.motions.loads import generate_suite
from rlcontroller.physics.plant import Plant
from rlcontroller.physics.structure import natural_modes

TRUE = Plant(Experiment())
MASSES = [25e3, 20e3, 20e3, 18e3, 15e3]


@pytest.fixture(scope="module")
def ten_minutes(tmp_path_factory) -> Path:
    """`rlc simulate-test`'s default test (600 s of 0.1 m/s^2 ambient ground, actuators shaking at 5 %) and
    `rlc identify` of it, seeded."""
    folder = tmp_path_factory.mktemp("identified")
    (folder / "test.csv").write_text(
        simulate_test(TRUE, ambient_ground(0.1, 600.0, 0.02, 0), 0.05, 0).to_csv()
    )
    return identify([folder / "test.csv"], folder / "model", masses=MASSES)


@pytest.mark.slow
def test_ten_minutes_give_the_frequencies_to_1_percent_and_the_damping_to_20(ten_minutes):
    building = load_experiment_with(ten_minutes).building
    frequencies = 1 / TRUE.building.periods()
    text = (ten_minutes / "identification.md").read_text()
    identified = [
        float(line.split("|")[2].split("±")[0])
        for line in text.splitlines()
        if line[:4] in {f"| {n} " for n in range(1, 6)}
    ]
    np.testing.assert_allclose(identified, frequencies, rtol=0.01)
    model = Plant(load_experiment_with(ten_minutes)).building
    np.testing.assert_allclose(1 / model.periods(), frequencies, rtol=0.01)
    np.testing.assert_allclose(model.modal_damping_ratios(), TRUE.building.modal_damping_ratios(), rtol=0.2)
    assert building.state == "physical"


@pytest.mark.slow
def test_the_mode_shapes_are_the_buildings(ten_minutes):
    """Each identified shape's modal assurance criterion with the true one above 0.999."""
    _, shapes = natural_modes(TRUE.building.mass, TRUE.building.stiffness)
    text = (ten_minutes / "identification.md").read_text()
    rows = [line for line in text.splitlines() if line[:4] in {f"| {n} " for n in range(1, 6)}]
    for index, row in enumerate(rows):
        shape = np.array([float(cell.split("±")[0]) for cell in row.split("|")[4].split()])
        true = shapes[:, index]
        assert (shape @ true) ** 2 / ((shape @ shape) * (true @ true)) > 0.999


@pytest.mark.slow
def test_lqg_designed_on_the_identified_model_controls_the_true_building(ten_minutes, tmp_path):
    """Designed on the model, simulated on the true building (the plant part's building): J1 within 5 % of
    LQG designed on the true matrices, for each LQG variant, on generated motions."""
    identified = Plant(load_experiment_with(ten_minutes, tmp_path, true_plant=True))
    motions = generate_suite(Experiment().excitation.generator, 6, 11, TRUE.building)
    results = [
        run_evaluation(plant, motions, classical_controllers(plant), "case", include_optimal=False).summary()
        for plant in (TRUE, identified)
    ]
    np.testing.assert_allclose(results[1]["J1"], results[0]["J1"], rtol=0.05)


def load_experiment_with(model: Path, folder: Path | None = None, true_plant: bool = False):
    """The paper's experiment designed on the identified `model` (and simulated on the true building)."""
    folder = folder or model
    raw = Experiment().model_dump(mode="json") | {"building": str(model / "building.yaml")}
    if true_plant:
        raw["plant"] = {"building": Experiment().building.model_dump(mode="json")}
    (folder / "experiment.yaml").write_text(yaml.safe_dump(raw))
    return load_experiment(folder / "experiment.yaml")


def recording(duration=600.0, noise=0.05, ground=0.1, shake=0.05):
    plant = Plant(
        Experiment(
            sensors={
                "measurements": [{"quantity": "absolute_acceleration", "scale": 5.0, "noise_std": noise}]
            }
        )
    )
    return simulate_test(plant, ambient_ground(ground, duration, 0.02, 0), shake, 0)


@pytest.mark.parametrize(
    ("test", "band", "expected"),
    [
        (lambda: recording(duration=30.0), 20.0, "30 s is too short to identify 5 modes"),
        (
            lambda: recording(duration=60.0),
            20.0,
            "holds 42 periods of the first mode (1.44 s); record at least 100",
        ),
        (
            lambda: recording(duration=120.0),
            20.0,
            "holds 83 periods of the first mode (1.44 s); record at least 100",
        ),
        (lambda: recording(), 30.0, "too coarse for modes up to 30 Hz"),
        (lambda: recording(noise=3.0), 20.0, "too quiet"),
        (lambda: recording(ground=1e-9, shake=0.0), 20.0, "too quiet"),
    ],
)
@pytest.mark.slow
def test_what_cannot_be_identified_is_refused(test, band, expected):
    with pytest.raises(RecordingError) as error:
        identify_model([test()], 5, band)
    assert expected in str(error.value) and "\n" not in str(error.value)
