"""Loads: ground motions (PEER NGA .AT2 and CSV records, generators) and records of floor forces, their
resampling onto a control grid, and scaling.

A `Load` is one of two kinds: a ground acceleration (uniform excitation of the base) or forces on the
floors (wind, or any measured force record), with a ground acceleration of zero. Every load is held in
SI units (m/s^2, N) from the moment it is read: records in g are converted once, here. Between samples a
load is piecewise linear.
"""

from __future__ import annotations

import csv
import hashlib
import math
import re
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from rlcontroller.config import (
    MAX_DURATION,
    MAX_GROUND_ACCELERATION,
    MAX_TIME_STEP,
    MIN_TIME_STEP,
)
from rlcontroller.errors import MotionError  # noqa: F401  (raised here; imported from here too)

STANDARD_GRAVITY = 9.80665  # m/s^2
UNITS_TO_SI = {"g": STANDARD_GRAVITY, "gal": 0.01}  # and the common spellings of m/s^2 and cm/s^2:
UNITS_TO_SI |= {f"m{per}": 1.0 for per in ("/s2", "/s^2", "/s²", "/s/s", "_s2", "ps2")}
UNITS_TO_SI |= {f"cm{per}": 0.01 for per in ("/s2", "/s^2", "/s²", "/s/s", "_s2", "ps2")}


SETTLING_TAIL_S = 20.0  # s of zero ground motion after a record on a yielding plant (its residual drift)
GROUND_ACCELERATION = "ground_acceleration"
FLOOR_FORCES = "floor_forces"


@dataclass(frozen=True)
class Load:
    """A ground acceleration history (m/s^2) sampled every `dt` seconds from t = 0; for a load on the
    floors instead (wind), `floor_forces` (samples, floors) in N, with a ground acceleration of zero."""

    name: str
    dt: float
    acceleration: np.ndarray = field(repr=False)
    synthetic: bool = False
    description: str = ""  # e.g. event and station, from a manifest
    floor_forces: np.ndarray | None = field(default=None, repr=False)

    @property
    def duration(self) -> float:
        return self.dt * (self.acceleration.size - 1)

    @property
    def pga(self) -> float:
        """Peak ground acceleration (m/s^2)."""
        return float(np.max(np.abs(self.acceleration)))

    @property
    def time(self) -> np.ndarray:
        return np.arange(self.acceleration.size) * self.dt

    @property
    def kind(self) -> str:
        """`GROUND_ACCELERATION` or `FLOOR_FORCES`."""
        return GROUND_ACCELERATION if self.floor_forces is None else FLOOR_FORCES


_WEST2_HEADER = re.compile(r"NPTS\s*=\s*(\d+)\s*,?\s*DT\s*=\s*([0-9.Ee+-]+)", re.IGNORECASE)
_WEST1_HEADER = re.compile(r"^\s*(\d+)\s+([0-9.Ee+-]+)\s+NPTS", re.IGNORECASE)


def checked(motion: Load, where: str) -> Load:
    """The motion if it is one a building can be judged on, else a MotionError naming `where`:
    at least two samples, a time step in [1e-4, 1] s, at most an hour, finite, not all zero,
    and a PGA of at most about 10 g (more is a unit mistake)."""
    count = motion.acceleration.size
    if count < 2:
        raise MotionError(f"{where}: {count} samples, expected at least 2")
    if not (math.isfinite(motion.dt) and MIN_TIME_STEP <= motion.dt <= MAX_TIME_STEP):
        raise MotionError(
            f"{where}: time step {motion.dt!r} s, expected {MIN_TIME_STEP:g} to {MAX_TIME_STEP:g} s"
        )
    if motion.duration > MAX_DURATION:
        raise MotionError(f"{where}: lasts {motion.duration:.0f} s, expected at most {MAX_DURATION:.0f} s")
    if not np.all(np.isfinite(motion.acceleration)):
        raise MotionError(f"{where}: the record holds non-finite values")
    if motion.pga == 0.0:
        raise MotionError(f"{where}: every sample is zero; there is nothing to control")
    if motion.pga > MAX_GROUND_ACCELERATION:
        raise MotionError(
            f"{where}: PGA {motion.pga / STANDARD_GRAVITY:.3g} g, expected at most "
            f"{MAX_GROUND_ACCELERATION / STANDARD_GRAVITY:.3g} g (wrong unit?)"
        )
    return motion


