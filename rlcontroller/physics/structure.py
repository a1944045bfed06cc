"""Linear shear building: mass, stiffness, damping and actuator matrices.

Conventions (see design.md): n floors, floor 0 is the ground. Story i joins floor i-1 and
floor i; mass m_i sits at floor i and story i has stiffness k_i. Coordinates are floor
displacements relative to the ground, so

    M x'' + C x' + K x = -M 1 a_g + Gamma u.

Units: kg, N/m, N*s/m, N, s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from rlcontroller.config import ActuatorConfig, BuildingConfig


@dataclass(frozen=True)
class Building:
    """A shear building with its actuators.

    `actuator_matrix` (Gamma, n x m) maps actuator forces u (N) to floor forces (N);
    `force_limits` (m,) are the actuators' force limits (N).
    """

    mass: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    actuator_matrix: np.ndarray
    force_limits: np.ndarray
    story_heights: np.ndarray | None = None

    @property
    def n_floors(self) -> int:
        return self.mass.shape[0]

    @property
    def n_actuators(self) -> int:
        return self.actuator_matrix.shape[1]

    @property
    def floor_masses(self) -> np.ndarray:
        """Floor masses m_i (kg), floor 1 first."""
        return np.diag(self.mass).copy()

    def modes(self) -> tuple[np.ndarray, np.ndarray]:
        """Natural circular frequencies (rad/s, ascending) and mass-normalised mode shapes."""
        return natural_modes(self.mass, self.stiffness)

    def periods(self) -> np.ndarray:
        """Natural periods (s), longest first."""
        omega, _ = self.modes()
        return 2.0 * np.pi / omega

    def modal_damping_ratios(self) -> np.ndarray:
        """Damping ratio of each mode, phi_i^T C phi_i / (2 omega_i), with M-normalised phi."""
        omega, shapes = self.modes()
        return np.einsum("ji,jk,ki->i", shapes, self.damping, shapes) / (2.0 * omega)


def natural_modes(mass: np.ndarray, stiffness: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Solve K phi = omega^2 M phi; return omega (rad/s, ascending) and phi with phi^T M phi = I."""
    eigenvalues, shapes = scipy.linalg.eigh(stiffness, mass)
    return np.sqrt(eigenvalues), shapes


def shear_stiffness_matrix(story_stiffness: np.ndarray) -> np.ndarray:
    """Tridiagonal stiffness matrix (N/m) of a shear building from story stiffnesses k_1..k_n."""
    k = np.asarray(story_stiffness, dtype=float)
    n = k.size
    k_above = np.append(k[1:], 0.0)
    matrix = np.diag(k + k_above)
    for i in range(n - 1):
        matrix[i, i + 1] = matrix[i + 1, i] = -k[i + 1]
    return matrix


def rayleigh_coefficients(omega_a: float, ratio_a: float, omega_b: float, ratio_b: float) -> tuple[float, float]:
    """Coefficients (a0, a1) of C = a0 M + a1 K giving the two damping ratios at the two frequencies.

    Each mode's ratio is zeta = a0 / (2 omega) + a1 omega / 2.
    """
    system = np.array([[1.0 / (2.0 * omega_a), omega_a / 2.0], [1.0 / (2.0 * omega_b), omega_b / 2.0]])
    a0, a1 = np.linalg.solve(system, [ratio_a, ratio_b])
    return float(a0), float(a1)


def actuator_matrix(n_floors: int, actuators: list[ActuatorConfig]) -> np.ndarray:
    """Gamma (n x m). Inter-story mount on story j: +1 on floor j, -1 on floor j-1 (none for the
    ground). Floor mount: +1 on floor j only."""
    gamma = np.zeros((n_floors, len(actuators)))
    for column, actuator in enumerate(actuators):
        floor = actuator.story - 1
        gamma[floor, column] = 1.0
        if actuator.mount == "inter_story" and floor > 0:
            gamma[floor - 1, column] = -1.0
    return gamma


def build(building: BuildingConfig, actuators: list[ActuatorConfig]) -> Building:
    """Assemble M, K, C and Gamma from the validated configuration."""
    mass = np.diag(np.asarray(building.masses, dtype=float))
    stiffness = shear_stiffness_matrix(np.asarray(building.stiffnesses, dtype=float))
    if building.damping.matrix is not None:
        damping = np.asarray(building.damping.matrix, dtype=float)
    else:
        omega, _ = natural_modes(mass, stiffness)
        first, second = building.damping.rayleigh
        a0, a1 = rayleigh_coefficients(omega[first.mode - 1], first.ratio, omega[second.mode - 1], second.ratio)
        damping = a0 * mass + a1 * stiffness
    heights = None if building.story_heights is None else np.asarray(building.story_heights, dtype=float)
    return Building(
        mass=mass,
        stiffness=stiffness,
        damping=damping,
        actuator_matrix=actuator_matrix(len(building.masses), actuators),
        force_limits=np.array([a.force_limit for a in actuators], dtype=float),
        story_heights=heights,
    )
