"""rlc reduce's two models: the fishbone's column line from a condensed stiffness, its hinges from noise-free
histories, and the model kept being the one that made the histories."""

from dataclasses import replace

import numpy as np
import pytest
from conftest import REPOSITORY
from test_hysteretic import motions

from rlcontroller.config import Experiment, HysteresisConfig
from rlcontroller.identification import fishbone
from rlcontroller.identification.hysteretic import accuracy, reduced_drifts
from rlcontroller.identification.reduction import fit_both
from rlcontroller.physics.fe.pushover import Pushover
from rlcontroller.physics.fishbone import ColumnLine
from rlcontroller.physics.plant import Plant

HEIGHTS = [3.0] * 5
# the "FE" frame: flexible beams (their rotations matter), columns stiffer below, a base spring
LINE = ColumnLine(
    np.array([25e3, 20e3, 20e3, 18e3, 15e3]),
    np.array(HEIGHTS),
    np.array([6e7, 5.5e7, 5e7, 4.5e7, 4e7]),
    np.array([8e7, 7e7, 7e7, 6e7, 4e7]),
    3e8,
)
HINGES = {
    "yield_rotation": [0.004, 0.004, 0.0035, 0.0035, 0.003],
    "post_yield_ratio": [0.05, 0.1, 0.05, 0.1, 0.05],
    "exponent": [2.0, 3.0, 1.5, 2.5, 2.0],
    "beta": [0.5, 0.6, 0.4, 0.5, 0.7],
    "gamma": [0.5, 0.4, 0.6, 0.5, 0.3],
}
STORIES = {
    "yield_drift": [0.010, 0.012, 0.012, 0.011, 0.009],
    "post_yield_ratio": [0.1, 0.05, 0.15, 0.1, 0.2],
    "exponent": [2.0, 3.0, 1.5, 2.5, 2.0],
    "beta": [0.5, 0.6, 0.4, 0.5, 0.7],
    "gamma": [0.5, 0.4, 0.6, 0.5, 0.3],
}


def true_fishbone(**update) -> HysteresisConfig:
    """The "FE" frame's hinges on LINE (2 RK4 sub-steps, as the fit steps)."""
    values = (
        {
            "model": "fishbone",
            "yield_drift": 0.01,
            "column_stiffness": LINE.column.tolist(),
            "substeps": 2,
            "beam_stiffness": LINE.beams.tolist(),
            "base_stiffness": LINE.base,
        }
        | HINGES
        | update
    )
    return HysteresisConfig(**values)


def design() -> Plant:
    """The default experiment's five-story masses on the column line's condensed stiffness, 3 m stories."""
    experiment = Experiment()
    experiment = experiment.model_copy(
        update={"building": experiment.building.model_copy(update={"story_heights": HEIGHTS})}
    )
    plant = Plant(experiment)
    assert np.allclose(np.diag(plant.building.mass)[:5], LINE.masses)
    plant.building = replace(plant.building, stiffness=LINE.lateral())
    return plant


def pushover_of(yield_drift: np.ndarray) -> Pushover:
    """A pushover that found these story yield drifts (m) and nothing else."""
    return Pushover(
        np.zeros((1, 5)), np.zeros((1, 5)), np.ones(5), yield_drift, np.full(5, 0.1), np.ones(5, bool)
    )


def test_the_column_line_is_found_from_its_condensed_stiffness():
    """Its 2 n + 1 values from the n x n matrix a column line condenses to: each to 1e-6."""
    found = fishbone.column_line(design().building)
    for mine, true in ((found.column, LINE.column), (found.beams, LINE.beams), (found.base, LINE.base)):
        np.testing.assert_allclose(mine, true, rtol=1e-6)


