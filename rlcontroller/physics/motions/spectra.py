"""Elastic response spectra of ground motions: the pseudo-acceleration omega^2 max|u| of a damped oscillator
u'' + 2 zeta omega u' + omega^2 u = -a_g, stepped exactly for a ground acceleration linear between samples."""

from __future__ import annotations

import numpy as np

from rlcontroller.physics.motions.excitation import Load


def pseudo_acceleration(motion: Load, periods: np.ndarray, damping: float = 0.05) -> np.ndarray:
    """Sa (m/s^2) of `motion` at `periods` (s) for the damping ratio `damping`."""
    import scipy.signal  # here, not at import: most commands compute no spectrum

    values = []
    for period in np.asarray(periods, dtype=float):
        omega = 2.0 * np.pi / period
        oscillator = ([-1.0], [1.0, 2.0 * damping * omega, omega**2])  # u / a_g
        numerator, denominator, _ = scipy.signal.cont2discrete(oscillator, motion.dt, method="foh")
        displacement = scipy.signal.lfilter(numerator.ravel(), denominator, motion.acceleration)
        values.append(omega**2 * float(np.max(np.abs(displacement))))
    return np.array(values)


def spectral_shape(motion: Load, periods: np.ndarray, damping: float = 0.02) -> np.ndarray:
    """Sa / PGA at `periods` (s): the motion's spectral shape, the same at any scale."""
    return pseudo_acceleration(motion, periods, damping) / motion.pga
