"""A nonlinear reduced model of an FE plant, calibrated from the FE model itself: what both reduced models
share (the calibration motions, the FE runs, the fit and its judgment) and the story springs' fit.

The FE plant's design model (its floor masses, the stiffness condensed to the floors, its damping mode by
mode) gets a Bouc-Wen spring in every story (`physics.hysteresis`: per story yield drift d_y, post-yield
ratio a, exponent n and shape beta, gamma = 1 - beta; the rest of the condensed stiffness stays linear), as
Patsialis & Taflanidis (Engineering Structures 2020) reduced the ASCE 9-story benchmark.

Calibration: a first-mode pushover of the FE model (`physics.fe.pushover`) gives each story's yield drift and
post-yield ratio to start from; the FE model runs uncontrolled on generated Kanai-Tajimi motions strong
enough to yield it (PGA 0.3-1.2 g, soft to firm soil, each followed by the settling tail that leaves the
residual drift); least squares (scipy's trust region reflective, within bounds: the yield drifts within a
factor 3 of the pushover's; a post-yield ratio down to -0.5, a story losing strength as the FE model's P-Delta
makes it, with every story collapsing past COLLAPSE_DRIFT_RATIO of its height) fits the 4 n parameters to the
FE story drift histories, each story's on each motion scaled by its peak, and to the residual drifts. Holding
the pushover's yield drifts and ratios and fitting only n and beta leaves a cost 7x higher on the nine-story
frame (docs/opensees.md). The fit is judged on other motions from another seed, never the records or a check
suite's: per story, the median relative error of the peak drift and of the residual drift, beside the linear
reduced model's. Nothing here knows what the FE model is made of: a Python or Tcl model, through the plant
protocol. The fishbone's fit is `identification.fishbone`'s, and `identification.reduction` chooses between
the two.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd

from rlcontroller.config import HysteresisConfig, KanaiTajimiConfig
from rlcontroller.errors import ModelError
from rlcontroller.physics.fe.pushover import Pushover
from rlcontroller.physics.fishbone import hysteretic_model
from rlcontroller.physics.metrics import RESIDUAL_WINDOW_S, peak
from rlcontroller.physics.motions.excitation import (
    STANDARD_GRAVITY,
    Load,
    on_control_grid,
    with_settling_tail,
)
from rlcontroller.physics.motions.generators import generate_suite
from rlcontroller.physics.plant import Plant
from rlcontroller.physics.response import Response

CALIBRATION_MOTIONS = KanaiTajimiConfig(
    dt=0.02,
    duration=(20.0, 30.0),
    ground_frequency=(5.0, 30.0),
    ground_damping=(0.4, 0.8),
    pga=(0.3 * STANDARD_GRAVITY, 1.2 * STANDARD_GRAVITY),
)
FIT_SEED, TEST_SEED = 20_000, 20_001  # training draws from 0 up, validation 10000, the check suites 31337
YIELD_RANGE = 3.0  # the fit keeps each story's yield drift within this factor of its pushover's
# per story; a negative post-yield ratio: the story loses strength past yield (the FE model's P-Delta)
BOUNDS = {"post_yield_ratio": (-0.5, 0.95), "exponent": (1.0, 20.0), "beta": (0.05, 0.95)}
# of the story height: the reduced model's stories collapse past it. Past what the FE model survives: the
# nine-story frame (hinges that do not lose strength) drifted 14.8 % of a story on a fit motion and stood; at
# 10 % the reduced models collapsed there and the fishbone's fit cost 456 instead of 110 (docs/opensees.md)
COLLAPSE_DRIFT_RATIO = 0.20
# RK4 sub-steps per ground sample: 2 while fitting (fast), 4 in the model written and judged. The exponent may
# reach 20 (an elastic-plastic hinge): the integrator reads |z|^n as at most 1 (`integrators.z_rate`), without
# which loops of exponent 10 diverged on 4 of the check suite's 320 motions at 2 sub-steps.
FIT_SUBSTEPS, PLANT_SUBSTEPS = 2, 4
MAX_EVALUATIONS = 200  # of the residuals (each Jacobian takes 4 n more)
YIELD_SPREAD = (0.8, 1.25)  # training draws every story's yield drift times a factor in this range
RESIDUAL_WEIGHT = 3.0  # a residual drift's error counts as much as this many samples of a history


@dataclass
class Fit:
    """A yielding model fitted to FE drift histories: its hysteresis, the least-squares cost at the end (half
    the sum of squared scaled residuals) and the residuals' evaluations it took."""

    hysteresis: HysteresisConfig
    cost: float
    evaluations: int


