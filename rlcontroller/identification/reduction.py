"""`rlc reduce`'s calibration: both nonlinear reduced models fitted to the FE model's own runs, the better fit
kept.

Story springs (`identification.hysteretic`) make each story yield alone, as a frame whose columns or braces
yield does; a fishbone (`identification.fishbone`) makes each floor's beams yield, their hinges acting on the
stories above and below, as a moment frame with strong columns does. Both are fitted to the same FE runs on
the same motions by the same measure, and the one with the lower cost there is kept: the choice is made on the
fitted motions only, and both are then judged on the other motions, beside the linear reduced model.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from rlcontroller.config import Experiment, HysteresisConfig, PlantConfig, PlantRandomization, RandomRange
from rlcontroller.errors import ModelError
from rlcontroller.identification import fishbone, hysteretic
from rlcontroller.physics.fe.pushover import Pushover, pushover
from rlcontroller.physics.motions.excitation import SETTLING_TAIL_S, Load
from rlcontroller.physics.plant import Plant

MODELS = {"story_springs": "Bouc-Wen story springs", "fishbone": "a fishbone (column line, yielding beams)"}


@dataclass
class Calibration:
    """The fits of both models, the one kept, the pushover they started from, and how well they hold on other
    motions."""

    fits: dict[str, hysteretic.Fit]  # by MODELS' key
    chosen: str  # the key of the fit with the lowest cost
    pushover: Pushover
    # per story: median errors of peak and residual drift of each model and the linear one
    accuracy: pd.DataFrame

    @property
    def hysteresis(self) -> HysteresisConfig:
        return self.fits[self.chosen].hysteresis


def calibrate(
    plant: Plant,
    fit_count: int = 8,
    test_count: int = 8,
    on_progress: Callable[[str], None] | None = None,
) -> Calibration:
    """Fit both reduced models of `plant`'s design model to its FE model on `fit_count` motions, keep the one
    with the lower cost, and judge them on `test_count` others (`hysteretic.calibration_motions`)."""
    if plant.fe_model is None:
        raise ValueError("a nonlinear reduced model is calibrated from an FE plant (plant.opensees)")
    say = on_progress or (lambda _: None)
    design = plant.design
    fitting = hysteretic.calibration_motions(fit_count, hysteretic.FIT_SEED)
    testing = hysteretic.calibration_motions(test_count, hysteretic.TEST_SEED)
    say("a first-mode pushover of the FE model: each story's yield drift and post-yield ratio to start from")
    fe = plant.config.opensees
    pushed = pushover(Path(fe.model), fe.function, design.building.mass, design.building.stiffness)
    if not pushed.yielded.any():
        raise ModelError(
            f"{fe.model}: no story yields in a first-mode pushover to 4 % of the height: the model is "
            "linear, and its reduced model is the linear one rlc designs on already (a yielding fit of it "
            "would be wrong)"
        )
    say(
        f"the FE model on {fit_count + test_count} generated motions of 0.3-1.2 g, then {SETTLING_TAIL_S:g} "
        "s of rest"
    )
    targets = [response.drift for response in hysteretic.fe_responses(plant, fitting + testing)]
    collapse = hysteretic.collapse_drifts(design)
    fits, chosen = fit_both(design, fitting, targets[:fit_count], pushed, collapse=collapse, on_progress=say)
    say(f"kept {MODELS[chosen]} (the lower cost); judged on the other {test_count}")
    models = {key: fit.hysteresis for key, fit in fits.items()} | {"linear": None}
    table = hysteretic.accuracy(design, models, testing, targets[fit_count:])
    return Calibration(fits, chosen, pushed, table)


def fit_both(
    design: Plant,
    motions: list[Load],
    targets: list[np.ndarray],
    pushed: Pushover,
    *,
    collapse: list[float] | None,
    on_progress: Callable[[str], None] | None = None,
) -> tuple[dict[str, hysteretic.Fit], str]:
    """Both models fitted to the FE drift histories `targets` ((K + 1, n) per motion), their stories
    collapsing past `collapse` (m), written with PLANT_SUBSTEPS; and the key of the one with the lower
    cost."""
    say = on_progress or (lambda _: None)
    fits = {}
    for key, fitter in (("story_springs", hysteretic.fit), ("fishbone", fishbone.fit)):
        say(f"fitting {MODELS[key]}: {4 * design.building.n_floors} parameters to {len(motions)} motions")
        fit = fitter(design, motions, targets, pushed, substeps=hysteretic.FIT_SUBSTEPS, collapse=collapse)
        fit.hysteresis = fit.hysteresis.model_copy(update={"substeps": hysteretic.PLANT_SUBSTEPS})
        fits[key] = fit
        say(f"  cost {fit.cost:.4g} after {fit.evaluations} evaluations")
    return fits, min(fits, key=lambda key: fits[key].cost)


def nonlinear_reduced_experiment(plant: Plant, hysteresis: HysteresisConfig) -> Experiment:
    """The experiment with its FE plant replaced by the nonlinear reduced model: the design model's
    building (resolved, matrices written out) with `hysteresis` as its plant part, and for training its
    yield drifts drawn around the fit (a factor in YIELD_SPREAD, log-uniform; a fishbone's yield rotations
    with them) beside any randomisation the experiment had."""
    design = plant.design.experiment
    spread = RandomRange(low=hysteretic.YIELD_SPREAD[0], high=hysteretic.YIELD_SPREAD[1], log=True)
    randomization = design.plant_randomization or PlantRandomization()
    update = {
        "plant": PlantConfig(hysteresis=hysteresis),
        "plant_randomization": randomization.model_copy(update={"yield_drift": spread}),
    }
    return design.model_copy(update=update)
