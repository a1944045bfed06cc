"""Study: how much can the roof mass driver cut the drift without ever being worse than its tuned mass?

Usage: python studies/devices/mass_driver_dominance.py [--check]

The safety check asks that no motion drift more than with the driver switched off (the tuned mass it then
is). For a linear loop a sufficient condition is dominance frequency by frequency: at every frequency and
story, the drift per unit ground acceleration is no larger than the tuned mass's. This study measures what
that leaves, on `rlc`'s own matrices of the experiment `five_story_amd` (its exact step map, sensors and
LQG + ground model's Kalman filter):

1. the closed loops' frequency responses, checked against steady sines simulated by `rlc`'s plant;
2. LQG + ground model's ratio to the tuned mass, frequency by frequency (where it amplifies);
3. the largest cut a linear controller can make under dominance: u = T(z) a_g on the measured ground, with
   T a sum of 40 Laguerre filters (pole 0.96) and a direct term, the spectrum-weighted drift minimised by a
   linear programme (scipy's HiGHS; |.| as a circumscribed 16-gon) under |drift| <= the tuned mass's at 400
   frequencies from 0.05 to 24.8 Hz. With a stable plant every nominal closed loop is such a T (Youla):
   feedback adds robustness, not nominal reach. The grid and the polygon relax the constraint, so the figure
   is optimistic for the family; 80 filters (pole 0.98) give about the same (0.981 against 0.987);
4. a gain on the experiment's Kalman estimate (what a controller file holds) designed for dominance: the
   spectrum-weighted drift plus a growing penalty on any excess over the tuned mass (L-BFGS), and with
   `--check` the safety check's verdict on it (about 3 min).

The weighting spectrum is Kanai-Tajimi, medium soil (omega_g 12 rad/s, zeta_g 0.6).
"""

from __future__ import annotations

import sys

import numpy as np
import scipy.optimize
import scipy.sparse as sparse

from rlcontroller.assets import CONFIGS
from rlcontroller.config import load_experiment, load_safety_check
from rlcontroller.config.scenarios import safety_standard
from rlcontroller.control.controllers import LQGController, Uncontrolled
from rlcontroller.control.lqg import LQGDesign, design_lqg_ground_model
from rlcontroller.evaluation.safety import safety_check
from rlcontroller.physics.motions.excitation import Load
from rlcontroller.physics.motions.generators import GroundModel
from rlcontroller.physics.plant import Plant
from rlcontroller.simulation.rollout import batch_rollout

FREQUENCIES = np.geomspace(0.05, 24.8, 400)  # Hz
LAGUERRE_POLE, LAGUERRE_COUNT, POLYGON = 0.96, 40, 16
MEDIUM_SOIL = GroundModel(frequency=12.0, damping=0.6)  # the weighting spectrum, Kanai-Tajimi


def responses(plant: Plant, design: LQGDesign, frequency: np.ndarray) -> dict[str, np.ndarray]:
    """Open-loop frequency responses at `frequency` (Hz), per unit ground acceleration (w) and per unit action
    (u): the story drifts (drift_w, drift_u; m per m/s^2 and per action) and the Kalman estimate (estimate_w,
    estimate_u), with the env's timing: action k held over [t_k, t_k+1], the readings at t_k feel action
    k-1."""
    step, kalman = plant.sampled(1).step, design.filter
    phi, force = step.phi, step.force_gain[:, 0] * plant.building.force_limits[0]
    free, held, measured, _ = kalman.update_matrices
    c, d = plant.sensors.c, plant.sensors.d[:, 0] * plant.building.force_limits[0]
    drift = plant.outputs("drift")[0]
    n_readings = c.shape[0]
    out = {key: [] for key in ("drift_w", "drift_u", "estimate_w", "estimate_u")}
    for z in np.exp(2j * np.pi * frequency * plant.control_dt):
        state = np.linalg.inv(z * np.eye(phi.shape[0]) - phi)
        state_w, state_u = state @ (step.ground_gain[:, 0] + step.ground_gain[:, 1] * z), state @ force
        estimate = np.linalg.inv(np.eye(free.shape[0]) - free.T / z)
        out["drift_w"].append(drift @ state_w)
        out["drift_u"].append(drift @ state_u)
        out["estimate_w"].append(estimate @ (measured[:n_readings].T @ (c @ state_w) + measured[n_readings]))
        out["estimate_u"].append(estimate @ (held[0] / z + measured[:n_readings].T @ (c @ state_u + d / z)))
    return {key: np.array(value) for key, value in out.items()}