def calibration_motions(count: int, seed: int) -> list[Load]:
    """`count` strong generated motions, each followed by SETTLING_TAIL_S of rest."""
    return [with_settling_tail(motion) for motion in generate_suite(CALIBRATION_MOTIONS, count, seed)]


def fe_responses(plant: Plant, motions: list[Load]) -> list[Response]:
    """The FE model's uncontrolled responses (its design model's actuators idle; kept between commands,
    `simulation.kept`: calibrating again runs no FE model)."""
    from rlcontroller.simulation.kept import uncontrolled

    return uncontrolled(plant.bare, motions)


def reduced_drifts(design: Plant, hysteresis: HysteresisConfig | None, motion: Load) -> np.ndarray:
    """Story drift histories (K + 1, n) (m) of the design model with `hysteresis` (story springs or a
    fishbone; None: linear) under `motion`."""
    grid = on_control_grid(motion, design.control_dt)
    if hysteresis is None:
        return design.bare.sampled(grid.substeps).simulate(grid).drift
    states = hysteretic_model(design.building, hysteresis).history(
        grid.ground, grid.substeps, design.control_dt
    )
    return states[:, : design.building.n_floors] @ design.building.drift_matrix().T


def residual(drift: np.ndarray, control_dt: float) -> np.ndarray:
    """Per story, the mean drift over the last RESIDUAL_WINDOW_S (m): the residual drift, signed."""
    return np.mean(drift[-max(1, round(RESIDUAL_WINDOW_S / control_dt)) :], axis=0)


def hysteresis_of(
    parameters: np.ndarray, substeps: int, collapse_drift: list[float] | None
) -> HysteresisConfig:
    """The per-story HysteresisConfig of the fit's parameter vector [log d_y; a; n; beta] (4 n), its stories
    collapsing past `collapse_drift` (m; None: never)."""
    log_drift, ratio, exponent, beta = parameters.reshape(4, -1)
    return HysteresisConfig(
        collapse_drift=collapse_drift,
        yield_drift=np.exp(log_drift).tolist(),
        post_yield_ratio=ratio.tolist(),
        exponent=exponent.tolist(),
        beta=beta.tolist(),
        gamma=(1.0 - beta).tolist(),
        substeps=substeps,
    )


def least_squares(
    design: Plant,
    motions: list[Load],
    targets: list[np.ndarray],
    start: np.ndarray,
    *,
    bounds: tuple[np.ndarray, np.ndarray],
    model_of: Callable[[np.ndarray], HysteresisConfig],
) -> Fit:
    """The parameters within `bounds` from `start` whose hysteresis (`model_of`) best reproduces the FE drift
    histories `targets` ((K + 1, n) per motion): each story's history on a motion scaled by its FE peak,
    sampled every control step, and its residual drift (weight RESIDUAL_WEIGHT) on the same scale."""
    import scipy.optimize

    scales = [np.maximum(peak(target), 1e-6) for target in targets]
    dt = design.control_dt

    def residuals(parameters: np.ndarray) -> np.ndarray:
        hysteresis = model_of(parameters)
        parts = []
        for motion, target, scale in zip(motions, targets, scales, strict=True):
            drift = reduced_drifts(design, hysteresis, motion)
            if not np.all(np.isfinite(drift)):  # a step too long for so sharp a yield: as far off as can be
                drift = np.where(np.isfinite(drift), drift, 1e3 * scale)
            parts.append(((drift - target) / scale).ravel())
            parts.append(RESIDUAL_WEIGHT * (residual(drift, dt) - residual(target, dt)) / scale)
        return np.concatenate(parts)

    result = scipy.optimize.least_squares(
        residuals, start, bounds=bounds, x_scale="jac", max_nfev=MAX_EVALUATIONS
    )
    return Fit(model_of(result.x), float(result.cost), int(result.nfev))


