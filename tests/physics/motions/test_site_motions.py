"""Rezaeian & Der Kiureghian's site-based motions: the drawn parameters are what the motions carry, the
predictive equations move with the scenario as real motions do, and the family's spectral shapes are those of
real records."""

import math

import numpy as np
import pytest
from scipy import integrate, special

from rlcontroller.config import SiteBasedConfig
from rlcontroller.physics.motions import site_motions
from rlcontroller.physics.motions.excitation import Load
from rlcontroller.physics.motions.generators import generate_suite
from rlcontroller.physics.motions.site_motions import Scenario, SiteParameters, physical, predicted_normals
from rlcontroller.physics.motions.spectra import pseudo_acceleration, spectral_shape

DT = 0.01


def _ensemble(parameters: SiteParameters, runs: int) -> tuple[np.ndarray, np.ndarray]:
    shape, rate = site_motions.gamma_envelope(parameters)
    end = float(special.gammaincinv(shape, 0.999)) / rate
    time = np.arange(int(end / DT) + 1) * DT
    rng = np.random.default_rng(7)
    return time, np.array([site_motions.modulated_noise(parameters, time, rng) for _ in range(runs)])


def test_the_motions_carry_their_duration_and_middle():
    """The ensemble's mean cumulative energy reaches 45 % at tmid and spends d595 between 5 % and 95 %."""
    parameters = SiteParameters(arias=0.05, d595=12.0, tmid=8.0, wmid=5.0, wslope=-0.1, zeta=0.2)
    time, motions = _ensemble(parameters, 64)
    energy = np.cumsum(np.mean(motions**2, axis=0))
    energy /= energy[-1]
    t05, t45, t95 = (float(np.interp(p, energy, time)) for p in (0.05, 0.45, 0.95))
    assert t45 == pytest.approx(parameters.tmid, rel=0.03)
    assert t95 - t05 == pytest.approx(parameters.d595, rel=0.03)


def test_the_filter_frequency_is_the_zero_crossing_rate():
    """A damped oscillator's response to white noise crosses zero upward at its own frequency on average (its
    second spectral moment over its zeroth is omega^2): how Rezaeian & Der Kiureghian identify wmid."""
    parameters = SiteParameters(arias=0.05, d595=20.0, tmid=12.0, wmid=3.0, wslope=0.0, zeta=0.3)
    time, motions = _ensemble(parameters, 48)
    window = (time > parameters.tmid - 4.0) & (time < parameters.tmid + 4.0)
    pieces = motions[:, window]
    upward = np.sum((pieces[:, :-1] < 0.0) & (pieces[:, 1:] >= 0.0))
    rate = upward / (pieces.shape[0] * (pieces.shape[1] - 1) * DT)
    assert rate == pytest.approx(parameters.wmid, rel=0.05)


def test_the_predictions_move_with_the_scenario_as_real_motions_do():
    """Larger earthquakes shake harder, longer and at lower frequencies; farther sites more weakly and
    longer."""

    def median(**scenario) -> SiteParameters:
        values = {"magnitude": 6.5, "distance": 30.0, "vs30": 600.0, "reverse": False} | scenario
        return physical(predicted_normals(Scenario(**values)))

    small, large = median(magnitude=6.0), median(magnitude=7.5)
    near, far = median(distance=10.0), median(distance=100.0)
    assert large.arias > 2.0 * small.arias and large.d595 > small.d595 and large.wmid < small.wmid
    assert far.arias < near.arias / 3.0 and far.d595 > near.d595


def test_the_slope_distribution_is_a_distribution():
    """wslope's quantile function inverts its two-sided exponential density, which integrates to one on [-2,
    0.5]."""
    a, b, c, low, high = site_motions.SLOPE_CDF

    def density(x: float) -> float:
        return c * math.exp(b * x) if x < 0 else c * math.exp(-a * x)

    total = integrate.quad(density, low, 0.0)[0] + integrate.quad(density, 0.0, high)[0]
    assert total == pytest.approx(1.0, abs=1e-3)
    for p in (0.01, 0.3, 0.7, 0.72, 0.9, 0.999):
        x = site_motions.slope_quantile(p)
        mass = integrate.quad(density, low, min(x, 0.0))[0] + (
            integrate.quad(density, 0.0, x)[0] if x > 0 else 0.0
        )
        assert mass == pytest.approx(p, abs=1e-6)


