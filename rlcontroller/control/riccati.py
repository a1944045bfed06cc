"""The discrete Riccati equations of LQR and the Kalman filter, solved on the modes a design can use and
checked against their own equation.

A building's higher modes may be so heavily damped that they die within one control step (the 76-story
benchmark's damping matrix gives modes above about 15 Hz critical damping or more: at 0.1 s their
transition eigenvalues are 1e-17 to 1e-9). Such a mode is quasi-static at the control rate: no controller
acting once a step can move it, and its eigenvalue, zero to machine precision, makes the Riccati solver's
generalised Schur reordering fail. When the full equation fails, the design keeps the invariant subspace
of the modes whose transition eigenvalue is at least `QUASI_STATIC` in modulus (ordered real Schur form,
decoupled by a Sylvester equation: an exact modal truncation), solves there, and lifts the gains back to
the full state: an LQR gain acts on the kept modes' coordinates, a Kalman gain corrects only them. The
closed loop is block-triangular, the dropped modes keep their open-loop decay. Only then: a zero
eigenvalue is not always such a mode (an actuator delay's buffer has them, and the design must see the
delay), and where the full equation solves, nothing changes.

Every solution is checked: a relative residual of its equation above `RESIDUAL_TOLERANCE` is a
`DesignError`, never a silent gain.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from rlcontroller.config import ConfigError

QUASI_STATIC = 1.0e-6  # |eigenvalue| of the step below which a mode is quasi-static at the control rate
RESIDUAL_TOLERANCE = 1.0e-8  # relative residual of the Riccati equation a design must meet


class DesignError(ConfigError):
    """A controller or filter cannot be designed for this model (one line saying why; the model is the
    user's, so the command line shows it as their error)."""


@dataclass(frozen=True)
class ModalTruncation:
    """The kept modes' subspace of a transition matrix phi: z ~ basis q, q = projector z, with
    projector @ basis = I and projector @ phi = (projector @ phi @ basis) @ projector."""

    basis: np.ndarray  # (n, k)
    projector: np.ndarray  # (k, n)


def modal_truncation(phi: np.ndarray, smallest: float = QUASI_STATIC) -> ModalTruncation | None:
    """The subspace of the modes of `phi` whose eigenvalues have modulus >= `smallest`, or None when
    every mode is kept."""
    moduli = np.abs(np.linalg.eigvals(phi))
    if moduli.min() >= smallest:
        return None
    schur, vectors, kept = scipy.linalg.schur(
        phi, output="real", sort=lambda re, im: np.hypot(re, im) >= smallest
    )
    if kept == 0:
        raise DesignError(
            f"every mode decays within one control step (largest |eigenvalue| {moduli.max():.2g})"
        )
    # T = [[T11, T12], [0, T22]]: X with T11 X - X T22 = -T12 decouples the blocks
    coupling = scipy.linalg.solve_sylvester(schur[:kept, :kept], -schur[kept:, kept:], -schur[:kept, kept:])
    return ModalTruncation(
        basis=vectors[:, :kept], projector=vectors[:, :kept].T - coupling @ vectors[:, kept:].T
    )


def solve_dare(
    a: np.ndarray,
    b: np.ndarray,
    q: np.ndarray,
    r: np.ndarray,
    *,
    s: np.ndarray | None = None,
    what: str = "LQR",
) -> np.ndarray:
    """X of A'XA - X - (A'XB + S)(B'XB + R)^-1 (B'XA + S') + Q = 0, checked: `DesignError` when scipy
    fails or the relative residual exceeds `RESIDUAL_TOLERANCE`; `what` names the design in the message."""
    cross = np.zeros_like(b) if s is None else s
    try:
        x = scipy.linalg.solve_discrete_are(a, b, q, r, s=s)
    except (ValueError, np.linalg.LinAlgError) as error:
        raise DesignError(
            f"{what}: the Riccati equation has no stabilising solution here ({error})"
        ) from None
    coupling = a.T @ x @ b + cross
    residual = a.T @ x @ a - x - coupling @ np.linalg.solve(b.T @ x @ b + r, coupling.T) + q
    scale = max(np.linalg.norm(x), np.linalg.norm(q), np.linalg.norm(a.T @ x @ a))
    relative = np.linalg.norm(residual) / scale
    if not np.isfinite(relative) or relative > RESIDUAL_TOLERANCE:
        raise DesignError(
            f"{what}: the Riccati solution misses its equation by {relative:.1e} (relative; at most "
            f"{RESIDUAL_TOLERANCE:g} accepted): the model is too ill-conditioned to design on"
        )
    return x


def lqr(
    phi: np.ndarray, b: np.ndarray, q: np.ndarray, r: np.ndarray, *, n: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(K, P) of the discrete LQR x+ = phi x + b u, cost x'Qx + 2x'Nu + u'Ru; a = -K x. Solved on the
    full model; where that fails (quasi-static modes, above), on the kept modes and lifted back."""
    try:
        riccati = solve_dare(phi, b, q, r, s=n, what="LQR")
    except DesignError:
        truncation = modal_truncation(phi)
        if truncation is None:
            raise
        return lqr_on_kept_modes(phi, b, q, r, n=n, truncation=truncation)
    return scipy.linalg.solve(b.T @ riccati @ b + r, b.T @ riccati @ phi + n.T), riccati


def lqr_on_kept_modes(
    phi: np.ndarray,
    b: np.ndarray,
    q: np.ndarray,
    r: np.ndarray,
    *,
    n: np.ndarray,
    truncation: ModalTruncation,
) -> tuple[np.ndarray, np.ndarray]:
    """`lqr` designed on `truncation`'s modes, K and P lifted back to the full state."""
    basis, projector = truncation.basis, truncation.projector
    reduced_phi, reduced_b = projector @ phi @ basis, projector @ b
    riccati = solve_dare(reduced_phi, reduced_b, basis.T @ q @ basis, r, s=basis.T @ n, what="LQR")
    gain = scipy.linalg.solve(
        reduced_b.T @ riccati @ reduced_b + r, reduced_b.T @ riccati @ reduced_phi + n.T @ basis
    )
    return gain @ projector, projector.T @ riccati @ projector


def kalman_gain(phi: np.ndarray, c: np.ndarray, process: np.ndarray, measurement: np.ndarray) -> np.ndarray:
    """Steady-state measurement-update gain L for x+ = phi x + w (cov process), y = c x + v (cov
    measurement); where the full equation fails (quasi-static modes, above), on the kept modes."""
    try:
        prior = solve_dare(phi.T, c.T, process, measurement, what="Kalman filter")
    except DesignError:
        truncation = modal_truncation(phi)
        if truncation is None:
            raise
        return kalman_gain_on_kept_modes(phi, c, process, measurement, truncation=truncation)
    return prior @ c.T @ np.linalg.inv(c @ prior @ c.T + measurement)


def kalman_gain_on_kept_modes(
    phi: np.ndarray,
    c: np.ndarray,
    process: np.ndarray,
    measurement: np.ndarray,
    *,
    truncation: ModalTruncation,
) -> np.ndarray:
    """`kalman_gain` designed on `truncation`'s modes, which alone the lifted gain corrects."""
    basis, projector = truncation.basis, truncation.projector
    reduced_phi, reduced_c = projector @ phi @ basis, c @ basis
    prior = solve_dare(
        reduced_phi.T, reduced_c.T, projector @ process @ projector.T, measurement, what="Kalman filter"
    )
    return basis @ prior @ reduced_c.T @ np.linalg.inv(reduced_c @ prior @ reduced_c.T + measurement)