def closed_drift(r: dict[str, np.ndarray], gain: np.ndarray) -> np.ndarray:
    """Drift per unit ground acceleration (frequencies, stories) under u = -gain @ estimate (unclipped)."""
    action = -(r["estimate_w"] @ gain) / (1 + r["estimate_u"] @ gain)
    return r["drift_w"] + r["drift_u"] * action[:, None]


def simulated_ratio(
    plant: Plant, controller: LQGController, frequency: float, amplitude: float = 0.2
) -> float:
    """Peak drift (max over stories) of the last 20 s of a 60 s sine, controlled over driver off."""
    time = np.arange(0.0, 60.0 + plant.control_dt / 2, plant.control_dt)
    sine = Load(f"sine {frequency:g} Hz", plant.control_dt, amplitude * np.sin(2 * np.pi * frequency * time))
    off, on = batch_rollout(plant, [sine], [Uncontrolled(plant.building.n_actuators), controller], seeds=[0])
    tail = time >= 40.0
    return float(np.max(np.abs(on[0][0].drift[tail])) / np.max(np.abs(off[0][0].drift[tail])))


def feedforward_bound(r: dict[str, np.ndarray], frequency: np.ndarray, dt: float) -> tuple[float, np.ndarray]:
    """The spectrum-weighted drift (to the tuned mass's) of the best u = T(z) a_g under dominance, and T."""
    z = np.exp(2j * np.pi * frequency * dt)
    a = LAGUERRE_POLE
    basis = np.array(
        [np.ones_like(z)]
        + [np.sqrt(1 - a * a) / (z - a) * ((1 - a * z) / (z - a)) ** j for j in range(LAGUERRE_COUNT)]
    ).T
    peak = np.abs(r["drift_w"]).max(axis=0)
    drift_w, drift_u = r["drift_w"] / peak, r["drift_u"] / peak
    reference = np.abs(drift_w)
    nf, ns, nq = drift_w.shape[0], drift_w.shape[1], basis.shape[1]
    rows, rhs = [], []
    for angle in 2 * np.pi * np.arange(POLYGON) / POLYGON:  # Re(e^-i angle drift) <= t: |drift| <= t, 16-gon
        turn = np.exp(-1j * angle)
        for story in range(ns):
            bound = sparse.coo_matrix(
                (-np.ones(nf), (np.arange(nf), np.arange(nf) * ns + story)), shape=(nf, nf * ns)
            )
            rows.append(
                sparse.hstack([sparse.coo_matrix(((turn * drift_u[:, story])[:, None] * basis).real), bound])
            )
            rhs.append(-(turn * drift_w[:, story]).real)
    weight = MEDIUM_SOIL.spectrum(frequency) * np.gradient(frequency)
    cost = np.concatenate([np.zeros(nq), (weight[:, None] * reference).ravel()])
    limits = [(None, None)] * nq + [(0.0, value + 1e-7) for value in reference.ravel()]
    result = scipy.optimize.linprog(cost, sparse.vstack(rows).tocsr(), np.concatenate(rhs), bounds=limits)
    transfer = basis @ result.x[:nq]
    drift = drift_w + drift_u * transfer[:, None]
    return weighted(drift, drift_w, weight), transfer


def weighted(drift: np.ndarray, reference: np.ndarray, weight: np.ndarray) -> float:
    """Spectrum-weighted mean square drift, to the reference's (all stories)."""
    return float(
        np.sum(np.abs(drift) ** 2 * weight[:, None]) / np.sum(np.abs(reference) ** 2 * weight[:, None])
    )


