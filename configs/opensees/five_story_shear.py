"""The paper's five-story shear building (configs/buildings/five_story.yaml) as an OpenSees model.

Eshkevari, Eshkevari, Sen and Pakzad's building: floor masses 25, 20, 20, 18, 15 t and story stiffnesses
5, 4, 4, 3, 3 MN/m (floor 1 first), Rayleigh damping of 1 % in mode 1 and 5 % in mode 5. A one-dimensional
model (ndm 1, ndf 1): a node per floor 1 m apart, a truss of axial stiffness E A / L = k_i per story (along
the building's lateral direction), the ground node fixed. It must agree with rlc's own plant of that
building (tests/test_opensees_plant.py: peak drifts within 0.1 % on the seven records).

This file is code: rlc runs it only when you name an experiment that names it (docs/opensees.md).
"""

import numpy as np
from scipy.linalg import eigh

MASSES = [25.0e3, 20.0e3, 20.0e3, 18.0e3, 15.0e3]  # kg
STIFFNESSES = [5.0e6, 4.0e6, 4.0e6, 3.0e6, 3.0e6]  # N/m
STORY_HEIGHT = 3.0  # m (the paper gives none; rlc uses them for drift ratios only)
DAMPING = ((1, 0.01), (5, 0.05))  # (mode, ratio): Rayleigh, C = a0 M + a1 K


def build_model(ops):
    """Build the model in the OpenSees domain; return what rlc needs of it."""
    ops.model("basic", "-ndm", 1, "-ndf", 1)
    ops.node(0, 0.0)
    ops.fix(0, 1)
    for floor, (mass, stiffness) in enumerate(zip(MASSES, STIFFNESSES, strict=True), start=1):
        ops.node(floor, float(floor))
        ops.mass(floor, mass)
        ops.uniaxialMaterial("Elastic", floor, stiffness)  # E with A = L = 1: E A / L = k
        ops.element(
            "truss", floor, floor - 1, floor, 1.0, floor, "-doRayleigh", 1
        )  # a truss has no Rayleigh damping unless asked
    n = len(MASSES)
    drift = np.eye(n) - np.eye(n, k=-1)  # story i's drift from the floor displacements
    circular = np.sqrt(eigh(drift.T @ np.diag(STIFFNESSES) @ drift, np.diag(MASSES), eigvals_only=True))
    (i, zeta_i), (j, zeta_j) = DAMPING
    w_i, w_j = circular[i - 1], circular[j - 1]
    # zeta = a0 / (2 w) + a1 w / 2 at both modes
    a1 = 2.0 * (zeta_j * w_j - zeta_i * w_i) / (w_j**2 - w_i**2)
    a0 = 2.0 * zeta_i * w_i - a1 * w_i**2
    ops.rayleigh(a0, 0.0, a1, 0.0)  # the stiffness part on the current (here: constant) stiffness
    return {
        "floors": [[floor] for floor in range(1, len(MASSES) + 1)],
        "direction": 1,
        "story_heights": [STORY_HEIGHT] * len(MASSES),
        "rayleigh": [float(a0), float(a1)],
    }
