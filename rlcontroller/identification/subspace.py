"""A building's state-space model identified from vibration tests (`recording`): combined deterministic-
stochastic subspace identification (N4SID, Van Overschee and De Moor 1994, Automatica 30(1); the `nfoursid`
package's implementation) with the measured ground and the actuators' forces as inputs and the floors'
absolute accelerations as outputs.

Why input-output N4SID rather than output-only stochastic subspace identification (pyOMA2's SSI): a controller
is designed on how the actuators and the ground drive the building (B), which output-only identification
cannot give; and with the ground measured, ambient data goes further (the known part of the excitation is not
noise).

The steps, each a choice a user can read in the report:
1. where the recording is sampled finer than 2.5 times the band of interest (`--band`, 20 Hz by default),
   every channel low-pass filtered and decimated alike (inputs and outputs through the same filter keep their
   relation);
2. N4SID of order 2 x modes, its block rows spanning 8 periods of the band's edge, then (identified again)
   the first mode's period, as far as the recording allows;
3. the continuous model: the ground piecewise linear between samples, the actuators' forces held between them
   (piecewise linear too once decimation has smoothed them); its poles the modes (frequency, damping ratio);
   its displacement and velocity rows derived from the accelerations through the model (x'' = a - a_g, so
   x = C_a A^-2 z, v = C_a A^-1 z: exact for a model of a structure); with one mode per floor, the state
   changed to [x; v] (`state: physical`);
4. the uncertainty of each frequency, damping ratio and mode shape from the scatter of the same identification
   on four equal segments (standard error: their standard deviation over 2).

What cannot be identified is refused, never invented: a recording shorter than 100 periods of the longest mode
found, a band above the Nyquist frequency, fewer oscillating modes below the band than asked, or a model that
explains less than half of a floor's measured acceleration (too quiet: the sensors' noise dominates).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
import scipy.linalg
import scipy.signal
from nfoursid.nfoursid import NFourSID
from nfoursid.utils import Decomposition, Utils

from rlcontroller.errors import RecordingError
from rlcontroller.identification.recording import Recording

OVERSAMPLING = 2.5  # the decimated rate over the band's edge
BLOCK_PERIODS = 8  # block rows span this many periods of the band's edge
MIN_PERIODS = 100  # a recording must hold this many periods of the longest mode found
MIN_EXPLAINED = 0.5  # of each floor's acceleration variance
SEGMENTS = 4


@dataclass(frozen=True)
class Mode:
    """One identified mode: frequency (Hz), damping ratio, shape (the floors' displacements, largest 1), and
    their standard errors."""

    frequency: float
    damping: float
    shape: np.ndarray
    frequency_error: float = math.nan
    damping_error: float = math.nan
    shape_error: np.ndarray = field(default_factory=lambda: np.zeros(0))


@dataclass(frozen=True)
class Identified:
    """The identified model as a state-space building file's arrays (`A`, `B`, `C`, `D`, continuous, SI;
    inputs: the actuators' forces then the ground; outputs: displacement, velocity, drift, absolute
    acceleration and, with the floor masses, story shear rows per floor), whether its state is physical,
    its modes, the variance of each floor's acceleration it explains, the ground feed-through it dropped
    (m/s^2 per m/s^2), and the sample time, block rows and decimation it used."""

    arrays: dict[str, np.ndarray]
    physical: bool
    modes: list[Mode]
    explained: np.ndarray
    dropped_feedthrough: float
    sample_time: float
    block_rows: int
    decimation: int  # samples of the recording per sample identified on


def identify(
    recordings: list[Recording], modes: int, band: float, masses: np.ndarray | None = None
) -> Identified:
    """The model of `modes` modes below `band` Hz from one or more recordings of the same sensors
    (concatenated after decimation), with story shear rows where the floor `masses` (kg) are given; a
    `RecordingError` says what is missing where it cannot be identified."""
    first = recordings[0]
    for recording in recordings[1:]:
        if (recording.floors, recording.actuators, recording.dt) != (first.floors, first.actuators, first.dt):
            raise RecordingError(
                f"{recording.name}: channels or sampling differ from {first.name}'s; identify one set of "
                "sensors"
            )
    floors = len(first.floors)
    if sorted(first.floors) != list(range(1, floors + 1)):
        raise RecordingError(
            f"{first.name}: needs an acceleration on every floor 1..{max(first.floors)} (drifts)"
        )
    nyquist = 0.5 / first.dt
    if band > nyquist:
        raise RecordingError(
            f"{first.name}: sampled every {first.dt:g} s (Nyquist {nyquist:g} Hz), too coarse for modes up "
            f"to {band:g} Hz; sample at least every {0.5 / band:.3g} s or lower --band"
        )
    if np.std(first.ground) == 0.0:
        raise RecordingError(f"{first.name}: the ground channel is constant: nothing excites the building")
    factor = max(1, int(1.0 / (first.dt * OVERSAMPLING * band)))
    inputs, outputs = zip(*(_decimated(recording, factor) for recording in recordings), strict=True)
    inputs, outputs = np.vstack(inputs), np.vstack(outputs)
    dt = first.dt * factor
    block_rows = max(math.ceil(BLOCK_PERIODS / (band * dt)), math.ceil(2 * modes / floors) + 1)
    if inputs.shape[0] < 10 * block_rows * (inputs.shape[1] + floors):
        raise RecordingError(
            f"{first.name}: {inputs.shape[0] * dt:.0f} s is too short to identify {modes} modes up to "
            f"{band:g} Hz"
        )
    model, poles = _n4sid(inputs, outputs, 2 * modes, block_rows, dt, band)
    explained = _check_explained(model, inputs, outputs, first)
    _check_modes(model, poles, modes, band, first.name)
    spanning = math.ceil(2 * np.pi / np.abs(poles[0]) / dt)  # block rows spanning the first mode's period
    if spanning > block_rows and inputs.shape[0] >= 10 * spanning * (inputs.shape[1] + floors):
        block_rows = spanning
        model, poles = _n4sid(inputs, outputs, 2 * modes, block_rows, dt, band)
        explained = _check_explained(model, inputs, outputs, first)
        _check_modes(model, poles, modes, band, first.name)
    longest = 2 * np.pi / np.abs(poles[0])
    duration = inputs.shape[0] * dt
    if duration < MIN_PERIODS * longest:
        raise RecordingError(
            f"{first.name}: {duration:.0f} s holds {duration / longest:.0f} periods of the first mode "
            f"({longest:.3g} s); record at least {MIN_PERIODS} ({MIN_PERIODS * longest:.0f} s)"
        )
    held = len(first.actuators) if factor == 1 else 0  # decimation smooths the held forces too
    arrays, physical, dropped = _structural(*model, floors, held, dt)
    if masses is not None:  # V_i = sum over floors j >= i of m_j a_j
        shear = np.triu(np.ones((floors, floors))) * masses
        acceleration = slice(3 * floors, 4 * floors)
        arrays["C"] = np.vstack([arrays["C"], shear @ arrays["C"][acceleration]])
        arrays["D"] = np.vstack([arrays["D"], shear @ arrays["D"][acceleration]])
    modes_found = _modes(arrays, floors)
    return Identified(
        arrays=arrays,
        physical=physical,
        modes=_with_errors(modes_found, inputs, outputs, modes, block_rows, dt, band, floors, held),
        explained=explained,
        dropped_feedthrough=dropped,
        sample_time=dt,
        block_rows=block_rows,
        decimation=factor,
    )


class ThinN4SID(NFourSID):
    """nfoursid's N4SID with the thin singular value decomposition of the observability estimate: 1.0.2 takes
    the full one, whose right factor is samples x samples (16 GB for an hour of data at 12.5 Hz); the leading
    factors it keeps are the same."""

    def _get_observability_matrix_decomposition(self) -> Decomposition:
        hankels = [
            Utils.block_hankel_matrix(data, self.num_block_rows) for data in (self.u_array, self.y_array)
        ]
        observability = self.R32 @ np.linalg.pinv(self.R22) @ np.concatenate(hankels)
        left, values, right = np.linalg.svd(observability, full_matrices=False)
        rank = self.x_dim
        return Decomposition(left[:, :rank], np.diag(values[:rank]), right[:rank])


def _decimated(recording: Recording, factor: int) -> tuple[np.ndarray, np.ndarray]:
    """Inputs [forces, ground] and outputs (accelerations) through the same anti-alias filter, every
    `factor`-th sample."""
    inputs = np.column_stack([recording.forces, recording.ground])
    outputs = recording.accelerations
    if factor == 1:
        return inputs, outputs
    return (scipy.signal.decimate(x, factor, axis=0, zero_phase=True) for x in (inputs, outputs))


def _n4sid(inputs, outputs, order, block_rows, dt, band) -> tuple[tuple[np.ndarray, ...], np.ndarray]:
    """The discrete (A, B, C, D) of `order` and its continuous oscillating poles below the band, ascending."""
    columns_u = [f"u{i}" for i in range(inputs.shape[1])]
    columns_y = [f"y{i}" for i in range(outputs.shape[1])]
    frame = pd.DataFrame(np.column_stack([inputs, outputs]), columns=columns_u + columns_y)
    identification = ThinN4SID(
        frame, output_columns=columns_y, input_columns=columns_u, num_block_rows=block_rows
    )
    identification.subspace_identification()
    model, _ = identification.system_identification(rank=order)
    discrete = (model.a, model.b, model.c, model.d)
    poles = np.log(np.linalg.eigvals(model.a).astype(complex)) / dt
    oscillating = poles[(poles.imag > 0) & (np.abs(poles) < 2 * np.pi * band)]
    return discrete, oscillating[np.argsort(np.abs(oscillating))]


def _check_modes(model, poles: np.ndarray, modes: int, band: float, name: str) -> None:
    """A stable model with the modes asked for below the band, or a `RecordingError` saying so."""
    if poles.size < modes or np.any(np.abs(np.linalg.eigvals(model[0])) >= 1.0):
        raise RecordingError(
            f"{name}: found {poles.size} stable oscillating modes below {band:g} Hz, asked for {modes}; "
            "record longer, excite more strongly, or ask for fewer --modes"
        )


def _check_explained(model, inputs: np.ndarray, outputs: np.ndarray, recording: Recording) -> np.ndarray:
    """The share of each floor's acceleration variance the model's response to the measured inputs accounts
    for (an unstable model: none); below `MIN_EXPLAINED` the recording is too quiet, a `RecordingError`."""
    explained = np.zeros(outputs.shape[1])
    if np.all(np.abs(np.linalg.eigvals(model[0])) < 1.0):
        explained = _explained(model, inputs, outputs)
    if np.min(explained) < MIN_EXPLAINED:
        floor = recording.floors[int(np.argmin(explained))]
        raise RecordingError(
            f"{recording.name}: too quiet: the model explains {max(np.min(explained), 0.0):.0%} of floor "
            f"{floor}'s acceleration (the sensors' noise dominates); excite the building more strongly or "
            "record longer"
        )
    return explained


def _explained(model, inputs: np.ndarray, outputs: np.ndarray) -> np.ndarray:
    """The share of each output's variance the model's response to the measured inputs accounts for."""
    import control  # python-control: the identified model as a discrete system, simulated from rest

    a, b, c, d = model
    system = control.ss(a, b, c, d, True)
    predicted = control.forced_response(system, U=inputs.T).outputs
    predicted = np.atleast_2d(predicted).T
    return 1.0 - np.var(outputs - predicted, axis=0) / np.var(outputs, axis=0)


def _continuous(a, b, c, d, dt: float, held: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The continuous (A, B, D) of a discrete model identified from samples: the inputs piecewise linear
    between samples (first-order hold: the ground; forces smoothed by decimation), the first `held` held
    between them (zero-order hold: forces at the recording's own rate). With a linear input a step is
    z1 = e^(A dt) z0 + M0 B u0 + M1 B u1, whose standard discrete form keeps B_d = (e^(A dt) M1 + M0) B and
    D_d = C M1 B + D (state z - M1 B u), so B and D follow from B_d and D_d."""
    n = a.shape[0]
    continuous_a = np.real(scipy.linalg.logm(a)) / dt
    augmented = np.zeros((3 * n, 3 * n))
    augmented[:n, :n], augmented[:n, n : 2 * n], augmented[n : 2 * n, 2 * n :] = (
        continuous_a,
        np.eye(n),
        np.eye(n),
    )
    exponential = scipy.linalg.expm(augmented * dt)
    held_gain, ramp = exponential[:n, n : 2 * n], exponential[:n, 2 * n :] / dt
    end = ramp  # M1: the weight of the step's end sample
    start = held_gain - ramp  # M0
    continuous_b = np.linalg.solve(a @ end + start, b)
    continuous_d = d - c @ end @ continuous_b
    if held:  # the first `held` inputs are held between samples (zero-order hold): B_d = M0 B + M1 B, D = D_d
        continuous_b[:, :held] = np.linalg.solve(held_gain, b[:, :held])
        continuous_d[:, :held] = d[:, :held]
    return continuous_a, continuous_b, continuous_d