def read_at2(path: str | Path) -> Load:
    """Read a PEER NGA (West1 or West2) .AT2 acceleration file in units of g."""
    path = Path(path)
    try:
        lines = path.read_text(errors="replace").splitlines()
    except OSError as error:
        raise MotionError(f"{path}: cannot read the file ({error.strerror})") from None
    if len(lines) < 4:
        raise MotionError(f"{path}: expected a 4-line PEER header, the file has {len(lines)} lines")
    if "UNITS OF G" not in lines[2].upper():
        raise MotionError(f"{path}:3: expected 'ACCELERATION ... IN UNITS OF G', got {lines[2].strip()!r}")
    header = _WEST2_HEADER.search(lines[3]) or _WEST1_HEADER.search(lines[3])
    if header is None:
        raise MotionError(f"{path}:4: expected 'NPTS=..., DT=...' (NGA-West2) or 'n dt NPTS, DT' (NGA-West1)")
    npts = int(header.group(1))
    try:
        dt = float(header.group(2))
    except ValueError:
        raise MotionError(f"{path}:4: DT must be a number, got {header.group(2)!r}") from None
    if not (math.isfinite(dt) and MIN_TIME_STEP <= dt <= MAX_TIME_STEP):
        raise MotionError(
            f"{path}:4: DT = {header.group(2)} s, expected {MIN_TIME_STEP:g} to {MAX_TIME_STEP:g} s"
        )
    if npts < 2 or npts * dt > MAX_DURATION:
        raise MotionError(
            f"{path}:4: NPTS = {npts}, expected at least 2 samples and at most {MAX_DURATION:.0f} s of record"
        )
    values: list[float] = []
    for number, line in enumerate(lines[4:], start=5):
        for token in line.split():
            try:
                values.append(float(token))
            except ValueError:
                raise MotionError(f"{path}:{number}: expected a number, got {token!r}") from None
    if len(values) != npts:
        what = "truncated?" if len(values) < npts else "extra values?"
        raise MotionError(f"{path}: header says NPTS={npts} but the file holds {len(values)} values ({what})")
    return checked(Load(name=path.stem, dt=dt, acceleration=np.asarray(values) * STANDARD_GRAVITY), str(path))


def read_csv(path: str | Path, unit: str | None = None) -> Load:
    """Read a two-column CSV (time in s, acceleration) with a header row.

    The unit is `unit` or taken from the second header, e.g. 'acceleration [g]', 'acc_m/s2';
    known units: g, m/s2 and cm/s2 (gal), also written /s^2, /s², /s/s, _s2 or ps2. Unevenly spaced
    times are interpolated to their median step.
    """
    path = Path(path)
    try:
        rows = list(csv.reader(path.read_text().splitlines()))
    except OSError as error:
        raise MotionError(f"{path}: cannot read the file ({error.strerror})") from None
    except UnicodeDecodeError:
        raise MotionError(f"{path}: not a text (UTF-8) file") from None
    if len(rows) < 3:
        raise MotionError(f"{path}: expected a header row and at least two samples")
    header = [cell.strip().lower() for cell in rows[0]]
    if len(header) > 2:
        return read_force_csv(path, rows)
    if unit is None:
        found = [
            u
            for u in UNITS_TO_SI
            if len(header) > 1 and re.search(rf"[\s_\[(]{re.escape(u)}[\])]?$", header[1])
        ]
        if not found:
            raise MotionError(
                f"{path}:1: cannot tell the acceleration unit from {rows[0]!r}; expected e.g. 'acceleration "
                "[g]'"
            )
        unit = max(found, key=len)
    if unit not in UNITS_TO_SI:
        raise MotionError(f"{path}: unknown unit {unit!r}, expected one of {sorted(UNITS_TO_SI)}")
    time, acceleration = [], []
    for number, row in enumerate(rows[1:], start=2):
        if not row or not "".join(row).strip():
            continue
        if len(row) != 2:
            raise MotionError(f"{path}:{number}: expected 2 columns (time, acceleration), got {len(row)}")
        try:
            time.append(float(row[0]))
            acceleration.append(float(row[1]))
        except ValueError:
            raise MotionError(f"{path}:{number}: expected two numbers, got {row!r}") from None
    times = np.asarray(time)
    if times.size < 2:
        raise MotionError(f"{path}: {times.size} samples, expected at least 2")
    if not np.all(np.isfinite(times)):
        raise MotionError(f"{path}:{int(np.argmax(~np.isfinite(times))) + 2}: time must be a finite number")
    steps = np.diff(times)
    if np.any(steps <= 0):
        bad = int(np.argmax(steps <= 0)) + 3
        raise MotionError(f"{path}:{bad}: time must increase strictly")
    values = np.asarray(acceleration) * UNITS_TO_SI[unit]
    dt = float(np.median(steps))
    motion = checked(Load(name=path.stem, dt=dt, acceleration=values), str(path))
    if times[-1] - times[0] > MAX_DURATION:
        raise MotionError(
            f"{path}: lasts {times[-1] - times[0]:.0f} s, expected at most {MAX_DURATION:.0f} s"
        )
    if np.allclose(steps, dt, rtol=1e-6, atol=0.0):
        return motion
    uniform = np.arange(0.0, times[-1] - times[0] + 0.5 * dt, dt)
    return Load(name=path.stem, dt=dt, acceleration=np.interp(uniform, times - times[0], values))


