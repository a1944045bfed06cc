import numpy as np
import pytest

from rlcontroller.physics.metrics import energy, j_metrics, peak, ratio_to_reference
from rlcontroller.physics.response import Response


def response(scale: float, force: float, steps: int = 4) -> Response:
    time = np.arange(steps + 1) * 0.5
    wave = np.array([0.0, 1.0, -2.0, 0.5, 0.0])[: steps + 1]
    floors = np.outer(wave, [1.0, 2.0])
    return Response(
        time=time,
        ground=np.zeros(steps + 1),
        displacement=scale * floors,
        velocity=scale * floors,
        drift=scale * floors,
        absolute_acceleration=scale * floors * 3,
        story_shear=scale * floors * 10,
        base_shear=scale * wave * 10,
        force=np.vstack([[0.0], np.full((steps, 1), force)]),
    )


def test_peak_and_energy_on_known_signals():
    np.testing.assert_array_equal(peak(np.array([[1.0, -3.0], [-2.0, 2.0]])), [2.0, 3.0])
    # A held force of 2 N over four 0.5 s steps: integral of u^2 = 4 * 0.5 * 4 = 8 N^2 s.
    assert energy(np.vstack([[0.0], np.full((4, 1), 2.0)]), 0.5)[0] == pytest.approx(8.0)


def test_j_metrics_of_a_halved_response():
    controlled, uncontrolled = response(0.5, 2.0), response(1.0, 0.0)
    metrics = j_metrics(controlled, uncontrolled)
    np.testing.assert_allclose(metrics["J1"], [0.5, 0.5])
    np.testing.assert_allclose(metrics["J2"], [0.5, 0.5])
    np.testing.assert_allclose(metrics["J4"], [0.5, 0.5])
    # E_u = 4 * 0.5 * 2^2 = 8; E_Vb,UC = 0.5 * (10^2 + 20^2 + 5^2 + 0) = 262.5
    np.testing.assert_allclose(metrics["J3"], [8.0 / 262.5])


def test_uncontrolled_against_itself_is_one():
    bare = response(1.0, 0.0)
    metrics = j_metrics(bare, bare)
    for name in ("J1", "J2", "J4"):
        np.testing.assert_array_equal(metrics[name], 1.0)
    np.testing.assert_array_equal(metrics["J3"], 0.0)


def test_wind_metrics_are_rms_about_the_mean_and_peaks_in_milli_g():
    from rlcontroller.physics.metrics import wind_metrics
    from rlcontroller.physics.response import Response

    time = np.linspace(0.0, 10.0, 1001)

    def response(scale: float) -> Response:
        wave = scale * np.sin(2 * np.pi * time)[:, None] * np.ones((1, 2))
        fields = {name: wave + 5.0 for name in ("displacement", "velocity", "drift", "story_shear", "force")}
        return Response(
            time=time, ground=0 * time, absolute_acceleration=wave + 5.0, base_shear=wave[:, 0], **fields
        )

    controlled = response(0.5)
    controlled.absolute_acceleration[:, 1] *= 0.5  # the top floor moves less
    metrics = wind_metrics(controlled, response(1.0))
    # the constant 5 does not count
    np.testing.assert_allclose(metrics["rms_acceleration"], [0.5, 0.25], rtol=1e-3)
    np.testing.assert_allclose(metrics["rms_acceleration_top"], [0.25], rtol=1e-3)
    np.testing.assert_allclose(metrics["peak_acceleration_top_mg"], [2.75 / 9.80665 * 1e3], rtol=1e-6)
    np.testing.assert_allclose(metrics["rms_top_displacement"], [0.5], rtol=1e-3)
    np.testing.assert_allclose(
        metrics["peak_acceleration_mg"], [5.5 / 9.80665 * 1e3, 2.75 / 9.80665 * 1e3], rtol=1e-6
    )


def test_the_ratio_to_the_reference_is_the_larger_of_the_peak_ratio_and_the_mean_story_ratio():
    reference = response(1.0, 0.0)  # story peaks 2 and 4
    assert ratio_to_reference(reference, reference) == 1.0
    assert ratio_to_reference(response(1.5, 0.0), reference) == pytest.approx(1.5)
    lopsided = response(1.0, 0.0)
    lopsided.drift[:, 0] *= 1.8  # story 1 peaks at 3.6, below story 2's reference 4: the overall peak holds
    assert ratio_to_reference(lopsided, reference) == pytest.approx((1.8 + 1.0) / 2)  # the mean J1 catches it