def _structural(a, b, c, d, floors: int, held: int, dt: float) -> tuple[dict[str, np.ndarray], bool, float]:
    """The continuous model with the derived displacement, velocity and drift rows, its ground feed-through
    dropped; the state made [x; v] when there is one mode per floor. The first `held` inputs were held between
    samples (the actuators' forces at the recording's own rate)."""
    a, b, d = _continuous(a, b, c, d, dt, held)
    inverse = np.linalg.inv(a)
    displacement = c @ inverse @ inverse
    velocity = c @ inverse
    dropped = float(np.max(np.abs(d[:, -1])))
    d = d.copy()
    d[:, -1] = 0.0
    physical = a.shape[0] == 2 * floors
    if physical:
        transform = np.vstack([displacement, velocity])
        if np.linalg.cond(transform) > 1e10:
            physical = False
        else:
            back = np.linalg.inv(transform)
            a, b, c = transform @ a @ back, transform @ b, c @ back
            displacement = np.hstack([np.eye(floors), np.zeros((floors, floors))])
            velocity = np.hstack([np.zeros((floors, floors)), np.eye(floors)])
    drift = (np.eye(floors) - np.eye(floors, k=-1)) @ displacement
    rows = np.vstack([displacement, velocity, drift, c])
    zeros = np.zeros((3 * floors, b.shape[1]))
    return {"A": a, "B": b, "C": rows, "D": np.vstack([zeros, d])}, physical, dropped


