"""The fishbone reduced model's fit (`physics.fishbone`, Nakashima, Ogawa & Inoue 2002): a moment frame whose
beams yield, its floors coupled through their rotations.

1. Linear: the column line's EI per story, the beams' rotational stiffness per floor and the base's (2 n + 1
   values) by least squares on the FE model's condensed stiffness and its inverse (each entry scaled by its
   diagonals): the reduced model starts where the design model is (on the nine-story frame: periods within 1
   %).
2. Non-linear: each floor's beam spring yields (Bouc-Wen on its rotation). Its 4 n parameters (log theta_y, a
   in [0, 0.95], n and beta within `hysteretic.BOUNDS`) are fitted as the story springs are
   (`hysteretic.least_squares`: the same FE runs, scaling and residual weight), theta_y within a factor
   YIELD_RANGE of the pushover's story yield drift ratios (the mean of the two stories a floor joins); a >= 0,
   as the strength a frame loses is the leaning column's P-Delta (the floors' weights), not the hinges'.
"""

from __future__ import annotations

import numpy as np

from rlcontroller.config import HysteresisConfig
from rlcontroller.identification.hysteretic import BOUNDS, FIT_SUBSTEPS, YIELD_RANGE, Fit, least_squares
from rlcontroller.physics.fe.pushover import Pushover
from rlcontroller.physics.fishbone import ColumnLine
from rlcontroller.physics.motions.excitation import Load
from rlcontroller.physics.plant import Plant
from rlcontroller.physics.structure import Building


def column_line(building: Building) -> ColumnLine:
    """The column line (EI, k_b, k_0) on `building`'s floor masses (kg) and story heights (m) whose condensed
    lateral stiffness matches the building's (N/m) and its inverse."""
    import scipy.optimize

    n = building.n_floors
    if building.story_heights is None:
        raise ValueError("a fishbone needs the building's story_heights (m)")
    masses, heights = np.diag(building.mass)[:n].copy(), np.asarray(building.story_heights, dtype=float)
    stiffness = building.stiffness[:n, :n]
    flexibility = np.linalg.inv(stiffness)
    scale_k = np.sqrt(np.outer(np.diag(stiffness), np.diag(stiffness)))
    scale_f = np.sqrt(np.outer(np.diag(flexibility), np.diag(flexibility)))

    def line_of(p: np.ndarray) -> ColumnLine:
        return ColumnLine(masses, heights, np.exp(p[:n]), np.exp(p[n : 2 * n]), float(np.exp(p[2 * n])))

    def residuals(p: np.ndarray) -> np.ndarray:
        k = line_of(p).lateral()
        return np.concatenate(
            [((k - stiffness) / scale_k).ravel(), ((np.linalg.inv(k) - flexibility) / scale_f).ravel()]
        )

    column = np.full(n, np.median(np.diag(stiffness)) * heights.mean() ** 3 / 24)  # half a story's 12 EI/h^3
    start = np.log(np.concatenate([column, 6 * column / heights.mean(), [6 * column[0] / heights.mean()]]))
    result = scipy.optimize.least_squares(
        residuals, start, bounds=(start - 8, start + 8), x_scale="jac", max_nfev=5000
    )
    return line_of(result.x)


def fit(
    design: Plant,
    motions: list[Load],
    targets: list[np.ndarray],
    pushed: Pushover,
    *,
    substeps: int = FIT_SUBSTEPS,
    collapse: list[float] | None = None,
) -> Fit:
    """The fishbone on `design`'s building fitted to the FE drift histories `targets` ((K + 1, n) per motion),
    its hinges started from the pushover's (`pushed`) story yield drifts, exponent 2 and beta 0.5; the stories
    keep the pushover's yield drifts (ductility) and collapse past `collapse` (m per story; None: never)."""
    building = design.building
    line = column_line(building)
    ratio = pushed.yield_drift / line.heights
    # a floor's beams join the stories below, above
    rotation = np.append((ratio[:-1] + ratio[1:]) / 2, ratio[-1])
    n = line.n
    start = np.concatenate([np.log(rotation), np.full(n, 0.03), np.full(n, 2.0), np.full(n, 0.5)])
    low = np.concatenate(
        [
            start[:n] - np.log(YIELD_RANGE),
            np.zeros(n),
            np.full(n, BOUNDS["exponent"][0]),
            np.full(n, BOUNDS["beta"][0]),
        ]
    )
    high = np.concatenate(
        [
            start[:n] + np.log(YIELD_RANGE),
            np.full(n, BOUNDS["post_yield_ratio"][1]),
            np.full(n, BOUNDS["exponent"][1]),
            np.full(n, BOUNDS["beta"][1]),
        ]
    )

    def hysteresis_of(parameters: np.ndarray) -> HysteresisConfig:
        log_rotation, post_yield, exponent, beta = parameters.reshape(4, -1)
        return HysteresisConfig(
            model="fishbone",
            yield_drift=pushed.yield_drift.tolist(),
            yield_rotation=np.exp(log_rotation).tolist(),
            post_yield_ratio=post_yield.tolist(),
            exponent=exponent.tolist(),
            beta=beta.tolist(),
            gamma=(1.0 - beta).tolist(),
            collapse_drift=collapse,
            substeps=substeps,
            column_stiffness=line.column.tolist(),
            beam_stiffness=line.beams.tolist(),
            base_stiffness=line.base,
        )

    return least_squares(design, motions, targets, start, bounds=(low, high), model_of=hysteresis_of)