MOTION_SUFFIXES = (".at2", ".csv")


FORCE_UNITS = {"n": 1.0, "kn": 1.0e3, "mn": 1.0e6}
FORCE_UNIT = re.compile(r"[\s_\[(](n|kn|mn)[\])]?$")  # the unit at the end of a column's header
MAX_FLOOR_FORCE = 1.0e9  # N per floor: beyond it a value is a unit mistake


def read_force_csv(path: Path, rows: list[list[str]]) -> Load:
    """A record of measured floor forces: a header `time, floor 1 [kN], floor 2 [kN], ...` (N, kN or
    MN, one column per floor from floor 1, the same unit for all) and evenly spaced times (s)."""
    header = [cell.strip().lower() for cell in rows[0]]
    matches = [FORCE_UNIT.search(cell) for cell in header[1:]]
    units = {match.group(1) for match in matches if match}
    if len(units) != 1 or not all(matches):
        raise MotionError(
            f"{path}:1: floor-force columns need one unit, e.g. 'floor 1 [kN]' (N, kN or MN), got {rows[0]!r}"
        )
    columns = len(header)
    values = []
    for number, row in enumerate(rows[1:], start=2):
        if not row or not "".join(row).strip():
            continue
        if len(row) != columns:
            raise MotionError(
                f"{path}:{number}: expected {columns} columns (time and {columns - 1} floors), got {len(row)}"
            )
        try:
            values.append([float(cell) for cell in row])
        except ValueError:
            raise MotionError(f"{path}:{number}: expected {columns} numbers, got {row!r}") from None
    table = np.asarray(values)
    if table.shape[0] < 2:
        raise MotionError(f"{path}: {table.shape[0]} samples, expected at least 2")
    if not np.all(np.isfinite(table)):
        line = int(np.argmax(~np.all(np.isfinite(table), axis=1))) + 2
        raise MotionError(f"{path}:{line}: every value must be a finite number")
    times, forces = table[:, 0], table[:, 1:] * FORCE_UNITS[units.pop()]
    steps = np.diff(times)
    if np.any(steps <= 0):
        raise MotionError(f"{path}:{int(np.argmax(steps <= 0)) + 3}: time must increase strictly")
    dt = float(np.median(steps))
    if not np.allclose(steps, dt, rtol=1e-6, atol=0.0):
        raise MotionError(f"{path}: the times must be evenly spaced (median step {dt:g} s)")
    if not (MIN_TIME_STEP <= dt <= MAX_TIME_STEP):
        raise MotionError(f"{path}: time step {dt:g} s, expected {MIN_TIME_STEP:g} to {MAX_TIME_STEP:g} s")
    if times[-1] - times[0] > MAX_DURATION:
        raise MotionError(
            f"{path}: lasts {times[-1] - times[0]:.0f} s, expected at most {MAX_DURATION:.0f} s"
        )
    if np.max(np.abs(forces)) > MAX_FLOOR_FORCE:
        raise MotionError(
            f"{path}: a force of {np.max(np.abs(forces)):.3g} N, expected at most {MAX_FLOOR_FORCE:g} N"
        )
    if not np.any(forces):
        raise MotionError(f"{path}: every force is zero: nothing loads the building")
    zero = np.zeros(times.size)
    return Load(name=path.stem, dt=dt, acceleration=zero, floor_forces=forces)


def read_motion(path: str | Path) -> Load:
    """Read a .AT2 or .csv ground-motion file by its extension."""
    path = Path(path)
    if path.suffix.lower() == ".at2":
        return read_at2(path)
    if path.suffix.lower() == ".csv":
        return read_csv(path)
    raise MotionError(f"{path}: unknown ground-motion format {path.suffix!r}, expected .AT2 or .csv")


def resample(motion: Load, dt: float) -> Load:
    """Linear interpolation onto a grid of step `dt` (s) (exact for the piecewise-linear motion
    when the new grid contains the old one)."""
    if math.isclose(dt, motion.dt, rel_tol=1e-9):
        return motion
    count = int(math.floor(motion.duration / dt + 1e-9)) + 1
    grid = np.arange(count) * dt
    forces = motion.floor_forces
    if forces is not None:
        forces = np.stack([np.interp(grid, motion.time, column) for column in forces.T], axis=1)
    return replace(
        motion, dt=dt, acceleration=np.interp(grid, motion.time, motion.acceleration), floor_forces=forces
    )


