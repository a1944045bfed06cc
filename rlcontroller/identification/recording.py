"""A vibration test's recording: what its sensors record, one CSV per test.

    # comment lines (what the test was)
    time,ground,force_1,force_3,absolute_acceleration_1,...,absolute_acceleration_5

`time` (s, uniform), `ground` the measured ground acceleration (m/s^2), `force_<story>` each actuator's
force (N) from this sample until the next (a test may drive its actuators as shakers; an ambient test has
none), `absolute_acceleration_<floor>` each floor's absolute acceleration (m/s^2) read at the sample, after
the new forces apply. SI units. `simulate_test` makes one from an experiment's plant: a test run on a
simulated building, with the experiment's sensor noise, so that identification can be checked against the
building it came from.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rlcontroller.control.controllers import Uncontrolled
from rlcontroller.errors import RecordingError
from rlcontroller.physics.motions.excitation import Load
from rlcontroller.physics.plant import Plant
from rlcontroller.simulation.rollout import batch_rollout

ACCELERATION = "absolute_acceleration_"
FORCE = "force_"


@dataclass(frozen=True)
class Recording:
    """One test (`name`: its file): samples every `dt` s of the ground (m/s^2), the actuators' forces (N, one
    column per `actuators` label) and the floors' absolute accelerations (m/s^2, one column per `floors`)."""

    name: str
    dt: float
    ground: np.ndarray
    forces: np.ndarray
    accelerations: np.ndarray
    actuators: tuple[str, ...]
    floors: tuple[int, ...]

    @property
    def duration(self) -> float:
        return self.dt * (self.ground.size - 1)

    def to_csv(self, comment: str = "") -> str:
        header = [
            "time",
            "ground",
            *(FORCE + a for a in self.actuators),
            *(f"{ACCELERATION}{f}" for f in self.floors),
        ]
        time = np.arange(self.ground.size) * self.dt
        table = np.column_stack([time, self.ground, self.forces, self.accelerations])
        text = io.StringIO()
        text.write("".join(f"# {line}\n" for line in comment.splitlines()))
        text.write(",".join(header) + "\n")
        np.savetxt(text, table, delimiter=",", fmt="%.9g")
        return text.getvalue()


def read_recording(path: Path) -> Recording:
    """A recording from its CSV; a missing column, a gap in time, a value that is not a finite number or
    a row of the wrong length is a `RecordingError` naming the file and line."""
    try:
        lines = path.read_text().splitlines()
    except OSError as error:
        raise RecordingError(f"{path}: cannot read the file ({error.strerror})") from None
    except UnicodeDecodeError:
        raise RecordingError(f"{path}: not a text (UTF-8) file") from None
    numbered = [
        (number, line) for number, line in enumerate(lines, 1) if line.strip() and not line.startswith("#")
    ]
    if len(numbered) < 3:
        raise RecordingError(f"{path}: expected a header row and samples")
    header_line, header = numbered[0][0], [cell.strip() for cell in next(csv.reader([numbered[0][1]]))]
    floors = [column for column in header if column.startswith(ACCELERATION)]
    actuators = [column for column in header if column.startswith(FORCE)]
    known = {"time", "ground", *floors, *actuators}
    if (
        header[:2] != ["time", "ground"]
        or len(set(header)) != len(header)
        or set(header) != known
        or not floors
    ):
        raise RecordingError(
            f"{path}:{header_line}: expected the columns time, ground, force_<story>..., "
            f"{ACCELERATION}<floor>... (each once), got {','.join(header)}"
        )
    try:
        floor_numbers = tuple(int(column.removeprefix(ACCELERATION)) for column in floors)
    except ValueError:
        raise RecordingError(
            f"{path}:{header_line}: a floor is named by its number, e.g. {ACCELERATION}3"
        ) from None
    for column in actuators:
        story = column.removeprefix(FORCE)
        if not story.isdigit() or not 1 <= int(story) <= max(floor_numbers):
            raise RecordingError(
                f"{path}:{header_line}: {column}: expected the number of a story the accelerations cover, 1 "
                f"to {max(floor_numbers)} (the top floor recorded is {ACCELERATION}{max(floor_numbers)})"
            )
    rows = []
    for number, line in numbered[1:]:
        cells = line.split(",")
        if len(cells) != len(header):
            raise RecordingError(
                f"{path}:{number}: {len(cells)} values, expected {len(header)} like the header"
            )
        try:
            values = [float(cell) for cell in cells]
        except ValueError:
            raise RecordingError(f"{path}:{number}: expected numbers, got {line.strip()[:60]!r}") from None
        if not all(np.isfinite(values)):
            column = header[int(np.argmin(np.isfinite(values)))]
            raise RecordingError(
                f"{path}:{number}: {column} is not a finite number (a gap in the recording?)"
            )
        rows.append(values)
    table = np.array(rows)
    steps = np.diff(table[:, 0])
    dt = float(f"{np.median(steps):.12g}")  # the step as written, not its rounding in the subtraction
    uneven = np.abs(steps - dt) > 1e-6 * dt
    if dt <= 0.0 or np.any(uneven):
        line = numbered[2 + int(np.argmax(uneven))][0] if np.any(uneven) else numbered[1][0]
        raise RecordingError(
            f"{path}:{line}: time must advance by the same step ({dt:g} s): a gap or a repeat"
        )
    first = 2 + len(actuators)
    return Recording(
        name=str(path),
        dt=dt,
        ground=table[:, 1],
        forces=table[:, 2:first],
        accelerations=table[:, first:],
        actuators=tuple(column.removeprefix(FORCE) for column in actuators),
        floors=floor_numbers,
    )