def test_the_hinges_are_found_from_histories_they_made():
    """From a pushover 40 % off, the fit returns the hinges that made the histories: other motions' peak and
    residual drifts to 1e-6 (the hinges yield: |z| reaches 0.9)."""
    plant = design()
    true = true_fishbone()
    fitting, testing = motions(2, 1), motions(2, 2)
    targets = [reduced_drifts(plant, true, motion) for motion in fitting]
    started = 3.0 * np.array(HINGES["yield_rotation"]) * np.array([1.4, 0.6, 1.4, 0.6, 1.4])  # ratio x 3 m
    found = fishbone.fit(plant, fitting, targets, pushover_of(started))
    np.testing.assert_allclose(found.hysteresis.yield_rotation, HINGES["yield_rotation"], rtol=1e-4)
    table = accuracy(
        plant, {"fit": found.hysteresis}, testing, [reduced_drifts(plant, true, m) for m in testing]
    )
    assert table["peak_drift_error_fit"].max() < 1e-6 and table["residual_drift_error_fit"].max() < 1e-6


@pytest.mark.parametrize(
    ("made_by", "kept"),
    [("fishbone", "fishbone"), ("story_springs", "story_springs")],
)
def test_the_model_kept_is_the_one_that_made_the_histories(made_by, kept):
    """Both models fitted to the same histories: the one that made them reaches a cost near 0, the other does
    not, and the lower cost is kept."""
    plant = design()
    true = true_fishbone() if made_by == "fishbone" else HysteresisConfig(substeps=2, **STORIES)
    fitting = motions(1, 1, seconds=8.0)
    targets = [reduced_drifts(plant, true, motion) for motion in fitting]
    pushed = pushover_of(np.array(STORIES["yield_drift"]) * np.array([1.2, 0.8, 1.2, 0.8, 1.2]))
    fits, chosen = fit_both(plant, fitting, targets, pushed, collapse=None)
    assert chosen == kept
    assert fits[kept].cost < 1e-6 < 1e-3 < min(fit.cost for key, fit in fits.items() if key != kept)
    assert all(fit.hysteresis.substeps == 4 for fit in fits.values())  # written as the plant steps them


def test_the_report_names_the_model_kept_and_judges_both():
    """calibration.md and the printed lines: the kept model first, its own parameters, both models' errors."""
    import pandas as pd

    from rlcontroller.api.identification import accuracy_lines, calibration_report
    from rlcontroller.identification.hysteretic import Fit
    from rlcontroller.identification.reduction import Calibration

    n = 5
    hinges = true_fishbone(yield_drift=[0.01] * n, collapse_drift=0.6)
    stories = HysteresisConfig(collapse_drift=0.6, **STORIES)
    errors = {
        f"{what}_drift_error_{key}": np.full(n, error)
        for what in ("peak", "residual")
        for key, error in (("story_springs", 0.30), ("fishbone", 0.05), ("linear", 0.9))
    }
    table = pd.DataFrame(
        errors | {"fe_peak_drift_m": np.full(n, 0.1), "fe_residual_drift_m": np.full(n, 0.02)}
    )
    table.index = pd.RangeIndex(1, n + 1, name="story")
    fits = {"story_springs": Fit(stories, 597.0, 52), "fishbone": Fit(hinges, 110.0, 40)}
    report = calibration_report(
        REPOSITORY / "x.yaml", Calibration(fits, "fishbone", pushover_of(np.full(n, 0.01)), table), 20, 8
    )
    assert (
        "**Kept: a fishbone" in report
        and "story springs 597 after 52" in report
        and "yield rotation (mrad)" in report
    )
    assert "| 3 | 30.0 | 5.0 | 90.0 | 30.0 | 5.0 | 90.0 | 100.0 | 20.0 |" in report
    assert "4.00" in report.split("| 1 |")[1].split("\n")[0]  # floor 1's yield rotation, mrad
    printed = accuracy_lines(table, "fishbone")
    assert "(fishbone / story_springs / linear)" in printed[0]
    assert " ".join(printed[1].split()) == "1 5.0 / 30.0 / 90.0 5.0 / 30.0 / 90.0"
