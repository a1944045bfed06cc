"""Turbulent along-wind loads on a building's floors, generated with a seed.

The wind at height z is U(z) + u(z, t): a logarithmic mean profile U(z) = (u*/kappa) ln(z / z0) set by
the terrain's roughness length z0 and the mean speed at a reference height, and a zero-mean turbulent
part u with

- Kaimal's spectrum, n S_u(z, n) / u*^2 = 200 f / (1 + 50 f)^(5/3), f = n z / U(z) (one-sided, n in
  Hz): it varies with height, which matters over a 300 m tower, where Davenport's spectrum does not;
- Davenport's coherence between heights, coh(z_i, z_j, n) = exp(-C n |z_i - z_j| / U_ij), U_ij the
  mean of U(z_i) and U(z_j), C = `decay`.

The field is simulated by the spectral representation method (Shinozuka and Deodatis 1991, 1996):
with the cross-spectral matrix S(n) = H(n) H(n)^T (Cholesky, real because the coherence is real),

    u_j(t) = sum_l sum_m 2 H_jm(n_l) sqrt(S-scale dn) cos(2 pi n_l t + phi_ml),

phi uniform and independent, n_l = (l + 1/2) dn below `cutoff` Hz; every realisation has the target
cross-spectra in expectation, summed by one inverse FFT per record. The forces are quasi-steady:
F_i(t) = 1/2 rho C_D A_i (U_i + u_i)^2, linearised to 1/2 rho C_D A_i U_i^2 + rho C_D A_i U_i u_i (the
mean and the fluctuating force), A_i the floor's tributary area (width x story height).

The records a suite or a training generator gives carry the fluctuating force only: its mean, applied
at t = 0 to a building at rest, would set a 1 %-damped tower ringing for minutes (a start-up artefact,
not wind), and its static response K^-1 F_mean is the same whatever the controller does. Every
criterion is therefore on the dynamic response about the mean-wind position. Units: m, s, m/s, N.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from rlcontroller.config import WindGeneratorConfig, WindSuiteConfig
from rlcontroller.physics.motions.excitation import Load, same_on_every_cpu
from rlcontroller.physics.structure import Building

KARMAN = 0.4
AIR_DENSITY = 1.22  # kg/m^3, the standard atmosphere near sea level (ASCE 7 uses 1.225)


@dataclass(frozen=True)
class WindField:
    """What the generator needs: the heights (m) of the loaded points, the mean speed `speed` (m/s)
    at `reference_height` (m), the roughness length `roughness` (m), the coherence decay, and the
    loads' drag coefficient, width (m) and tributary heights (m)."""

    heights: np.ndarray
    speed: float
    reference_height: float
    roughness: float
    decay: float = 10.0
    drag_coefficient: float = 1.3
    width: float = 42.0
    tributary_heights: np.ndarray | None = None

    @property
    def friction_velocity(self) -> float:
        """u* (m/s) of the log law through `speed` at `reference_height`."""
        return KARMAN * self.speed / np.log(self.reference_height / self.roughness)

    def mean_speed(self, heights: np.ndarray | None = None) -> np.ndarray:
        """U(z) (m/s) of the log law at the loaded heights (or at `heights`)."""
        z = self.heights if heights is None else np.asarray(heights, dtype=float)
        return self.friction_velocity / KARMAN * np.log(z / self.roughness)

    def spectrum(self, frequencies: np.ndarray) -> np.ndarray:
        """Kaimal's one-sided auto-spectra S_u(z_j, n) (m^2/s^2/Hz), shape (frequencies, heights)."""
        n = np.asarray(frequencies, dtype=float)[:, None]
        reduced = n * self.heights / self.mean_speed()
        return self.friction_velocity**2 * 200.0 * reduced / (1.0 + 50.0 * reduced) ** (5.0 / 3.0) / n

    def coherence(self, frequencies: np.ndarray) -> np.ndarray:
        """Davenport's coherence between every pair of heights, shape (frequencies, heights, heights)."""
        n = np.asarray(frequencies, dtype=float)[:, None, None]
        speed = self.mean_speed()
        separation = np.abs(self.heights[:, None] - self.heights[None, :])
        mean = 0.5 * (speed[:, None] + speed[None, :])
        return np.exp(-self.decay * n * separation / mean)

    def cross_spectra(self, frequencies: np.ndarray) -> np.ndarray:
        """The target one-sided cross-spectral matrices, shape (frequencies, heights, heights)."""
        root = np.sqrt(self.spectrum(frequencies))
        return root[:, :, None] * root[:, None, :] * self.coherence(frequencies)

    def areas(self) -> np.ndarray:
        """Each loaded point's tributary area (m^2): the width times its tributary height."""
        if self.tributary_heights is not None:
            return self.width * np.asarray(self.tributary_heights, dtype=float)
        edges = np.concatenate([[0.0], 0.5 * (self.heights[1:] + self.heights[:-1]), [self.heights[-1]]])
        return self.width * np.diff(edges)


