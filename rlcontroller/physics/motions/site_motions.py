"""Site-based stochastic ground motions: the model of Rezaeian & Der Kiureghian (2010, "Simulation of
synthetic ground motions for specified earthquake and site characteristics", EESD 39, 1155-1180), whose six
parameters are predicted from an earthquake scenario (magnitude, rupture distance, Vs30, faulting) with their
record-to-record variability, as fitted to NGA strong-motion records. A motion is modulated, filtered white
noise:

    a(t) = q(t) * sum_i h(t - tau_i; w_f(tau_i)) w_i / sigma_h(t),   then high-passed,

| parameter | what it is                                         | unit | marginal (the 2010 paper)          |
|-----------|----------------------------------------------------|------|------------------------------------|
| `arias`   | Arias intensity                                    | s g  | lognormal(-4.8255, 1.4318)         |
| `d595`    | significant duration, 5 % to 95 % of Arias         | s    | 5 + 40 Beta(1.1314, 2.4474)        |
| `tmid`    | time at 45 % of Arias intensity                    | s    | 0.5 + 39.5 Beta(1.5792, 3.6405)    |
| `wmid`    | the filter's frequency at tmid                     | Hz   | Gamma(4.0982, scale 1.4330)        |
| `wslope`  | its rate, w_f(t) = wmid + wslope (t - tmid)        | Hz/s | two-sided exponential on [-2, 0.5] |
| `zeta`    | the filter's damping ratio                         | -    | 0.02 + 0.98 Beta(1.4250, 5.7208)   |

q(t) is the gamma modulating function t^(a2 - 1) exp(-a3 t), fixed by tmid and d595; h is the impulse response
of a damped oscillator (its pseudo-acceleration) with the frequency the filter has when the pulse arrives; a
critically damped second-order high-pass with corner f_c removes the long-period drift real records'
processing removes.

The predictive equations (each parameter's standard-normal image linear in M (u1: M/7), F, R (u1: ln(R/25))
and Vs30 (u1: ln(Vs30/750)), with inter- and intra-event errors and the correlation of their totals) are the
coefficients the SCEC Broadband Platform publishes for this model (module `rzz2015_gmpe`, Rezaeian, Zhong &
Zareian 2015's fit). Two choices are this project's, stated: the filter's frequency is held above `FLOOR_HZ`
(a steep negative slope would take it through zero in a long motion's tail), and f_c is drawn per motion (Su,
Dabaghi & Broccardo 2024 show it governs the spectrum beyond 1 s and varies from record to record)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rlcontroller.config import SiteBasedConfig
from rlcontroller.physics.motions.excitation import Load

# the predictive equations: u_k = b0 + b1 M + b2 F + b3 R + b4 Vs30 (u1: M / 7, ln(R / 25), ln(Vs30 / 750))
COEFFICIENTS = np.array(
    [
        [-2.2962, 2.9440, -0.0707, -1.3564, -0.2654],
        [-6.1946, 0.9703, -0.7034, 0.0087, -0.0007],
        [-5.0105, 0.6625, -0.3450, 0.0139, -0.0002],
        [2.2525, -0.2586, -0.0808, -0.0084, 0.0000],
        [-2.4886, 0.3440, 0.0441, 0.0026, -0.0001],
        [-0.2583, 0.1293, -0.4772, -0.0115, 0.0004],
    ]
)
INTRA_EVENT = np.array([0.5937, 0.5688, 0.4145, 0.7228, 0.9529, 0.7601])  # sigma, of u_k
INTER_EVENT = np.array([0.2738, 0.4574, 0.5114, 0.6918, 0.1286, 0.6815])  # tau
TOTAL_CORRELATION = np.array(
    [
        [1.0000, -0.3555, 0.0066, -0.1545, 0.1341, -0.0078],
        [-0.3555, 1.0000, 0.6729, -0.1303, -0.1576, -0.1958],
        [0.0066, 0.6729, 1.0000, -0.2761, -0.1977, -0.2188],
        [-0.1545, -0.1303, -0.2761, 1.0000, -0.2034, 0.2814],
        [0.1341, -0.1576, -0.1977, -0.2034, 1.0000, -0.0137],
        [-0.0078, -0.1958, -0.2188, 0.2814, -0.0137, 1.0000],
    ]
)
SLOPE_CDF = (17.095, 6.7729, 4.8512, -2.0, 0.5)  # wslope's two-sided exponential: a, b, c, low, high (Hz/s)
FLOOR_HZ = 0.3  # the filter's frequency is held above this (Hz)
LONGEST = 90.0  # s: a motion ends at 99.9 % of its Arias intensity, or here


@dataclass(frozen=True)
class Scenario:
    """An earthquake and a site: moment magnitude, rupture distance (km), Vs30 (m/s), reverse faulting or
    not."""

    magnitude: float
    distance: float
    vs30: float
    reverse: bool

    def describe(self) -> str:
        kind = "reverse" if self.reverse else "strike-slip"
        return f"M{self.magnitude:.2f} {kind}, R {self.distance:.0f} km, Vs30 {self.vs30:.0f} m/s"


@dataclass(frozen=True)
class SiteParameters:
    """The model's six parameters (units in the module's table)."""

    arias: float
    d595: float
    tmid: float
    wmid: float
    wslope: float
    zeta: float


def predicted_normals(scenario: Scenario) -> np.ndarray:
    """The mean standard-normal images (u1..u6) of the six parameters for `scenario`."""
    m, f, r, v = scenario.magnitude, float(scenario.reverse), scenario.distance, scenario.vs30
    first = np.array([1.0, m / 7.0, f, math.log(r / 25.0), math.log(v / 750.0)])
    rest = np.array([1.0, m, f, r, v])
    return np.concatenate([[COEFFICIENTS[0] @ first], COEFFICIENTS[1:] @ rest])


def total_covariance() -> np.ndarray:
    """The covariance of the six standard-normal images' total (inter- plus intra-event) errors."""
    std = np.hypot(INTRA_EVENT, INTER_EVENT)
    return TOTAL_CORRELATION * np.outer(std, std)


