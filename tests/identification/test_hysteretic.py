"""The nonlinear reduced model's calibration: it finds the parameters that made noise-free histories, its
accuracy measure against hand-computed errors, and `rlc reduce`'s files and one-line errors."""

import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest
from conftest import REPOSITORY

from rlcontroller.config import Experiment, HysteresisConfig
from rlcontroller.identification.hysteretic import accuracy, calibration_motions, fit, reduced_drifts
from rlcontroller.physics.fe.pushover import Pushover
from rlcontroller.physics.motions.excitation import scale_to_pga
from rlcontroller.physics.plant import Plant
from tests.conftest import OPENSEES_FAILURES, OPENSEES_MISSING

DESIGN = Plant(Experiment())  # the five-story building: a shear building, its story springs its stiffnesses
TRUE = HysteresisConfig(
    yield_drift=[0.012, 0.010, 0.011, 0.009, 0.008],
    post_yield_ratio=[0.1, 0.05, 0.15, 0.1, 0.2],
    exponent=[2.0, 3.0, 1.5, 2.5, 2.0],
    beta=[0.5, 0.6, 0.4, 0.5, 0.7],
    gamma=[0.5, 0.4, 0.6, 0.5, 0.3],
    substeps=2,
)


def motions(count: int, seed: int, seconds: float = 12.0, pga: float = 3.0):
    """Short strong motions (`pga`, m/s^2: 3 yields every story), with their settling tail."""
    chosen = []
    for motion in calibration_motions(count, seed):
        keep = round(seconds / motion.dt)
        chosen.append(scale_to_pga(replace(motion, acceleration=motion.acceleration[:keep]), pga))
    return chosen


def test_the_fit_recovers_the_histories_that_known_parameters_made():
    """Noise-free 'FE' histories from the reduced model itself: from a pushover guess 40 % off, the fit
    reproduces other motions' peak drifts within 2 % per story (the linear model is far off)."""
    fitting, testing = motions(2, 1), motions(2, 2)
    targets = [reduced_drifts(DESIGN, TRUE, motion) for motion in fitting]
    assert np.max(np.abs(targets[0]) / np.array(TRUE.yield_drift)) > 2  # they yield
    guess = np.array(TRUE.yield_drift) * np.array([1.4, 0.6, 1.4, 0.6, 1.4])
    pushed = Pushover(
        np.zeros((1, 5)), np.zeros((1, 5)), np.ones(5), guess, np.full(5, 0.1), np.ones(5, bool)
    )
    found = fit(DESIGN, fitting, targets, pushed)
    models = {"fitted": found.hysteresis, "linear": None}
    table = accuracy(DESIGN, models, testing, [reduced_drifts(DESIGN, TRUE, motion) for motion in testing])
    assert table["peak_drift_error_fitted"].max() < 0.02 < 0.2 < table["peak_drift_error_linear"].min()
    assert found.cost < 1e-2


def test_the_fit_finds_a_story_that_loses_strength_where_stories_may_collapse():
    """With collapse drifts the fit may take a negative post-yield ratio, and finds the one that made the
    histories (story 2 losing strength); without, the ratios stay at or above 0."""
    true = TRUE.model_copy(update={"post_yield_ratio": [0.1, -0.02, 0.15, 0.1, 0.2], "collapse_drift": 0.3})
    fitting, testing = motions(2, 1, pga=2.0), motions(2, 2, pga=2.0)  # story 2 to a ductility of 6, not 30
    targets = [reduced_drifts(DESIGN, true, motion) for motion in fitting]
    # none falls
    assert 4.0 < np.max(np.abs(targets[0][:, 1])) / true.yield_drift[1] < 0.3 / true.yield_drift[1]
    guess = np.array(true.yield_drift) * np.array([1.2, 0.8, 1.2, 0.8, 1.2])
    pushed = Pushover(
        np.zeros((1, 5)), np.zeros((1, 5)), np.ones(5), guess, np.full(5, 0.1), np.ones(5, bool)
    )
    fitted = fit(DESIGN, fitting, targets, pushed, collapse=[0.3] * 5).hysteresis
    assert fitted.post_yield_ratio[1] == pytest.approx(-0.02, abs=0.01) and fitted.collapse_drift == [0.3] * 5
    table = accuracy(
        DESIGN, {"fitted": fitted}, testing, [reduced_drifts(DESIGN, true, motion) for motion in testing]
    )
    assert table["peak_drift_error_fitted"].max() < 0.02
    held = fit(DESIGN, fitting, targets, pushed).hysteresis
    assert min(held.post_yield_ratio) >= 0.0 and held.collapse_drift is None


def test_accuracy_is_the_median_relative_error_per_story():
    """Against 'FE' histories that are the model's own times 1.1, 1.2 and 1.3: every peak error is 1/11,
    1/6 and 3/13; the median 1/6; the residuals' errors the same, or smaller where a residual under 1 % of
    its peak is measured against that instead."""
    chosen = motions(3, 3)
    factors = (1.1, 1.2, 1.3)
    targets = [
        factor * reduced_drifts(DESIGN, TRUE, motion) for factor, motion in zip(factors, chosen, strict=True)
    ]
    table = accuracy(DESIGN, {"model": TRUE}, chosen, targets)
    np.testing.assert_allclose(table["peak_drift_error_model"], 0.2 / 1.2, rtol=1e-9)
    residual = table["residual_drift_error_model"]
    assert np.all(residual <= 0.2 / 1.2 + 1e-9) and np.sum(np.isclose(residual, 0.2 / 1.2, rtol=1e-9)) >= 3


def test_reduce_refuses_an_experiment_without_an_fe_plant(tmp_path):
    from typer.testing import CliRunner

    from rlcontroller.cli.app import app

    result = CliRunner().invoke(app, ["reduce", "configs/five_story.yaml", "--out", str(tmp_path / "r")])
    assert result.exit_code != 0
    assert "plant.opensees: expected an FE plant to calibrate a nonlinear reduced model from" in result.output
    assert len(result.output.strip().splitlines()) == 1 and not (tmp_path / "r").exists()


def test_reduce_refuses_a_linear_fe_model_in_one_line_before_its_runs(tmp_path):
    """The five-story OpenSees shear model never yields: a Bouc-Wen fit of it was 21-838 % off."""
    pytest.importorskip("openseespy.opensees", reason=OPENSEES_MISSING, exc_type=OPENSEES_FAILURES)
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "rlcontroller",
            "reduce",
            "studies/opensees/five_story_opensees.yaml",
            "--out",
            str(tmp_path / "r"),
        ],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=REPOSITORY,
    )
    lines = done.stderr.strip().splitlines()
    assert (
        done.returncode != 0 and "no story yields in a first-mode pushover to 4 % of the height" in lines[-1]
    )
    assert "generated motions" not in done.stdout + done.stderr  # refused before the FE model's runs
    assert not (tmp_path / "r").exists()