def _modes(arrays: dict[str, np.ndarray], floors: int) -> list[Mode]:
    """The oscillating modes of the model, ascending: frequency, damping, the floors' displacement shape."""
    eigenvalues, vectors = np.linalg.eig(arrays["A"])
    keep = eigenvalues.imag > 0
    eigenvalues, vectors = eigenvalues[keep], vectors[:, keep]
    order = np.argsort(np.abs(eigenvalues))
    displacement = arrays["C"][:floors]
    modes = []
    for index in order:
        pole, shape = eigenvalues[index], displacement @ vectors[:, index]
        shape = np.real(shape * np.exp(-1j * np.angle(shape[np.argmax(np.abs(shape))])))
        shape = shape / shape[np.argmax(np.abs(shape))]
        modes.append(Mode(frequency=abs(pole) / (2 * np.pi), damping=-pole.real / abs(pole), shape=shape))
    return modes


def _with_errors(modes, inputs, outputs, asked, block_rows, dt, band, floors, held) -> list[Mode]:
    """`modes` with standard errors from the same identification on `SEGMENTS` equal segments (matched by
    the nearest frequency); without them (segments too short to identify) NaN."""
    length = inputs.shape[0] // SEGMENTS
    estimates = []
    for k in range(SEGMENTS):
        part = slice(k * length, (k + 1) * length)
        try:
            model, poles = _n4sid(inputs[part], outputs[part], 2 * asked, block_rows, dt, band)
            _check_modes(model, poles, asked, band, "segment")
        except (RecordingError, np.linalg.LinAlgError, ValueError):
            return modes
        estimates.append(_modes(_structural(*model, floors, held, dt)[0], floors))
    result = []
    for mode in modes:
        matched = [min(found, key=lambda m: abs(m.frequency - mode.frequency)) for found in estimates]
        shapes = np.array([m.shape * np.sign(m.shape @ mode.shape) for m in matched])
        scale = math.sqrt(SEGMENTS)
        result.append(
            Mode(
                frequency=mode.frequency,
                damping=mode.damping,
                shape=mode.shape,
                frequency_error=float(np.std([m.frequency for m in matched], ddof=1) / scale),
                damping_error=float(np.std([m.damping for m in matched], ddof=1) / scale),
                shape_error=np.std(shapes, axis=0, ddof=1) / scale,
            )
        )
    return result
