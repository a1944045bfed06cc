"""Linear shear building: mass, stiffness, damping and actuator matrices, with its mass devices.

Conventions (see design.md): n floors, floor 0 is the ground. Story i joins floor i-1 and
floor i; mass m_i sits at floor i and story i has stiffness k_i. Coordinates are displacements
relative to the ground, so

    M x'' + C x' + K x = -M 1 a_g + Gamma u.

Mass devices (tuned masses, active mass drivers) add one degree of freedom each after the n
floors: a mass m_d joined to its floor by k_d and c_d; an active one adds a column to Gamma
(+1 on the mass, -1 on its floor). The commanded forces u are the actuators' then the active
masses'. Units: kg, N/m, N*s/m, N, s.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg

from rlcontroller.config import ActuatorConfig, BuildingConfig, MatrixBuildingConfig
from rlcontroller.devices import Damper as DamperConfig
from rlcontroller.devices import DeviceConfig, MassDevice


@dataclass(frozen=True)
class Building:
    """A shear building with its actuators and mass devices.

    `mass`, `stiffness`, `damping` are over the degrees of freedom: the floors, then one per mass
    device. `actuator_matrix` (Gamma, dofs x m) maps the commanded forces u (N) to forces on the
    degrees of freedom (N); `force_limits` (m,) are their limits (N).
    """

    mass: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    actuator_matrix: np.ndarray
    force_limits: np.ndarray
    story_heights: np.ndarray | None = None
    devices: tuple[MassDevice, ...] = ()
    dampers: tuple[
        DamperConfig, ...
    ] = ()  # semi-active, as configured; their commands are the last columns of Gamma

    @property
    def n_dofs(self) -> int:
        """Degrees of freedom: the floors, then the mass devices."""
        return self.mass.shape[0]

    @property
    def n_states(self) -> int:
        """Length of the state [x; x']."""
        return 2 * self.mass.shape[0]

    @property
    def n_floors(self) -> int:
        return self.mass.shape[0] - len(self.devices)

    @property
    def n_actuators(self) -> int:
        return self.actuator_matrix.shape[1]

    @property
    def floor_masses(self) -> np.ndarray:
        """Floor masses m_i (kg), floor 1 first."""
        return np.diag(self.mass)[: self.n_floors].copy()

    @property
    def dof_floors(self) -> np.ndarray:
        """The floor (1-based) of each degree of freedom: its own, or the one a device sits on."""
        return np.array([*range(1, self.n_floors + 1), *(device.floor for device in self.devices)])

    def drift_matrix(self) -> np.ndarray:
        """D (floors x dofs) with story drift = D x: x_j - x_(j-1), the ground's x_0 = 0."""
        n = self.n_dofs
        return (np.eye(n) - np.eye(n, k=-1))[: self.n_floors]

    def stroke_matrix(self) -> np.ndarray:
        """S (devices x dofs) with stroke = S x: each device's displacement relative to its floor."""
        matrix = np.zeros((len(self.devices), self.n_dofs))
        for index, device in enumerate(self.devices):
            matrix[index, self.n_floors + index] = 1.0
            matrix[index, device.floor - 1] = -1.0
        return matrix

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


def rayleigh_coefficients(
    omega_a: float, ratio_a: float, omega_b: float, ratio_b: float
) -> tuple[float, float]:
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


def tune_devices(building: Building, devices: list[DeviceConfig]) -> tuple[MassDevice, ...]:
    """The mass devices among `devices`, tuned on `building` (the design model)."""
    omega, shapes = natural_modes(building.mass, building.stiffness)
    return tuple(device.tuned(building.mass, omega, shapes) for device in devices if not device.semi_active)


def with_devices(building: Building, devices: tuple[MassDevice, ...]) -> Building:
    """`building` (without devices) with the mass devices added as degrees of freedom after its
    floors, the active ones' forces after its actuators'."""
    n, count = building.n_dofs, len(devices)
    size = n + count
    mass, stiffness, damping = (np.zeros((size, size)) for _ in range(3))
    mass[:n, :n], stiffness[:n, :n], damping[:n, :n] = building.mass, building.stiffness, building.damping
    active = [index for index, device in enumerate(devices) if device.active]
    gamma = np.zeros((size, building.n_actuators + len(active)))
    gamma[:n, : building.n_actuators] = building.actuator_matrix
    for index, device in enumerate(devices):
        dof, floor = n + index, device.floor - 1
        mass[dof, dof] = device.mass
        for matrix, value in ((stiffness, device.stiffness), (damping, device.damping)):
            matrix[dof, dof] += value
            matrix[floor, floor] += value
            matrix[dof, floor] -= value
            matrix[floor, dof] -= value
    for column, index in enumerate(active, start=building.n_actuators):
        gamma[n + index, column], gamma[devices[index].floor - 1, column] = 1.0, -1.0
    limits = np.concatenate([building.force_limits, [devices[index].force_limit for index in active]])
    return replace(
        building,
        mass=mass,
        stiffness=stiffness,
        damping=damping,
        actuator_matrix=gamma,
        force_limits=limits,
        devices=devices,
    )


def with_dampers(building: Building, dampers: list[DamperConfig]) -> Building:
    """`building` with its semi-active dampers: an inter-story column of Gamma each, after the other
    commanded devices, with a unit "limit" (the action itself is the damper's command)."""
    gamma = actuator_matrix(building.n_dofs, [ActuatorConfig(story=damper.story) for damper in dampers])
    return replace(
        building,
        actuator_matrix=np.hstack([building.actuator_matrix, gamma]),
        force_limits=np.concatenate([building.force_limits, np.ones(len(dampers))]),
        dampers=tuple(dampers),
    )


def modal_damping_matrix(mass: np.ndarray, stiffness: np.ndarray, ratios: list[float]) -> np.ndarray:
    """The classical damping matrix with the given ratio for each mode (the last ratio for the higher
    modes): C = M Phi diag(2 zeta_i omega_i) Phi' M, with M-normalised Phi."""
    omega, shapes = natural_modes(mass, stiffness)
    zeta = np.array([ratios[min(i, len(ratios) - 1)] for i in range(omega.size)])
    return mass @ shapes @ np.diag(2.0 * zeta * omega) @ shapes.T @ mass


def from_matrices(building: MatrixBuildingConfig, actuators: list[ActuatorConfig]) -> Building:
    """A building given by its matrices (SI), one translational degree of freedom per floor."""
    mass = np.asarray(building.mass_matrix, dtype=float)
    stiffness = np.asarray(building.stiffness_matrix, dtype=float)
    if building.damping_matrix is not None:
        damping = np.asarray(building.damping_matrix, dtype=float)
    else:
        damping = modal_damping_matrix(mass, stiffness, building.modal_damping)
    return Building(
        mass=mass,
        stiffness=stiffness,
        damping=damping,
        actuator_matrix=actuator_matrix(mass.shape[0], actuators),
        force_limits=np.array([a.force_limit for a in actuators], dtype=float),
        story_heights=np.asarray(building.story_heights, dtype=float),
    )


def build(building: BuildingConfig, actuators: list[ActuatorConfig]) -> Building:
    """Assemble M, K, C and Gamma of the floors and actuators from the validated configuration
    (`with_devices` adds the mass devices)."""
    if isinstance(building, MatrixBuildingConfig):
        return from_matrices(building, actuators)
    mass = np.diag(np.asarray(building.masses, dtype=float))
    stiffness = shear_stiffness_matrix(np.asarray(building.stiffnesses, dtype=float))
    if building.damping.matrix is not None:
        damping = np.asarray(building.damping.matrix, dtype=float)
    else:
        omega, _ = natural_modes(mass, stiffness)
        first, second = building.damping.rayleigh
        a0, a1 = rayleigh_coefficients(
            omega[first.mode - 1], first.ratio, omega[second.mode - 1], second.ratio
        )
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
