"""A first-mode pushover of an FE model, and each story's bilinear idealisation of it.

The model (a Python or Tcl file, `physics.fe.opensees`) is built at rest under its gravity loads; lateral
forces in the shape M phi_1 (its reduced model's first mode, at the floors' control nodes) are raised by
displacement control of the roof, in `steps` equal increments up to `roof_drift` of the building's height
(Newton, then the fallbacks of a time step; the push stops early where none converges, past the frame's
capacity). Each story's shear is the sum of the lateral forces above it; its drift the difference of its
floors' displacements.

Each story's shear-drift curve is idealised as bilinear by equal energy (FEMA 356's method): the initial
stiffness k_0 (the reduced model's story spring, `physics.hysteresis.story_springs`), then the line to the
curve's last point, the two enclosing the same area as the curve. Its knee is the story's yield drift d_y; the
second slope over k_0 its post-yield ratio (negative where P-Delta wins). A story whose curve stays within 5 %
of k_0 d never yielded in the push: its yield drift is then the largest drift it reached, a lower bound (so
the ductility computed with it, an upper bound).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rlcontroller.physics.fe.build import build_model
from rlcontroller.physics.fe.integrator import check_floors, set_solver
from rlcontroller.physics.fe.opensees import NonConvergence, opensees
from rlcontroller.physics.hysteresis import drift_matrix, story_springs

PUSH_SERIES = PUSH_PATTERN = 103  # beside the plant's own (`physics.fe.opensees`: 101, 102)
ELASTIC_TOLERANCE = 0.05  # a story within 5 % of its initial stiffness at the end of the push never yielded


@dataclass(frozen=True)
class Pushover:
    """A first-mode pushover: per step the story drifts (m) and shears (N), and each story's bilinear
    idealisation: initial stiffness (N/m), yield drift (m), post-yield ratio, and whether it yielded."""

    drift: np.ndarray  # (steps + 1, n)
    shear: np.ndarray  # (steps + 1, n)
    stiffness: np.ndarray
    yield_drift: np.ndarray
    post_yield_ratio: np.ndarray
    yielded: np.ndarray  # bool (n,)


def bilinear(drift: np.ndarray, shear: np.ndarray, stiffness: float) -> tuple[float, float, bool]:
    """The equal-energy bilinear idealisation of one story's curve from the origin (drift (m), shear (N),
    rising drift): (yield drift (m), post-yield ratio, whether it yielded)."""
    last_drift, last_shear = float(drift[-1]), float(shear[-1])
    if last_shear >= (1.0 - ELASTIC_TOLERANCE) * stiffness * last_drift:
        return last_drift, 1.0, False
    area = float(np.trapezoid(shear, drift))
    # 0.5 k d_y^2 + 0.5 (k d_y + V) (D - d_y) = area  =>  d_y (k D - V) = 2 area - V D
    yield_drift = (2.0 * area - last_shear * last_drift) / (stiffness * last_drift - last_shear)
    yield_drift = float(np.clip(yield_drift, 1e-9, last_drift))
    slope = (last_shear - stiffness * yield_drift) / max(last_drift - yield_drift, 1e-12)
    return yield_drift, slope / stiffness, True


def pushover(
    path: Path,
    function: str,
    mass: np.ndarray,
    stiffness: np.ndarray,
    *,
    roof_drift: float = 0.04,
    steps: int = 200,
) -> Pushover:
    """Push the FE model of `path` in its first mode's shape to `roof_drift` (of its height) and idealise
    each story's curve (module docstring); `mass` (kg) and `stiffness` (N/m) are its reduced model's floor
    matrices (`physics.fe.build.reduced_building`: the plant's design building), which give the shape."""
    import scipy.linalg

    description = build_model(path, function)  # at rest under its gravity loads, as the push starts
    check_floors(description, len(mass), path)
    ops, nodes, dof = opensees(), description.control_nodes, description.direction
    _, shapes = scipy.linalg.eigh(stiffness, mass, subset_by_index=[0, 0])
    pattern = mass @ shapes[:, 0]
    pattern = pattern / pattern[-1]  # the roof's force 1 (the load factor's unit, in the model's force)
    at_rest = np.array([ops.nodeDisp(n, dof) for n in nodes])
    ndf = np.atleast_1d(ops.nodeDisp(nodes[0])).size
    ops.timeSeries("Linear", PUSH_SERIES)
    ops.pattern("Plain", PUSH_PATTERN, PUSH_SERIES)
    for node, force in zip(nodes, pattern, strict=True):
        ops.load(node, *[float(force) if d == dof else 0.0 for d in range(1, ndf + 1)])
    height = sum(description.story_heights)  # model units
    increment = roof_drift * height / steps
    set_solver(description, path)
    ops.numberer("RCM")
    ops.integrator("DisplacementControl", nodes[-1], dof, increment)
    ops.analysis("Static")
    displacements, factors = [np.zeros(len(nodes))], [0.0]
    for _ in range(steps):
        if not _pushed(ops, description.algorithms):
            break  # past the frame's capacity: the curve so far
        displacements.append(np.array([ops.nodeDisp(n, dof) for n in nodes]) - at_rest)
        factors.append(float(ops.getTime()))
    ops.wipe()
    if len(factors) < 3:
        raise NonConvergence(
            f"{path}: the pushover did not converge at its first steps (of {increment:g} at the roof)"
        )
    floors = np.array(displacements) * description.length
    story_shear = np.outer(factors, np.cumsum(pattern[::-1])[::-1]) * description.force
    story_drift = floors @ drift_matrix(len(nodes)).T
    springs = story_springs(mass, stiffness)
    fits = [bilinear(story_drift[:, i], story_shear[:, i], springs[i]) for i in range(len(nodes))]
    yield_drift, ratio, yielded = (np.array(values) for values in zip(*fits, strict=True))
    return Pushover(story_drift, story_shear, springs, yield_drift, ratio, yielded.astype(bool))


def _pushed(ops, algorithms: tuple) -> bool:
    """One displacement increment with each algorithm in turn (the first stays set): converged or not."""
    if ops.analyze(1) == 0:
        return True
    for algorithm in algorithms[1:]:
        ops.algorithm(*algorithm)
        converged = ops.analyze(1) == 0
        ops.algorithm(*algorithms[0])
        if converged:
            return True
    return False
