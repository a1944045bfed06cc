"""Ground-motion generators for training and validation (never the records a controller is judged on):
the paper's white noise with impulses, filtered Kanai-Tajimi motions, near-fault pulses, Rezaeian & Der
Kiureghian's site-based motions (`site_motions`) and mixtures of them; and the Kanai-Tajimi ground model that
LQG + ground model and the ground-model estimate assume."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from rlcontroller.config import (
    GeneratorConfig,
    KanaiTajimiConfig,
    MixtureConfig,
    NearFaultConfig,
    NoiseImpulsesConfig,
    SiteBasedConfig,
)
from rlcontroller.physics.motions.excitation import Load, same_on_every_cpu


@dataclass(frozen=True)
class GroundModel:
    """Kanai-Tajimi ground filter  x_f'' + 2 damping frequency x_f' + frequency^2 x_f = -w  (w white),
    a_g = -frequency^2 x_f - 2 damping frequency x_f'. The defaults are the firm-soil values of
    Kanai-Tajimi (Tajimi 1960), not fitted to any record."""

    frequency: float = 15.6  # rad/s
    damping: float = 0.6

    @property
    def output(self) -> np.ndarray:
        """a_g = output @ [x_f, x_f']."""
        return np.array([-(self.frequency**2), -2.0 * self.damping * self.frequency])

    def spectrum(self, frequencies: np.ndarray) -> np.ndarray:
        """|a_g / w|^2 at `frequencies` (Hz): the filter's power gain, 1 at 0 Hz (white bedrock = 1)."""
        s = 2j * np.pi * np.asarray(frequencies, dtype=float)
        w, z = self.frequency, self.damping
        return np.abs((w**2 + 2 * z * w * s) / (s**2 + 2 * z * w * s + w**2)) ** 2

    def state_scale(self, ground_scale: float) -> np.ndarray:
        """Typical sizes of x_f (m) and x_f' (m/s) for a ground acceleration of `ground_scale`."""
        return np.array([ground_scale / self.frequency**2, ground_scale / self.frequency])


def _uniform(rng: np.random.Generator, bounds: tuple[float, float]) -> float:
    return float(rng.uniform(bounds[0], bounds[1]))


def noise_impulses(
    config: NoiseImpulsesConfig, rng: np.random.Generator, name: str = "noise_impulses"
) -> Load:
    """The paper's training motion: Gaussian white noise plus random half-sine impulses."""
    duration = _uniform(rng, config.duration)
    time = np.arange(int(duration / config.dt) + 1) * config.dt
    acceleration = rng.normal(0.0, _uniform(rng, config.noise_std), time.size)
    for _ in range(int(rng.integers(config.impulses[0], config.impulses[1] + 1))):
        amplitude = _uniform(rng, config.impulse_amplitude) * rng.choice([-1.0, 1.0])
        width = _uniform(rng, config.impulse_duration)
        start = float(rng.uniform(0.0, max(duration - width, 0.0)))
        inside = (time >= start) & (time <= start + width)
        acceleration[inside] += amplitude * np.sin(np.pi * (time[inside] - start) / width)
    return Load(name, config.dt, acceleration, synthetic=True)


def kanai_tajimi(config: KanaiTajimiConfig, rng: np.random.Generator, name: str = "kanai_tajimi") -> Load:
    """Kanai-Tajimi filtered white noise, H(s) = (2 z w s + w^2) / (s^2 + 2 z w s + w^2), times a
    rise-plateau-decay envelope, scaled to a random PGA (m/s^2)."""
    import scipy.signal  # here, not at import: it takes 0.6 s, and most commands generate no motion

    omega, zeta = _uniform(rng, config.ground_frequency), _uniform(rng, config.ground_damping)
    rise, strong, decay = (
        _uniform(rng, config.rise_time),
        _uniform(rng, config.strong_duration),
        _uniform(rng, config.decay_rate),
    )
    duration = _uniform(rng, config.duration)
    time = np.arange(int(duration / config.dt) + 1) * config.dt
    numerator, denominator, _ = scipy.signal.cont2discrete(
        ([2 * zeta * omega, omega**2], [1.0, 2 * zeta * omega, omega**2]), config.dt, method="zoh"
    )
    filtered = scipy.signal.lfilter(numerator.ravel(), denominator, rng.normal(size=time.size))
    envelope = np.where(
        time < rise, (time / rise) ** 2, np.exp(-decay * np.maximum(time - rise - strong, 0.0))
    )
    acceleration = filtered * envelope
    peak = np.max(np.abs(acceleration))
    if peak > 0:
        acceleration *= _log_or_uniform(rng, config.pga, config.pga_log) / peak
    return Load(name, config.dt, acceleration, synthetic=True)


def _log_or_uniform(rng: np.random.Generator, bounds: tuple[float, float], log: bool) -> float:
    return float(np.exp(rng.uniform(np.log(bounds[0]), np.log(bounds[1])))) if log else _uniform(rng, bounds)


def near_fault(config: NearFaultConfig, rng: np.random.Generator, name: str = "near_fault") -> Load:
    """A Kanai-Tajimi background plus a Mavroeidis-Papageorgiou (2003) pulse, scaled to a random PGA.

    The pulse's velocity is (1 + cos(2 pi f (t - t0) / gamma)) cos(2 pi f (t - t0) + nu) / 2 for
    |t - t0| <= gamma / (2 f), f = 1 / period; its acceleration (the derivative) is added with a
    peak `pulse_ratio` times the background's, centred in the background's strong phase."""
    background = kanai_tajimi(config.background, rng, name)
    time, acceleration = background.time, background.acceleration.copy()
    frequency, cycles = 1.0 / _uniform(rng, config.pulse_period), _uniform(rng, config.pulse_cycles)
    phase, ratio = float(rng.uniform(0.0, 2.0 * np.pi)), _uniform(rng, config.pulse_ratio)
    centre = float(rng.uniform(0.2, 0.5)) * time[-1]
    shifted = time - centre
    inside = np.abs(shifted) <= cycles / (2.0 * frequency)
    velocity = np.where(
        inside,
        0.5
        * (1.0 + np.cos(2.0 * np.pi * frequency * shifted / cycles))
        * np.cos(2.0 * np.pi * frequency * shifted + phase),
        0.0,
    )
    pulse = np.gradient(velocity, config.dt)
    if np.max(np.abs(pulse)) > 0:
        acceleration += pulse * ratio * np.max(np.abs(acceleration)) / np.max(np.abs(pulse))
    peak = np.max(np.abs(acceleration))
    if peak > 0:
        acceleration *= _log_or_uniform(rng, config.pga, config.pga_log) / peak
    return Load(name, config.dt, acceleration, synthetic=True)


def generate(config: GeneratorConfig, rng: np.random.Generator, name: str | None = None) -> Load:
    """One synthetic motion from the configured generator (its samples the same on every CPU)."""
    if isinstance(config, MixtureConfig):
        weights = np.array([component.weight for component in config.components])
        chosen = config.components[int(rng.choice(len(weights), p=weights / weights.sum()))]
        return generate(chosen.generator, rng, name)
    if isinstance(config, KanaiTajimiConfig):
        motion = kanai_tajimi(config, rng, name or "kanai_tajimi")
    elif isinstance(config, NearFaultConfig):
        motion = near_fault(config, rng, name or "near_fault")
    elif isinstance(config, SiteBasedConfig):
        from rlcontroller.physics.motions.site_motions import site_based

        motion = site_based(config, rng, name or "site_based")
    else:
        motion = noise_impulses(config, rng, name or "noise_impulses")
    return replace(motion, acceleration=same_on_every_cpu(motion.acceleration))


def generate_suite(config: GeneratorConfig, count: int, seed: int) -> list[Load]:
    """`count` motions from one seed (the same seed gives the same suite)."""
    rng = np.random.default_rng(seed)
    return [generate(config, rng, f"{config.kind}_{seed}_{i}") for i in range(count)]
