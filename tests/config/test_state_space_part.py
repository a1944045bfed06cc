"""A state-space building part: read from an .npz as data, checked, and refused in one line naming the file
and the field where it cannot be what the experiment asks of it."""

import io
import zipfile

import numpy as np
import pytest
import scipy.signal
import yaml

from rlcontroller.config import ConfigError, Experiment, load_experiment
from rlcontroller.physics.dynamics import state_space_arrays
from rlcontroller.physics.plant import Plant
from rlcontroller.physics.state_space import state_space_outputs

# the paper's five-story building, actuators 1, 3, 5
ARRAYS = state_space_arrays(Plant(Experiment()).building)


def write(folder, arrays=None, experiment=None, **part) -> str:
    """An experiment whose building is `arrays` (default: the five-story building's model) in `folder`."""
    np.savez(folder / "model.npz", **(ARRAYS if arrays is None else arrays))
    building = {"state_space": "model.npz", "inputs": {"actuators": [0, 1, 2], "ground": 3}}
    building["outputs"] = state_space_outputs(5)
    building.update(part)
    raw = {"building": building, **(experiment or {})}
    (folder / "experiment.yaml").write_text(yaml.safe_dump(raw))
    return str(folder / "experiment.yaml")


def test_a_model_loads_and_keeps_what_it_was_given(tmp_path):
    experiment = load_experiment(write(tmp_path))
    np.testing.assert_array_equal(experiment.building.state_matrix, ARRAYS["A"])
    assert experiment.building.n_floors == 5 and experiment.building.source.endswith("model.npz")


DISCRETE_A, DISCRETE_B, *_ = scipy.signal.cont2discrete(
    (ARRAYS["A"], ARRAYS["B"], ARRAYS["C"], ARRAYS["D"]), 0.003
)
DISCRETE_3_MS = {"A": DISCRETE_A, "B": DISCRETE_B, "dt": 0.003}
UNSTABLE = ARRAYS["A"].copy()
UNSTABLE[5, 0] = 1.0e6  # a floor pushed away by its own displacement


@pytest.mark.parametrize(
    ("arrays", "part", "experiment", "expected"),
    [
        ({"A": ARRAYS["A"][:, :9]}, {}, {}, "state_matrix (A) must be square"),
        ({"A": UNSTABLE}, {}, {}, "unstable or undamped pole"),
        ({"A": np.full((10, 10), np.nan)}, {}, {}, "state_matrix[0][0]: Input should be a finite number"),
        (DISCRETE_3_MS, {}, {}, "sample_time: 0.003 s does not divide the control step (0.02 s)"),
        ({"D": ARRAYS["D"] + np.eye(25, 4, k=-3)}, {}, {}, "D's ground column is 1, expected 0"),
        (
            {},
            {"inputs": {"actuators": [0, 1], "ground": 3}},
            {},
            "inputs.actuators: 2 columns, expected one per actuator (3",
        ),
        (
            {},
            {"inputs": {"actuators": [0, 1, 9], "ground": 3}},
            {},
            "inputs: 9 is not a column of B, expected 0..3",
        ),
        (
            {},
            {"outputs": {"drift": [10, 11], "absolute_acceleration": [15, 16, 17, 18, 19]}},
            {},
            "5 rows, expected 2",
        ),
        ({}, {"outputs": {"absolute_acceleration": [15, 16, 17, 18, 19]}}, {}, "drift"),
        (
            {},
            {"outputs": {"drift": [10, 11, 12, 13, 14]}},
            {},
            "reads absolute_acceleration, which the state-space model",
        ),
        ({}, {}, {"sensors": {"state_estimate": True}}, "needs a model with state: physical"),
        ({}, {}, {"simulation": {"method": "newmark"}}, "method: newmark needs M, K, C"),
        ({}, {}, {"plant": {"stiffness": 0.9}}, "plant.stiffness: a state-space model has no stiffness"),
        (
            {},
            {},
            {"devices": [{"type": "tuned_mass", "floor": 5, "mass_ratio": 0.02}]},
            "devices on a state-space model",
        ),
    ],
)
def test_a_model_that_cannot_be_the_building_is_one_line(tmp_path, arrays, part, experiment, expected):
    path = write(tmp_path, ARRAYS | arrays, experiment, **part)
    with pytest.raises(ConfigError) as error:
        load_experiment(path)
    message = str(error.value)
    assert expected in message and "\n" not in message and "experiment.yaml" in message


@pytest.mark.parametrize(
    ("arrays", "expected"),
    [
        (ARRAYS | {"A": np.array([object()] * 4)}, "A: dtype object, expected numbers"),  # never unpickled
        (ARRAYS | {"A": ARRAYS["A"] + 0j}, "A: dtype complex128, expected numbers"),
        (ARRAYS | {"A": ARRAYS["A"] > 0}, "array 'A' holds bool, expected real numbers"),
        ({key: ARRAYS[key] for key in "ABC"}, "no array 'D'"),
        (ARRAYS | {"E": ARRAYS["A"]}, "unknown arrays ['E']"),
    ],
)
def test_a_model_file_is_data_and_read_as_such(tmp_path, arrays, expected):
    np.savez(tmp_path / "model.npz", **arrays)
    path = write(tmp_path, arrays)
    with pytest.raises(ConfigError, match=None) as error:
        load_experiment(path)
    assert expected in str(error.value) and "model.npz" in str(error.value)


def test_an_array_header_declaring_more_than_the_file_holds_is_refused_before_reading(tmp_path):
    """A forged header (745 GiB declared, 16 bytes stored) is refused from the header, never allocated."""
    path = write(tmp_path)
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        header, {"descr": "<f8", "fortran_order": False, "shape": (100000, 1000000)}
    )
    with zipfile.ZipFile(tmp_path / "model.npz", "a") as archive:
        archive.writestr("dt.npy", header.getvalue() + bytes(16))
    with pytest.raises(ConfigError) as error:
        load_experiment(path)
    expected = "model.npz: dt: its header declares (100000, 1000000) of float64, the file holds other bytes"
    assert expected in str(error.value)


def test_the_plant_may_be_another_building_than_the_design_model(tmp_path):
    """Designed on a state-space model, simulated as the shear building given in the plant part."""
    path = write(tmp_path, experiment={"plant": {"building": {"stiffnesses": [4.5e6, 4e6, 4e6, 3e6, 3e6]}}})
    plant = Plant(load_experiment(path))
    assert plant.building.stiffness[0, 0] == 4.5e6 + 4e6
    assert plant.design.building.a.shape == (10, 10)
