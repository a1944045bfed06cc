"""Classical laws as controller files: LQG on the experiment's own Kalman estimate, MPC over it, or a constant
command (passive dampers), as a one-layer network of zero weights whose bias is the action and whose prior is
the law (`classical_policy`); how each was designed, in a sentence (`design_note`); and the checks a file's
classical law must pass to be read as one (`classical_law`, `mpc_from_file`: a forged MPC model never reaches
the QP solver)."""

from __future__ import annotations

import numpy as np

from rlcontroller.config import ConfigError
from rlcontroller.control.controllers import LQGPrior
from rlcontroller.control.mpc import DEFAULT_HORIZON, STROKE_PRICE, MPCDesign, mpc_design
from rlcontroller.control.mpc_controllers import ObservedMPC
from rlcontroller.control.networks import Actor, Layer, Normalizer
from rlcontroller.control.policy_controller import PolicyController
from rlcontroller.physics.plant import Plant

LAWS = {  # a classical law: its name in tables
    "lqg_ground": "LQG + ground",
    "lqg_ground_model": "LQG + ground model",
    "lqg_wind_model": "LQG + wind model",
    "mpc": "MPC",
    "passive-on": "passive-on",
    "passive-off": "passive-off",
}
PASSIVE_COMMANDS = {"passive-on": 1.0, "passive-off": -1.0}  # a passive law's held action
# MPCDesign's, as mpc_*
MPC_ARRAYS = ("phi", "action_gain", "cost_state", "cost_action", "terminal", "strokes")
MAX_HORIZON = 200  # control steps of a file's MPC (the experiment's kwargs.horizon range)
# an MPC file's model against its design model's, of the largest entry (any CPU's arithmetic)
MODEL_TOLERANCE = 1e-6


def classical_policy(plant: Plant, law: str) -> PolicyController:
    """`law` for `plant` as a controller file holds it, with how it was designed: LQG (the experiment's
    own, on its Kalman estimate, designed on the design model with the experiment's cost), MPC (the same
    estimate and cost over `DEFAULT_HORIZON` steps) or a constant command."""
    m, size = plant.building.n_actuators, plant.layout.size
    if law not in LAWS:
        raise ConfigError(f"law {law!r}: expected one of {', '.join(LAWS)}")
    if law == "mpc" and (plant.semi_active is not None or prior_kind(plant) != "lqg_ground_model"):
        raise ConfigError(
            "law mpc: MPC as a controller file runs on the env's Kalman estimate of LQG + ground model: "
            "actuators or mass drivers under ground motion with sensors.ground_model: true (dampers: rlc "
            "compare lqg --mpc)"
        )
    prior, bias, mpc = None, np.zeros(m, dtype=np.float32), None
    if law in PASSIVE_COMMANDS:
        bias[:] = PASSIVE_COMMANDS[law]
    else:
        if not plant.experiment.sensors.state_estimate or law not in ("mpc", prior_kind(plant)):
            raise ConfigError(
                f"law {law}: this experiment's LQG on its estimate is {prior_kind(plant)}"
                " (needs sensors.state_estimate: true)"
            )
        prior = LQGPrior.design(plant)
        if law == "mpc":
            mpc = ObservedMPC(mpc_design(plant.design, DEFAULT_HORIZON), prior, plant.layout)
    actor = Actor((Layer(np.zeros((m, size), dtype=np.float32), bias, None),), squash=False)
    designed = design_note(plant, law)
    return PolicyController(
        actor, None, prior, LAWS[law], algorithm="classical", law=law, designed=designed, mpc=mpc
    )


def design_note(plant: Plant, law: str) -> str:
    """How the classical `law` for `plant` was designed, in a sentence (a controller file's `designed`)."""
    if law in PASSIVE_COMMANDS:
        return (
            f"every damper held at its {'largest' if law == 'passive-on' else 'least'} command; no training"
        )
    terms = ", ".join(
        f"{t.quantity} ({t.weight:g}, scale {t.scale:g})"
        for t in plant.experiment.reward.terms
        if t.quadratic
    )
    robust = plant.experiment.sensors.input_noise
    recovery = f" and loop transfer recovery's input noise ({robust:g} of the force limits)" if robust else ""
    if law == "mpc":
        return (
            f"MPC over {DEFAULT_HORIZON} control steps ({DEFAULT_HORIZON * plant.control_dt:g} s): the "
            f"experiment's quadratic cost ({terms}) with the Riccati solution as terminal weight, the force "
            f"limits hard, the strokes soft (priced {STROKE_PRICE[0]:g} and {STROKE_PRICE[1]:g} per unit "
            "excess), solved by OSQP every step on the estimate of LQG + ground model's Kalman filter (its "
            f"sensors and their noise{recovery}, on the design model), LQR's clipped action where no plan is "
            "left; no training"
        )
    return (
        f"{LAWS[law]}: the Riccati gains of the experiment's quadratic cost ({terms}) and its Kalman filter "
        f"on its sensors and their noise{recovery}, both on the design model; no training"
    )


