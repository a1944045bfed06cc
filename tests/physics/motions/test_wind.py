"""The wind field: over many realisations its auto-spectra are Kaimal's, its coherence Davenport's and
its variance the spectrum's integral; the fluctuating force has zero mean; a seed fixes it. The load
model of LQG + wind model matches the spectrum and coherence where it is fitted."""

import numpy as np
import pytest
import scipy.signal

from rlcontroller.physics.motions.wind import (
    WindField,
    fluctuating_forces,
    load_model,
    mean_force,
    turbulence,
)

FIELD = WindField(
    heights=np.array([40.0, 80.0, 160.0, 300.0]), speed=25.0, reference_height=10.0, roughness=0.3
)
DT, DURATION, REALISATIONS = 0.25, 1800.0, 24


@pytest.fixture(scope="module")
def spectra():
    """Welch estimates of the one-sided cross-spectra, averaged over the realisations."""
    rng = np.random.default_rng(11)
    total = None
    for _ in range(REALISATIONS):
        u = turbulence(FIELD, DURATION, DT, rng, cutoff=1.0)
        frequencies, cross = scipy.signal.csd(u[:, :, None], u[:, None, :], fs=1.0 / DT, nperseg=1024, axis=0)
        total = cross if total is None else total + cross
    return frequencies, total / REALISATIONS


def bands(frequencies):
    return [(frequencies > low) & (frequencies < 1.5 * low) for low in (0.01, 0.03, 0.08, 0.2, 0.5)]


def test_the_auto_spectra_are_kaimals(spectra):
    frequencies, cross = spectra
    target = FIELD.spectrum(frequencies[1:])
    for band in bands(frequencies[1:]):
        estimate = np.real(np.diagonal(cross[1:][band], axis1=1, axis2=2)).mean(axis=0)
        np.testing.assert_allclose(estimate, target[band].mean(axis=0), rtol=0.12)


def test_the_coherence_is_davenports(spectra):
    frequencies, cross = spectra
    auto = np.real(np.diagonal(cross, axis1=1, axis2=2))
    target = FIELD.coherence(frequencies[1:])
    for i, j in ((0, 1), (1, 2), (2, 3), (0, 3)):
        normalised = np.real(cross[1:, i, j]) / np.sqrt(auto[1:, i] * auto[1:, j])
        for band in bands(frequencies[1:]):
            assert normalised[band].mean() == pytest.approx(target[band, i, j].mean(), abs=0.06)


def test_the_variance_is_the_spectrum_integral_and_the_mean_is_zero():
    rng = np.random.default_rng(3)
    u = np.stack([turbulence(FIELD, DURATION, DT, rng, cutoff=1.0) for _ in range(8)])
    dn = 1.0 / (2 * (round(DURATION / DT) + 1) * DT)
    frequencies = (np.arange(int(1.0 / dn)) + 0.5) * dn
    expected = FIELD.spectrum(frequencies).sum(axis=0) * dn
    np.testing.assert_allclose(u.var(axis=(0, 1)), expected, rtol=0.08)
    assert np.all(np.abs(u.mean(axis=(0, 1))) < 0.1 * np.sqrt(expected))
    # Kaimal: sigma_u^2 ~ 6 u*^2
    assert expected[-1] / FIELD.friction_velocity**2 == pytest.approx(6.0, rel=0.1)


def test_the_fluctuating_force_has_zero_mean_and_a_seed_fixes_the_record():
    forces = fluctuating_forces(FIELD, DURATION, DT, np.random.default_rng(5))
    records = [fluctuating_forces(FIELD, DURATION, DT, np.random.default_rng(seed)) for seed in range(12)]
    assert np.all(np.abs(np.mean([f.mean(axis=0) for f in records], axis=0)) < 0.02 * mean_force(FIELD))
    np.testing.assert_array_equal(forces, fluctuating_forces(FIELD, DURATION, DT, np.random.default_rng(5)))
    assert not np.array_equal(forces, fluctuating_forces(FIELD, DURATION, DT, np.random.default_rng(6)))
    assert FIELD.mean_speed(np.array([10.0]))[0] == pytest.approx(25.0)  # the reference speed at its height
    np.testing.assert_allclose(FIELD.areas().sum(), 42.0 * 300.0)  # the tributary areas cover the facade


def test_the_load_model_matches_kaimal_at_the_first_mode_and_davenport_between_floors():
    """LQG + wind model's first-order load model: Kaimal's level at the mode (two thirds up), Kaimal's
    variance, a corner below the mode, and the floors correlated as Davenport's coherence says there."""
    frequency = 0.16
    model = load_model(FIELD, frequency)
    variance = 6.0 * FIELD.friction_velocity**2
    t = model.time_constant
    first_order = 4.0 * variance * t / (1.0 + (2.0 * np.pi * frequency * t) ** 2)
    reference = WindField(
        heights=np.array([200.0]),
        speed=FIELD.speed,
        reference_height=FIELD.reference_height,
        roughness=FIELD.roughness,
    )
    assert first_order == pytest.approx(reference.spectrum(np.array([frequency]))[0, 0], rel=1e-9)
    assert 1.0 / (2.0 * np.pi * t) < frequency
    per_speed = mean_force(FIELD) * 2.0 / FIELD.mean_speed()  # rho C_D A U
    np.testing.assert_allclose(np.diag(model.covariance), per_speed**2 * variance)
    correlation = model.covariance[0, -1] / np.sqrt(model.covariance[0, 0] * model.covariance[-1, -1])
    separation, mean = 260.0, FIELD.mean_speed()[[0, -1]].mean()
    assert correlation == pytest.approx(np.exp(-FIELD.decay * frequency * separation / mean), rel=1e-9)
