"""The paper's evaluation criteria J1-J4, per story (or actuator), for one record.

C = controlled, UC = uncontrolled response to the same record:
    J1 = max|drift_C| / max|drift_UC|                       per story
    J2 = max|a_C| / max|a_UC|  (absolute acceleration)      per floor
    J3 = E(u) / E(V_b,UC),  E(x) = integral of x^2 dt       per actuator
    J4 = max|V_C| / max|V_UC|  (story shear)                per story
Forces are held over each control step, so their energy sums u_k^2 dt exactly; the base-shear
energy uses the same rectangle rule on its samples.
"""

from __future__ import annotations

import numpy as np

from rlcontroller.physics.motions.excitation import STANDARD_GRAVITY
from rlcontroller.physics.response import Response

METRICS = ("J1", "J2", "J3", "J4")
# per story, yielding plants
YIELDING_METRICS = ("ductility", "residual_drift_m", "hysteretic_energy_J", "collapsed")
WIND_METRICS = (  # under floor loads
    "rms_acceleration",
    "rms_acceleration_top",
    "rms_top_displacement",
    "peak_acceleration_mg",
    "peak_acceleration_top_mg",
)
DEVICE_METRICS = (  # with devices: per mass device, then per commanded device
    "stroke_m",
    "stroke_rms_m",
    "damper_energy_J",
    "power_peak_W",
    "power_rms_W",
    "dissipated_energy_J",
    "stroke_over_limit",
    "contacts",
    "contact_force_N",
)
RESIDUAL_WINDOW_S = 5.0  # the residual drift is the mean drift over the tail's last seconds


def peak(history: np.ndarray) -> np.ndarray:
    """Largest absolute value over time (axis 0), per component."""
    return np.max(np.abs(history), axis=0)


def ratio_to_reference(controlled: Response, reference: Response) -> float:
    """The safety check's measure of one motion: the peak drift (over stories and time) against the
    reference's, or the mean over stories of each story's peak drift against the reference's (J1 against
    the reference), the larger. Above 1: worse than the reference on this motion."""
    controlled_peak, reference_peak = peak(controlled.drift), peak(reference.drift)
    overall = float(np.max(controlled_peak) / np.max(reference_peak))
    return max(overall, float(np.mean(controlled_peak / reference_peak)))


def energy(history: np.ndarray, dt: float) -> np.ndarray:
    """Rectangle-rule integral of x^2 dt over samples 1..K (the samples of each held step)."""
    return np.sum(history[1:] ** 2, axis=0) * dt


def j_metrics(controlled: Response, uncontrolled: Response) -> dict[str, np.ndarray]:
    """J1 (per story), J2 (per floor), J3 (per actuator), J4 (per story) of one record."""
    dt = float(controlled.time[1] - controlled.time[0])
    return {
        "J1": peak(controlled.drift) / peak(uncontrolled.drift),
        "J2": peak(controlled.absolute_acceleration) / peak(uncontrolled.absolute_acceleration),
        "J3": energy(controlled.force, dt) / energy(uncontrolled.base_shear, dt),
        "J4": peak(controlled.story_shear) / peak(uncontrolled.story_shear),
    }


def wind_metrics(controlled: Response, uncontrolled: Response) -> dict[str, np.ndarray]:
    """Occupant comfort under wind: per floor, RMS absolute acceleration (C / UC) and its peak in
    milli-g (the unit comfort criteria use); the same for the top floor alone, whose occupants feel
    the most, and its RMS displacement (C / UC). The RMS is about the record's mean (the mean wind's
    static part removed)."""

    def rms(history: np.ndarray) -> np.ndarray:
        return np.std(history[1:], axis=0)

    ratio = rms(controlled.absolute_acceleration) / rms(uncontrolled.absolute_acceleration)
    peak_mg = peak(controlled.absolute_acceleration) / STANDARD_GRAVITY * 1e3
    top = controlled.displacement[:, -1:], uncontrolled.displacement[:, -1:]
    return {
        "rms_acceleration": ratio,
        "rms_acceleration_top": ratio[-1:],
        "rms_top_displacement": rms(top[0]) / rms(top[1]),
        "peak_acceleration_mg": peak_mg,
        "peak_acceleration_top_mg": peak_mg[-1:],
    }


def device_metrics(
    result: Response, *, damping: np.ndarray, stroke_limits: np.ndarray
) -> dict[str, np.ndarray]:
    """Per mass device (dashpot coefficients `damping`, N*s/m; `stroke_limits`, m): peak and RMS stroke (m)
    and the energy its dashpot dissipated (J); per commanded device: peak and RMS power (W), force times the
    velocity across it, at the control steps (the force held over the step ending there), and the energy it
    took out of the building (J; negative: it put energy in)."""
    dt = float(result.time[1] - result.time[0])
    duration = dt * (result.time.size - 1)
    power = result.force * result.device_velocity
    return {
        "stroke_m": peak(result.stroke),
        "stroke_rms_m": np.sqrt(energy(result.stroke, dt) / duration),
        "damper_energy_J": damping * energy(result.stroke_velocity, dt),
        "power_peak_W": peak(power),
        "power_rms_W": np.sqrt(energy(power, dt) / duration),
        "dissipated_energy_J": -np.sum(power[1:], axis=0) * dt,
    } | stop_metrics(result, stroke_limits)


def stop_metrics(result: Response, stroke_limits: np.ndarray) -> dict[str, np.ndarray]:
    """Per mass device meeting end-stops (`physics.end_stops`) at `stroke_limits` (m; nan: a free mass): its
    peak stroke over its limit, the contacts with its stops and the largest force one put on it (N); none
    without stops."""
    if result.stop_contacts is None:
        return {}
    return {
        "stroke_over_limit": peak(result.stroke) / stroke_limits,
        "contacts": np.sum(result.stop_contacts, axis=0),
        "contact_force_N": np.max(result.stop_force, axis=0),
    }


def yielding_metrics(
    result: Response, yield_drift: np.ndarray, collapse_drift: np.ndarray | None = None
) -> dict[str, np.ndarray]:
    """Per story of a yielding plant, for a response that ends with the settling tail:
    ductility demand max|d| / d_y, residual drift |mean d| over the last RESIDUAL_WINDOW_S (m;
    the mean over several periods removes the free vibration left), and the hysteretic energy
    sum of the integral of (1 - a) k d_y z dd (J, trapezoid rule on the control steps); with finite
    `collapse_drift` (m) also whether the story collapsed (1) or not (0)."""
    force = result.hysteretic_force
    metrics = {
        "ductility": peak(result.drift) / yield_drift,
        **residual_drift(result),
        "hysteretic_energy_J": np.sum(0.5 * (force[1:] + force[:-1]) * np.diff(result.drift, axis=0), axis=0),
    }
    if collapse_drift is not None and np.all(np.isfinite(collapse_drift)):
        metrics["collapsed"] = (peak(result.drift) >= collapse_drift).astype(float)
    return metrics


def residual_drift(result: Response) -> dict[str, np.ndarray]:
    """Per story, for a response that ends with the settling tail: |mean drift| over the last
    RESIDUAL_WINDOW_S (m; the mean over several periods removes the free vibration left)."""
    dt = float(result.time[1] - result.time[0])
    last = max(1, round(RESIDUAL_WINDOW_S / dt))
    return {"residual_drift_m": np.abs(np.mean(result.drift[-last:], axis=0))}
