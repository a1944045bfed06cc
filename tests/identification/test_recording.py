"""A test recording: written and read back as it was, and a damaged one refused in one line naming the file
and line."""

import numpy as np
import pytest

from rlcontroller.config import Experiment
from rlcontroller.errors import RecordingError
from rlcontroller.identification.recording import ambient_ground, read_recording, simulate_test
from rlcontroller.physics.plant import Plant


@pytest.fixture(scope="module")
def recording():
    return simulate_test(Plant(Experiment()), ambient_ground(0.1, 20.0, 0.02, 0), 0.05, 0)


def test_a_recording_reads_back_as_written(recording, tmp_path):
    path = tmp_path / "test.csv"
    path.write_text(recording.to_csv("a comment\nover two lines"))
    read = read_recording(path)
    assert (read.actuators, read.floors, read.dt) == (("1", "3", "5"), (1, 2, 3, 4, 5), 0.02)
    for name in ("ground", "forces", "accelerations"):
        np.testing.assert_allclose(getattr(read, name), getattr(recording, name), rtol=1e-8, atol=1e-12)


def test_the_recorded_forces_are_the_shaking_and_the_readings_carry_the_sensors_noise(recording):
    """Forces of 5 % of the 100 kN limits (RMS), held from each sample on; the floors' readings differ from
    the noise-free response by the experiment's 0.05 m/s^2 noise (RMS), the ground's by its own."""
    assert recording.forces.shape == (1001, 3) and 4e3 < np.std(recording.forces) < 6e3
    quiet = simulate_test(
        Plant(Experiment(sensors={"ground_noise_std": 0.0})), ambient_ground(0.1, 20.0, 0.02, 0), 0.05, 0
    )
    noise = recording.ground - quiet.ground
    assert 0.045 < np.std(noise) < 0.055


@pytest.mark.parametrize(
    ("edit", "expected"),
    [
        (
            lambda lines: lines[:3] + ["0.06,nan" + lines[3][lines[3].index(",", 5) :]] + lines[4:],
            ":4: ground is not a finite",
        ),
        (lambda lines: lines[:3] + lines[4:], ":4: time must advance by the same step"),
        (lambda lines: lines[:3] + ["0.04,1,2"] + lines[4:], ":4: 3 values, expected 10"),
        (lambda lines: ["time,ground,force_1,acc_1"] + lines[1:], ":1: expected the columns time, ground"),
        (lambda lines: lines[:2], "expected a header row and samples"),
        # floor 5's accelerometer missing, the force on story 5 still there: never a 4-floor model silently
        (
            lambda lines: [line.rsplit(",", 1)[0] for line in lines],
            ":1: force_5: expected the number of a story the accelerations cover, 1 to 4",
        ),
        (
            lambda lines: [lines[0].replace("force_3", "force_x")] + lines[1:],
            ":1: force_x: expected the number",
        ),
    ],
)
def test_a_damaged_recording_is_refused_in_one_line(recording, tmp_path, edit, expected):
    path = tmp_path / "bad.csv"
    lines = recording.to_csv().splitlines()
    path.write_text("\n".join(edit(lines)) + "\n")
    with pytest.raises(RecordingError) as error:
        read_recording(path)
    assert (
        str(error.value).startswith(str(path))
        and expected in str(error.value)
        and "\n" not in str(error.value)
    )