def scale_to_pga(motion: Load, pga: float) -> Load:
    """The motion scaled to a peak ground acceleration `pga` (m/s^2)."""
    if motion.floor_forces is not None:
        raise MotionError(f"{motion.name}: a record of floor forces has no ground acceleration to scale")
    return replace(motion, acceleration=motion.acceleration * (pga / motion.pga))


def with_settling_tail(motion: Load) -> Load:
    """The motion followed by SETTLING_TAIL_S of zero ground motion and floor loads (for residual drifts)."""
    tail = np.zeros(round(SETTLING_TAIL_S / motion.dt))
    forces = motion.floor_forces
    if forces is not None:
        forces = np.concatenate([forces, np.zeros((tail.size, forces.shape[1]))])
    return replace(motion, acceleration=np.concatenate([motion.acceleration, tail]), floor_forces=forces)


@dataclass(frozen=True)
class LoadGrid:
    """A load on the grid a plant steps on: `substeps` samples per control step, never decimated.

    `ground` (samples,) m/s^2 and `floor_forces` (samples, floors) N or None, at control_dt / substeps;
    `n_steps` whole control steps."""

    ground: np.ndarray = field(repr=False)
    floor_forces: np.ndarray | None = field(repr=False)
    substeps: int

    @property
    def n_steps(self) -> int:
        return (self.ground.size - 1) // self.substeps

    @property
    def ground_at_steps(self) -> np.ndarray:
        """The ground acceleration at the control instants 0..n_steps (m/s^2)."""
        return self.ground[:: self.substeps][: self.n_steps + 1]

    @property
    def forces_at_steps(self) -> np.ndarray | None:
        """The floor forces at the control instants 0..n_steps (N), or None."""
        return None if self.floor_forces is None else self.floor_forces[:: self.substeps][: self.n_steps + 1]

    def step_windows(self) -> tuple[np.ndarray, np.ndarray | None]:
        """What a plant's own integrator takes per control step (views): the r + 1 ground samples spanning
        each step (steps, r + 1), and the floor forces' (steps, r + 1, floors) or None."""
        r = self.substeps
        ground = sliding_window_view(self.ground, r + 1)[::r][: self.n_steps]
        if self.floor_forces is None:
            return ground, None
        return ground, sliding_window_view(self.floor_forces, r + 1, axis=0)[::r][: self.n_steps].swapaxes(
            1, 2
        )


def on_control_grid(load: Load, control_dt: float) -> LoadGrid:
    """The load sampled at control_dt / r with r = ceil(control_dt / load.dt): never decimated; resampled
    only if its step does not divide control_dt."""
    if load.duration < control_dt:
        raise MotionError(
            f"{load.name}: lasts {load.duration:g} s, shorter than one control step ({control_dt:g} s)"
        )
    substeps = max(1, math.ceil(control_dt / load.dt - 1e-9))
    resampled = resample(load, control_dt / substeps)
    return LoadGrid(resampled.acceleration, resampled.floor_forces, substeps)


SAME_BITS = 16  # a generated load's resolution: 2^-16 of the power of two above its peak


def same_on_every_cpu(samples: np.ndarray) -> np.ndarray:
    """Generated samples rounded to a multiple of 2^-SAME_BITS of the power of two above their peak (at most
    3e-5 of the peak: far below any sensor's noise). A BLAS kernel changes the last bits of a generator's
    float64 arithmetic from one CPU to another (by about 1e-13 of the peak for wind), and `content_seed`
    hashes the samples, so a load's sensor noise would change with the CPU (a check motion's J1 moved by up to
    0.2 that way, float32 rounding still left 44 of 13.9 million wind samples different); rounded this
    coarsely they are the same on every CPU but for about one sample in 10^8."""
    samples = np.asarray(samples, dtype=np.float64)
    peak = float(np.max(np.abs(samples), initial=0.0))
    if peak == 0.0:
        return samples.copy()
    quantum = np.ldexp(1.0, np.frexp(peak)[1] - SAME_BITS)  # exact: a power of two
    return np.round(samples / quantum) * quantum


def content_seed(motion: Load, seed: int = 0) -> int:
    """A seed fixed by the motion's samples and time step and by `seed`, not by its name, file or
    position in a suite: the same record gets the same sensor noise wherever it is evaluated."""
    content = (
        np.float64(motion.dt).tobytes()
        + np.ascontiguousarray(motion.acceleration, dtype=np.float64).tobytes()
    )
    if motion.floor_forces is not None:
        content += np.ascontiguousarray(motion.floor_forces, dtype=np.float64).tobytes()
    digest = hashlib.sha256(content + int(seed).to_bytes(8, "little", signed=False)).digest()
    return int.from_bytes(digest[:8], "little") >> 1