class Shakers:
    """The actuators driven open loop by a given sequence of actions (one row per control step)."""

    name = "shakers"

    def __init__(self, actions: np.ndarray) -> None:
        self.actions = actions
        self.step = 0

    def reset(self) -> None:
        self.step = 0

    def act(self, observation: np.ndarray) -> np.ndarray:
        action = self.actions[min(self.step, len(self.actions) - 1)]
        self.step += 1
        return np.broadcast_to(action, (*np.shape(observation)[:-1], action.size)).copy()


def simulate_test(plant: Plant, ground: Load, shaking: float, seed: int) -> Recording:
    """A test on the simulated `plant`: the ground `ground` and, with `shaking` > 0, every actuator driven by
    white noise of that RMS (a fraction of its force limit, held over each control step); recorded at the
    control step with the experiment's sensor noise on every floor's absolute acceleration (the noise of
    its absolute acceleration sensors, else 0) and on the ground (`sensors.ground_noise_std`)."""
    rng = np.random.default_rng(seed)
    m, control_dt = plant.building.n_actuators, plant.control_dt
    steps = int(round(ground.duration / control_dt))
    actions = np.clip(shaking * rng.standard_normal((steps + 1, m)), -1.0, 1.0)
    controller = Shakers(actions) if shaking > 0 else Uncontrolled(m)
    response = batch_rollout(plant, [ground], [controller])[0][0][0]
    applied = np.vstack([response.force[1:], actions[-1:] * plant.force_limits])  # from each sample on
    _, feedthrough = plant.outputs("absolute_acceleration")
    accelerations = response.absolute_acceleration + (applied - response.force) @ feedthrough.T
    sensors = plant.experiment.sensors
    noise = [m.noise_std for m in sensors.measurements if m.quantity == "absolute_acceleration"]
    accelerations = accelerations + (noise[0] if noise else 0.0) * rng.standard_normal(accelerations.shape)
    measured_ground = response.ground + sensors.ground_noise_std * rng.standard_normal(response.ground.shape)
    labels = plant.experiment.command_labels()
    return Recording(
        name=ground.name,
        dt=control_dt,
        ground=measured_ground,
        forces=applied if shaking > 0 else np.zeros((applied.shape[0], 0)),
        accelerations=accelerations,
        actuators=tuple(labels) if shaking > 0 else (),
        floors=tuple(range(1, plant.building.n_floors + 1)),
    )


def ambient_ground(rms: float, duration: float, dt: float, seed: int) -> Load:
    """Ambient vibration: white-noise ground acceleration of `rms` (m/s^2) sampled every `dt` s."""
    rng = np.random.default_rng([seed, 1])
    return Load(name="ambient", dt=dt, acceleration=rms * rng.standard_normal(int(round(duration / dt)) + 1))