def fit(
    design: Plant,
    motions: list[Load],
    targets: list[np.ndarray],
    pushed: Pushover,
    *,
    substeps: int = FIT_SUBSTEPS,
    collapse: list[float] | None = None,
) -> Fit:
    """Bouc-Wen story springs fitted (`least_squares`) to the FE drift histories `targets` from the yield
    drifts and post-yield ratios of the FE model's pushover (`pushed`), exponent 2 and beta 0.5. With
    `collapse` drifts (m per story) a story may lose strength past yield (a down to BOUNDS' lower one);
    without, a >= 0."""
    n = design.building.n_floors
    bounds = (
        BOUNDS
        if collapse is not None
        else BOUNDS | {"post_yield_ratio": (0.0, BOUNDS["post_yield_ratio"][1])}
    )
    ratio = np.clip(pushed.post_yield_ratio, *bounds["post_yield_ratio"])
    start = np.concatenate([np.log(pushed.yield_drift), ratio, np.full(n, 2.0), np.full(n, 0.5)])
    low = np.concatenate(
        [start[:n] - np.log(YIELD_RANGE), *(np.full(n, bound[0]) for bound in bounds.values())]
    )
    high = np.concatenate(
        [start[:n] + np.log(YIELD_RANGE), *(np.full(n, bound[1]) for bound in bounds.values())]
    )
    return least_squares(
        design,
        motions,
        targets,
        start,
        bounds=(low, high),
        model_of=lambda p: hysteresis_of(p, substeps, collapse),
    )


def collapse_drifts(design: Plant) -> list[float]:
    """Each story's collapse drift (m): COLLAPSE_DRIFT_RATIO of its height (the design model's)."""
    heights = design.building.story_heights
    if heights is None:
        raise ModelError(
            "the FE model's description gives no story_heights: the reduced model's collapse needs them"
        )
    return (COLLAPSE_DRIFT_RATIO * np.asarray(heights)).tolist()


def accuracy(
    design: Plant, models: dict[str, HysteresisConfig | None], motions: list[Load], targets: list[np.ndarray]
) -> pd.DataFrame:
    """Per story, over `motions`: for each of `models` (by its label; None: the linear reduced model) the
    median relative error of the peak drift and of the residual drift (|model - FE| / FE; the residual's
    against the FE peak drift when the FE residual is under 1 % of it, as a residual that small is noise),
    then the FE's."""
    dt, rows = design.control_dt, {}
    for label, model in models.items():
        peak_errors, residual_errors = [], []
        for motion, target in zip(motions, targets, strict=True):
            drift = reduced_drifts(design, model, motion)
            fe_peak, fe_residual = peak(target), np.abs(residual(target, dt))
            peak_errors.append(np.abs(peak(drift) - fe_peak) / fe_peak)
            reference = np.maximum(fe_residual, 0.01 * fe_peak)
            residual_errors.append(np.abs(np.abs(residual(drift, dt)) - fe_residual) / reference)
        rows[f"peak_drift_error_{label}"] = np.median(peak_errors, axis=0)
        rows[f"residual_drift_error_{label}"] = np.median(residual_errors, axis=0)
    rows["fe_peak_drift_m"] = np.median([peak(t) for t in targets], axis=0)
    rows["fe_residual_drift_m"] = np.median([np.abs(residual(t, dt)) for t in targets], axis=0)
    frame = pd.DataFrame(rows)
    frame.index = pd.RangeIndex(1, len(frame) + 1, name="story")
    return frame