def prior_kind(plant: Plant) -> str:
    if plant.wind is not None:
        return "lqg_wind_model"
    return "lqg_ground_model" if plant.experiment.sensors.ground_model else "lqg_ground"


def mpc_from_file(
    section: dict, weights: dict[str, np.ndarray], plant: Plant, prior: LQGPrior
) -> ObservedMPC:
    """A file's MPC law on the env's estimate (`prior` its fallback) once its horizon is a whole number of
    steps within `MAX_HORIZON`, its model the control-step map of the folder's design model (with its ground
    model), its terminal weight symmetric and positive semi-definite and its QP finite: a convex QP on the
    model it claims, so no forged matrix reaches the solver (ValueError otherwise)."""
    horizon = section.get("horizon") if isinstance(section, dict) else None
    if isinstance(horizon, bool) or not isinstance(horizon, int) or not 1 <= horizon <= MAX_HORIZON:
        raise ValueError(
            f"mpc.horizon {horizon!r}: expected a whole number of control steps in [1, {MAX_HORIZON}]"
        )
    step = plant.design.sampled().ground_model
    model = {"mpc_phi": step.phi, "mpc_action_gain": step.force_gain * plant.force_limits}
    for key, expected in model.items():
        difference = np.max(np.abs(weights[key] - expected)) / max(float(np.max(np.abs(expected))), 1e-300)
        if not difference <= MODEL_TOLERANCE:
            raise ValueError(
                f"{key}: not the control-step map of the folder's config.yaml design model (largest "
                f"difference {difference:.3g} of its largest entry, at most {MODEL_TOLERANCE:g} accepted)"
            )
    terminal = weights["mpc_terminal"]
    scale = max(1.0, float(np.max(np.abs(terminal))))
    if (
        not np.allclose(terminal, terminal.T, rtol=0.0, atol=1e-9 * scale)
        or np.min(np.linalg.eigvalsh(0.5 * (terminal + terminal.T))) < -1e-9 * scale
    ):
        raise ValueError("mpc_terminal: expected a symmetric positive semi-definite matrix")
    design = MPCDesign(**{key: weights[f"mpc_{key}"] for key in MPC_ARRAYS}, horizon=horizon)
    with np.errstate(over="ignore", invalid="ignore"):  # a forged cost's overflow is refused just below
        mpc = ObservedMPC(design, prior, plant.layout)  # its QP built here, once; OSQP set up on first use
    problem = mpc.planner.problem
    if not all(
        np.all(np.isfinite(array)) for array in (problem.hessian, problem.linear, problem.constraints)
    ):
        raise ValueError(
            "mpc_cost_state, mpc_cost_action, mpc_terminal: their QP overflows (entries too large)"
        )
    return mpc


def classical_law(
    description: dict, actor: Actor, normalizer: Normalizer | None, prior: LQGPrior | None
) -> str | None:
    """A classical file's law once its data is checked to be exactly that law (ValueError otherwise)."""
    kind = description.get("kind", "learned")
    if kind not in ("learned", "classical"):
        raise ValueError(f"kind {kind!r}: expected learned or classical")
    law = description.get("law") if kind == "classical" else None
    if (law == "mpc") != (description.get("mpc") is not None):
        raise ValueError("mpc: a classical mpc law has an mpc section, nothing else has")
    if kind == "learned":
        return None
    if law not in LAWS:
        raise ValueError(f"law {law!r}: expected one of {', '.join(LAWS)}")
    (layer,) = actor.layers if len(actor.layers) == 1 else (None,)
    if layer is None or np.any(layer.weight != 0.0) or normalizer is not None or actor.squash or actor.odd:
        raise ValueError(f"a classical {law} law has one layer of zero weights and no normalisation")
    expected_bias = PASSIVE_COMMANDS.get(law, 0.0)
    if np.any(layer.bias != expected_bias) or (prior is None) != (law in PASSIVE_COMMANDS):
        raise ValueError(f"a classical {law} law: its bias must be {expected_bias:g} and its prior {law}")
    expected_prior = "lqg_ground_model" if law == "mpc" else law
    if prior is not None and description["prior"] != expected_prior:
        raise ValueError(f"a classical {law} law: its prior is {description['prior']}")
    return law
