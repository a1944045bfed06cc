"""The pushover's bilinear idealisation against curves whose answer is known, and the FE frame's pushover
against its own static condensation."""

from pathlib import Path

import numpy as np
import pytest

from rlcontroller.physics.fe.pushover import bilinear
from tests.conftest import OPENSEES_FAILURES, OPENSEES_MISSING


def test_a_bilinear_curve_is_idealised_as_itself():
    k, yield_drift, ratio = 2.0e8, 0.03, 0.05
    drift = np.linspace(0.0, 0.15, 301)
    shear = np.where(drift < yield_drift, k * drift, k * yield_drift + ratio * k * (drift - yield_drift))
    fitted_drift, fitted_ratio, yielded = bilinear(drift, shear, k)
    assert yielded and fitted_drift == pytest.approx(yield_drift, rel=1e-3)
    assert fitted_ratio == pytest.approx(ratio, rel=1e-2)


def test_equal_energy_holds_for_a_rounded_curve_and_an_elastic_one_never_yields():
    """A smooth curve (V = V_y tanh(k d / V_y)): the bilinear idealisation encloses the curve's area, its
    knee lies below the curve's asymptote; a straight line is reported as never yielding."""
    k, strength = 2.0e8, 6.0e6
    drift = np.linspace(0.0, 0.2, 2001)
    shear = strength * np.tanh(k * drift / strength)
    fitted_drift, ratio, yielded = bilinear(drift, shear, k)
    knee = k * fitted_drift
    area = 0.5 * knee * fitted_drift + 0.5 * (knee + shear[-1]) * (drift[-1] - fitted_drift)
    assert yielded and area == pytest.approx(np.trapezoid(shear, drift), rel=1e-9)
    assert knee < strength and 0.0 <= ratio < 0.05
    assert bilinear(drift, k * drift, k) == (drift[-1], 1.0, False)


@pytest.mark.slow
def test_the_frame_pushover_starts_at_its_condensed_story_stiffness_and_yields_every_story():
    pytest.importorskip("openseespy.opensees", reason=OPENSEES_MISSING, exc_type=OPENSEES_FAILURES)
    from rlcontroller.physics.fe.build import reduced_building
    from rlcontroller.physics.fe.pushover import pushover

    model = Path("configs/opensees/nine_story_frame.py")
    reduced = reduced_building(model, "build_model")
    floors = np.array(reduced["mass_matrix"]), np.array(reduced["stiffness_matrix"])
    push = pushover(model, "build_model", *floors, roof_drift=0.04, steps=200)
    first = push.shear[1] / push.drift[1]  # the first increment, 0.02 % of the height: elastic
    # the FE push against the static condensation
    np.testing.assert_allclose(first, push.stiffness, rtol=0.01)
    assert push.yielded.all() and np.all(push.drift[-1] > push.yield_drift)
    # 0.5-1.5 % of a story
    assert np.all((push.yield_drift / 3.96 > 0.005) & (push.yield_drift / 3.96 < 0.015))
    assert np.all((push.post_yield_ratio > -0.1) & (push.post_yield_ratio < 0.2))