def dominant_gain(
    r: dict[str, np.ndarray], frequency: np.ndarray, start: np.ndarray, slack: float
) -> np.ndarray:
    """A gain on the Kalman estimate: spectrum-weighted drift plus mu times the squared excess over the tuned
    mass plus `slack` of each story's peak (to that peak), mu raised from 1e2 to 1e6."""
    reference = np.abs(r["drift_w"])
    peak, weight = reference.max(axis=0), MEDIUM_SOIL.spectrum(frequency) * np.gradient(frequency)

    def objective(gain: np.ndarray, mu: float) -> float:
        drift = np.abs(closed_drift(r, gain))
        excess = np.maximum(drift - reference - slack * peak, 0.0) / peak
        return weighted(drift, r["drift_w"], weight) + mu * float(np.sum(excess**2))

    gain = start
    for mu in (1e2, 1e3, 1e4, 1e5, 1e6):
        gain = scipy.optimize.minimize(objective, gain, args=(mu,), method="L-BFGS-B").x
    return gain


def main() -> None:
    plant = Plant(load_experiment(CONFIGS / "experiments" / "five_story_amd.yaml"))
    design = design_lqg_ground_model(plant.design)
    r = responses(plant, design, FREQUENCIES)
    weight = MEDIUM_SOIL.spectrum(FREQUENCIES) * np.gradient(FREQUENCIES)
    lqg = np.abs(closed_drift(r, design.feedback[0])) / np.abs(r["drift_w"])

    print("1. frequency responses against steady sines of rlc's plant (0.2 m/s^2, LQG + ground model):")
    controller = LQGController(design, plant)
    for f in (0.4, 0.69, 1.0):
        k = np.argmin(np.abs(FREQUENCIES - f))
        predicted = np.max(np.abs(closed_drift(r, design.feedback[0])[k])) / np.max(np.abs(r["drift_w"][k]))
        simulated = simulated_ratio(plant, controller, FREQUENCIES[k])
        print(f"   {FREQUENCIES[k]:.3f} Hz: predicted {predicted:.3f}, simulated {simulated:.3f}")

    print("2. LQG + ground model, drift over the driver off's, stories 1-5:")
    for f in (0.2, 0.3, 0.4, 0.5, 0.69, 0.9, 1.0, 1.2, 2.0, 3.0):
        k = np.argmin(np.abs(FREQUENCIES - f))
        print(f"   {FREQUENCIES[k]:5.2f} Hz: " + " ".join(f"{v:.2f}" for v in lqg[k]))
    print(
        "   spectrum-weighted drift "
        f"{weighted(closed_drift(r, design.feedback[0]), r['drift_w'], weight):.3f}"
        f" of the driver off's; worst ratio below 5 Hz {lqg[FREQUENCIES < 5.0].max():.2f}"
    )

    bound, transfer = feedforward_bound(r, FREQUENCIES, plant.control_dt)
    print(
        f"3. any linear controller under dominance (feedforward bound): spectrum-weighted drift {bound:.3f}"
        f" of the driver off's (|T| up to {np.abs(transfer).max():.0f} action per m/s^2)"
    )

    standard = load_safety_check(safety_standard(plant.experiment))
    for slack in (0.0, 0.005):
        gain = dominant_gain(r, FREQUENCIES, 0.1 * design.feedback[0], slack)
        drift = closed_drift(r, gain)
        excess = (np.abs(drift) - np.abs(r["drift_w"])) / np.abs(r["drift_w"]).max(axis=0)
        share = weighted(drift, r["drift_w"], weight)
        print(
            f"4. a gain on the Kalman estimate designed for dominance, slack {slack:g} of a story's peak: "
            f"spectrum-weighted drift {share:.3f}, largest excess {excess.max():.4f}"
        )
        if "--check" in sys.argv[1:]:
            name = f"dominant gain, slack {slack:g}"
            shaped = LQGController(
                LQGDesign(gain[None, :], design.feedforward, design.filter), plant, name=name
            )
            print("\n".join(safety_check(plant, shaped, standard, scenarios=[]).lines()), flush=True)


if __name__ == "__main__":
    main()