def turbulence(
    field: WindField, duration: float, dt: float, rng: np.random.Generator, *, cutoff: float = 2.0
) -> np.ndarray:
    """One realisation of u(z_j, t) (m/s) at t = 0, dt, ..., shape (samples, heights): the spectral
    representation with frequencies n_l = (l + 1/2) dn, dn = 1 / (samples dt), below `cutoff` Hz
    (and below the Nyquist frequency 1 / (2 dt))."""
    samples = int(round(duration / dt)) + 1
    length = 2 * samples  # the record repeats after length * dt: longer than the record
    dn = 1.0 / (length * dt)
    count = int(min(cutoff, 0.5 / dt) / dn)
    frequencies = (np.arange(count) + 0.5) * dn
    factor = np.linalg.cholesky(field.cross_spectra(frequencies) * dn + 1e-12 * np.eye(field.heights.size))
    phases = np.exp(1j * rng.uniform(0.0, 2.0 * np.pi, size=(count, field.heights.size)))
    # u_j(t) = Re sum_l B_jl e^(2 pi i n_l t), B_l = sqrt(2) H(n_l) e^(i phi_l) (one-sided spectra)
    amplitudes = np.sqrt(2.0) * np.einsum("ljm,lm->lj", factor, phases)
    spectrum = np.zeros((length, field.heights.size), dtype=complex)
    spectrum[:count] = amplitudes
    time = np.arange(length) * dt
    series = np.fft.ifft(spectrum, axis=0) * length * np.exp(1j * np.pi * dn * time)[:, None]
    return series.real[:samples]


def mean_force(field: WindField) -> np.ndarray:
    """The mean along-wind force 1/2 rho C_D A U^2 (N) on every loaded point."""
    return 0.5 * AIR_DENSITY * field.drag_coefficient * field.areas() * field.mean_speed() ** 2


def force_per_speed(field: WindField) -> np.ndarray:
    """rho C_D A U (N per m/s): the fluctuating force of the linearised quasi-steady law is this times u."""
    return AIR_DENSITY * field.drag_coefficient * field.areas() * field.mean_speed()


def fluctuating_forces(
    field: WindField, duration: float, dt: float, rng: np.random.Generator, *, cutoff: float = 2.0
) -> np.ndarray:
    """The fluctuating along-wind force rho C_D A U u (N) on every loaded point at t = 0, dt, ...,
    shape (samples, heights), the same on every CPU (`excitation.same_on_every_cpu`); the whole force is
    `mean_force` plus this."""
    return same_on_every_cpu(force_per_speed(field) * turbulence(field, duration, dt, rng, cutoff=cutoff))


@dataclass(frozen=True)
class WindLoadModel:
    """A linear model of the fluctuating floor forces for a controller's estimator (LQG + wind model):
    every force a first-order (Markov) process f' = -f / time_constant + white noise, with the
    stationary covariance `covariance` (N^2) between the points. Not the generator: a design model."""

    time_constant: float  # s
    covariance: np.ndarray  # (points, points), N^2