def test_the_high_pass_removes_drift_and_keeps_shaking():
    """s^2 / (s + w_c)^2: a constant offset dies away, a 5 Hz shaking passes whole."""
    time = np.arange(0.0, 60.0, DT)
    settled = site_motions.high_pass(np.ones(time.size), DT, 0.1)
    assert abs(settled[-1]) < 1e-3
    shaking = site_motions.high_pass(np.sin(2 * np.pi * 5.0 * time), DT, 0.1)
    assert np.max(np.abs(shaking[time > 30.0])) == pytest.approx(1.0, rel=0.01)


def test_a_response_spectrum_at_resonance():
    """Under a harmonic ground acceleration at its own period, a 5 %-damped oscillator's steady
    pseudo-acceleration is the amplitude over 2 zeta."""
    time = np.arange(0.0, 80.0, DT)
    motion = Load("sine", DT, np.sin(2 * np.pi * time))
    assert pseudo_acceleration(motion, np.array([1.0]), 0.05)[0] == pytest.approx(10.0, rel=2e-3)


def test_a_response_spectrum_against_an_ode_solver():
    """On a random record, the same peaks as scipy's RK45 (tight tolerances) on the oscillator's equation with
    the ground acceleration linear between samples."""
    rng = np.random.default_rng(3)
    # from rest, as a record starts
    motion = Load("noise", DT, np.concatenate([[0.0], rng.normal(size=1000)]))
    periods, zeta = np.array([0.3, 1.0, 3.0]), 0.02
    for period, sa in zip(periods, pseudo_acceleration(motion, periods, zeta), strict=True):
        omega = 2.0 * np.pi / period

        def rate(t: float, state: np.ndarray, omega: float = omega) -> list[float]:
            ground = np.interp(t, motion.time, motion.acceleration)
            return [state[1], -ground - 2.0 * zeta * omega * state[1] - omega**2 * state[0]]

        solution = integrate.solve_ivp(
            rate,
            (0.0, motion.duration),
            [0.0, 0.0],
            t_eval=motion.time,
            rtol=1e-10,
            atol=1e-12,
            max_step=DT / 4,
        )
        assert sa == pytest.approx(omega**2 * np.max(np.abs(solution.y[0])), rel=1e-4)


@pytest.mark.slow
def test_the_family_has_real_records_spectral_shape():
    """The check suite's family, median Sa/PGA (2 % damped): near what issue 77 measured on 233 real strong
    motions held back from the project (0.48 at 2 s, 0.07 at 6.25 s), where round 6's Kanai-Tajimi family gave
    twice and three times as much; at short periods above 1, as every real record's."""
    config = SiteBasedConfig(pga=(0.0196, 14.71), pga_log=True)
    periods = np.array([6.25, 2.0, 0.2])
    shapes = np.array([spectral_shape(motion, periods) for motion in generate_suite(config, 160, 31337)])
    median = np.median(shapes, axis=0)
    assert 0.07 / 2.0 < median[0] < 0.07 * 2.0
    assert 0.48 / 1.5 < median[1] < 0.48 * 1.5
    assert median[2] > 1.5


@pytest.mark.parametrize(
    ("generator", "message"),
    [
        (
            {"magnitude": [9, 10]},
            "excitation.generator.magnitude[0]: Input should be less than or equal to 8",
        ),
        ({"distance": [50, 10]}, "excitation.generator.distance: expected [low, high] with low <= high"),
        ({"vs": [300, 800]}, "excitation.generator.vs: unknown key; did you mean 'vs30'?"),
    ],
)
def test_a_scenario_outside_the_model_is_one_line(generator, message):
    from rlcontroller.config.loading import build_experiment
    from rlcontroller.errors import ConfigError

    with pytest.raises(ConfigError) as error:
        build_experiment({"excitation": {"generator": {"kind": "site_based"} | generator}})
    assert str(error.value).startswith(f"<config>: {message}") and "\n" not in str(error.value)