def physical(normals: np.ndarray) -> SiteParameters:
    """The six parameters from their standard-normal images, through their marginal distributions."""
    from scipy import stats  # here, not at import: most commands generate no motion

    p = np.clip(stats.norm.cdf(normals), 1e-12, 1.0 - 1e-12)
    return SiteParameters(
        arias=float(np.exp(stats.norm.ppf(p[0], -4.8255, 1.4318))),
        d595=float(5.0 + 40.0 * stats.beta.ppf(p[1], 1.1314, 2.4474)),
        tmid=float(0.5 + 39.5 * stats.beta.ppf(p[2], 1.5792, 3.6405)),
        wmid=float(stats.gamma.ppf(p[3], 4.0982, scale=1.4330)),
        wslope=slope_quantile(float(p[4])),
        zeta=float(0.02 + 0.98 * stats.beta.ppf(p[5], 1.4250, 5.7208)),
    )


def slope_quantile(p: float) -> float:
    """The inverse of wslope's distribution: density c exp(b x) below 0 and c exp(-a x) above, on [low,
    high]."""
    a, b, c, low, high = SLOPE_CDF
    at_zero = c / b * (1.0 - math.exp(b * low))
    if p < at_zero:
        return math.log(p * b / c + math.exp(b * low)) / b
    return min(-math.log(max(1.0 - (p - at_zero) * a / c, 1e-300)) / a, high)


def draw(config: SiteBasedConfig, rng: np.random.Generator) -> tuple[Scenario, SiteParameters, float]:
    """A scenario from the config's ranges, its parameters with their variability, and a corner frequency
    (Hz)."""
    low, high = config.distance
    scenario = Scenario(
        magnitude=float(rng.uniform(*config.magnitude)),
        distance=float(np.exp(rng.uniform(math.log(low), math.log(high)))),
        vs30=float(rng.uniform(*config.vs30)),
        reverse=bool(rng.uniform() < config.reverse_share),
    )
    errors = np.linalg.cholesky(total_covariance()) @ rng.normal(size=6)
    low, high = config.corner_frequency
    corner = float(np.exp(rng.uniform(math.log(low), math.log(high))))
    return scenario, physical(predicted_normals(scenario) + errors), corner