def load_model(field: WindField, frequency: float) -> WindLoadModel:
    """The `WindLoadModel` of `field`, fitted at the building's first natural `frequency` (Hz).

    The time constant T makes the first-order spectrum 4 sigma^2 T / (1 + (2 pi n T)^2) equal to
    Kaimal's at `frequency` at two thirds of the height (where the first mode's generalised force
    comes from), with Kaimal's variance sigma_u^2 = 6 u*^2 (the larger of the two roots: the corner
    below the mode, as Kaimal's energy is). The covariance is rho C_D A_i U_i rho C_D A_j U_j sigma_u^2
    times Davenport's coherence at `frequency`, so the model loads the first mode as the wind does
    there, not as a wind coherent over the whole height would.
    """
    variance = 6.0 * field.friction_velocity**2
    reference = replace(field, heights=np.array([2.0 / 3.0 * field.heights.max()]))
    target = float(reference.spectrum(np.array([frequency]))[0, 0])
    omega = 2.0 * np.pi * frequency
    discriminant = 16.0 * variance**2 - 4.0 * target**2 * omega**2
    if discriminant < 0.0:  # cannot happen with Kaimal's spectrum (n S / sigma^2 <= 0.22 < 1 / pi)
        raise ValueError(
            "no first-order spectrum of Kaimal's variance reaches Kaimal's level at the frequency"
        )
    time_constant = (4.0 * variance + np.sqrt(discriminant)) / (2.0 * target * omega**2)
    per_speed = force_per_speed(field)
    covariance = np.outer(per_speed, per_speed) * variance * field.coherence(np.array([frequency]))[0]
    return WindLoadModel(time_constant=float(time_constant), covariance=covariance)


DEFAULT_STORY_HEIGHT = 3.0  # m, for buildings whose story heights are not given


def floor_field(config: WindSuiteConfig | WindGeneratorConfig, building: Building, speed: float) -> WindField:
    """The wind field of a suite or generator at one mean speed on `building`'s floors (at the tops of
    its stories; 3 m stories when it gives none)."""
    stories = building.story_heights
    if stories is None:
        stories = np.full(building.n_floors, DEFAULT_STORY_HEIGHT)
    return WindField(
        heights=np.cumsum(stories),
        speed=speed,
        reference_height=config.reference_height,
        roughness=config.roughness,
        decay=config.decay,
        drag_coefficient=config.drag_coefficient,
        width=config.width,
        tributary_heights=np.asarray(stories, dtype=float),
    )


def generated_wind(
    config: WindGeneratorConfig, building: Building, rng: np.random.Generator, name: str
) -> Load:
    """One wind load record for training: a mean speed and a duration drawn in the generator's ranges."""
    speed = float(rng.uniform(*config.speed))
    duration = float(rng.uniform(*config.duration))
    forces = fluctuating_forces(
        floor_field(config, building, speed), duration, config.dt, rng, cutoff=config.cutoff
    )
    zero = np.zeros(forces.shape[0])
    return Load(
        name, config.dt, zero, synthetic=True, description=f"wind {speed:.1f} m/s", floor_forces=forces
    )


def wind_suite(suite: WindSuiteConfig, building: Building) -> list[Load]:
    """The suite's wind load records on `building`'s floors, as motions with floor forces and no
    ground acceleration, all from one seed."""
    rng = np.random.default_rng(suite.seed)
    records = []
    for speed in suite.speeds:
        field = floor_field(suite, building, speed)
        for number in range(suite.records_per_speed):
            forces = fluctuating_forces(field, suite.duration, suite.dt, rng, cutoff=suite.cutoff)
            name = f"wind_{speed:g}ms_{number + 1}"
            zero = np.zeros(forces.shape[0])
            records.append(Load(name, suite.dt, zero, synthetic=True, floor_forces=forces))
    return records


def suite_label(suite: WindSuiteConfig, source: str) -> str:
    """How tables name a wind suite read from `source`."""
    speeds = ", ".join(f"{speed:g}" for speed in suite.speeds)
    return (
        f"{len(suite.speeds) * suite.records_per_speed} generated wind records of {suite.duration:g} s "
        f"({speeds} m/s at {suite.reference_height:g} m, seed {suite.seed}), from {source}"
    )