def gamma_envelope(parameters: SiteParameters) -> tuple[float, float]:
    """The shape k and rate (1/s) of the gamma law the modulating function's cumulative energy follows
    (q^2 ~ t^(k-1) exp(-rate t), k = 2 a2 - 1, rate = 2 a3): its 45 % point at tmid, 5 % to 95 % lasting
    d595."""
    from scipy import optimize, special

    def quantile(p: float, k: float) -> float:
        return float(special.gammaincinv(k, p))

    target = parameters.d595 / parameters.tmid

    def excess(log_k: float) -> float:
        k = math.exp(log_k)
        return (quantile(0.95, k) - quantile(0.05, k)) / quantile(0.45, k) - target

    low, high = math.log(0.05), math.log(5000.0)  # the ratio falls from about 90 to 0.05 over these shapes
    log_k = (
        low
        if excess(low) < 0
        else high
        if excess(high) > 0
        else optimize.brentq(excess, low, high, xtol=1e-10)
    )
    k = math.exp(log_k)
    return k, quantile(0.45, k) / parameters.tmid


def modulated_noise(parameters: SiteParameters, time: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The filtered white noise, normalised to unit variance, times the modulating function (peak 1)."""
    dt = float(time[1] - time[0])
    omega = 2.0 * np.pi * np.maximum(parameters.wmid + parameters.wslope * (time - parameters.tmid), FLOOR_HZ)
    zeta = parameters.zeta
    damped = omega * math.sqrt(1.0 - zeta**2)
    noise = rng.normal(size=time.size)
    filtered, variance = np.zeros(time.size), np.zeros(time.size)
    decay = np.exp(-zeta * omega * dt)  # per lag, of each pulse's response
    envelope = np.ones(time.size)
    for lag in range(time.size):  # the response to every pulse `lag` steps after it, all pulses at once
        if lag:
            envelope[: time.size - lag] *= decay[: time.size - lag]
        alive = envelope[: time.size - lag]
        if lag and alive.max(initial=0.0) < 1e-4:
            break
        gain = omega[: time.size - lag] / math.sqrt(1.0 - zeta**2)
        response = gain * alive * np.sin(damped[: time.size - lag] * lag * dt)
        filtered[lag:] += response * noise[: time.size - lag]
        variance[lag:] += response**2
    shape, rate = gamma_envelope(parameters)
    middle = np.maximum(time, dt / 2.0)  # a shape below 1 peaks at t = 0, where its power is infinite
    modulation = middle ** ((shape - 1.0) / 2.0) * np.exp(-rate * middle / 2.0)
    modulation /= modulation.max()
    return modulation * np.divide(filtered, np.sqrt(variance), out=np.zeros(time.size), where=variance > 0)


def high_pass(acceleration: np.ndarray, dt: float, corner: float) -> np.ndarray:
    """The relative acceleration of a critically damped oscillator of frequency `corner` (Hz) under
    `acceleration`: s^2 / (s + w_c)^2, the high-pass of the model."""
    import scipy.signal

    w = 2.0 * np.pi * corner
    numerator, denominator = scipy.signal.bilinear([1.0, 0.0, 0.0], [1.0, 2.0 * w, w * w], fs=1.0 / dt)
    return scipy.signal.lfilter(numerator, denominator, acceleration)


def site_based(config: SiteBasedConfig, rng: np.random.Generator, name: str = "site_based") -> Load:
    """One motion of the model for a scenario drawn from `config`, scaled to a PGA drawn from it (m/s^2); its
    description names the scenario and the parameters."""
    scenario, parameters, corner = draw(config, rng)
    shape, rate = gamma_envelope(parameters)
    from scipy import special

    end = min(float(special.gammaincinv(shape, 0.999)) / rate, LONGEST)
    time = np.arange(int(end / config.dt) + 1) * config.dt
    acceleration = high_pass(modulated_noise(parameters, time, rng), config.dt, corner)
    low, high = config.pga
    pga = (
        float(np.exp(rng.uniform(math.log(low), math.log(high))))
        if config.pga_log
        else float(rng.uniform(low, high))
    )
    acceleration *= pga / np.max(np.abs(acceleration))
    words = (
        f"{scenario.describe()}; D5-95 {parameters.d595:.1f} s, tmid {parameters.tmid:.1f} s, "
        f"filter {parameters.wmid:.2f} Hz {parameters.wslope:+.3f} Hz/s, zeta {parameters.zeta:.2f}, "
        f"f_c {corner:.2f} Hz"
    )
    return Load(name, config.dt, acceleration, synthetic=True, description=words)
