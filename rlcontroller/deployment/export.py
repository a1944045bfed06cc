"""A trained controller as one self-contained ONNX graph: raw sensor readings in, forces out.

The graph does, per control step and for a batch of buildings, what the env and `PolicyController`
do in Python: scale the readings and push them into the sensor history, update the Kalman estimate
(designed on the design model, when the observation has one), normalise the observation (if the
run did), run the policy's network, add the LQG prior's action (residual policies), clip, apply
the experiment's supervisor if it has one (`control.supervisor`: trigger level, dissipative forces
only, runtime assurance against the fail-safe twin), and multiply by the force limits.

Inputs (float64, one row per building):
    readings (N, p): the configured sensors, SI units (m/s^2 for accelerations), in config order;
    ground (N, 1): the measured ground acceleration (m/s^2);
    state (N, S): the controller's own state, zeros before the motion starts.
Outputs: force (N, m) in N, one per actuator (config order); next_state (N, S), the next call's state.
The state is the observation of this step (history, scaled estimate, the twin's block, last action), the last
ground reading, with a supervisor's trigger the largest reading it watches so far (m/s^2), with measured
velocities each stroke's (m/s) and whether the fallback took over, and with runtime assurance the twin's
difference state, its running story peaks and whether the devices are handed back. Call once per control step
(`control_dt_s` in the metadata), at the instant the readings are taken; apply the force until the next call.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np

from rlcontroller.config import ConfigError, load_experiment
from rlcontroller.control.estimation import observation_filter
from rlcontroller.control.policy_controller import PolicyController
from rlcontroller.control.policy_file import policy_paths, read_policy
from rlcontroller.control.supervisor import trigger_readings
from rlcontroller.deployment.assurance_graph import assurance_state_size, assured
from rlcontroller.deployment.fallback_graph import fallback_state_size, fallen_back, measured_velocity
from rlcontroller.deployment.graph import DOUBLE, FLOAT, OPSET, Graph, network, squashed
from rlcontroller.deployment.runtime import FAITHFUL, graph_deviation
from rlcontroller.deployment.twin_graph import twin_block
from rlcontroller.files import atomic_write
from rlcontroller.physics.plant import Plant


def controller_graph(plant: Plant, controller: PolicyController, source: str = ""):
    """The ONNX model of `controller` (its normaliser, network and prior) with the observation the
    env builds for `plant`: sensors, history and Kalman estimate."""
    from onnx import helper

    layout, sensors, experiment = plant.layout, plant.sensors, plant.experiment
    p, m = sensors.c.shape[0], plant.building.n_actuators
    block, history = p + 1, experiment.sensors.history
    size = layout.size
    g = Graph()

    scaled = g.node("Div", ["readings", g.constant("reading_scale", layout.reading_scale)], "scaled_readings")
    ground = g.node("Div", ["ground", g.constant("ground_scale", [layout.ground_scale])], "scaled_ground")
    blocks = [g.node("Concat", [scaled, ground], "newest_block", axis=1)]
    if history > 1:
        blocks.append(g.columns("state", 0, (history - 1) * block, "older_blocks"))
    held = g.columns("state", layout.action.start, layout.action.stop, "held_action")
    actions = g.columns("state", layout.actions.start, layout.actions.stop, "last_actions")
    parts = [g.node("Concat", blocks, "history", axis=1) if len(blocks) > 1 else blocks[0]]
    if layout.estimate.stop > layout.estimate.start:
        parts.append(_kalman(g, plant, held))
    if layout.twin.stop > layout.twin.start:
        parts.append(twin_block(g, plant, held, parts[-1]))
    observation = g.node("Concat", [*parts, actions], "observation", axis=1)
    # the policy reads the observation as the env stores it (float32), as `PolicyController` does in Python
    stored = g.node(
        "Cast", [g.node("Cast", [observation], "observation_f32", to=FLOAT)], "stored_observation", to=DOUBLE
    )

    network_input = stored
    normalizer = controller.normalizer
    if normalizer is not None:
        centred = g.node("Sub", [observation, g.constant("observation_mean", normalizer.mean)], "centred")
        spread = np.sqrt(normalizer.var + normalizer.epsilon)
        divided = g.node("Div", [centred, g.constant("observation_spread", spread)], "divided")
        network_input = g.clip(divided, -normalizer.clip, normalizer.clip, output="normalised")
    x = g.node("Cast", [network_input], "network_input", to=FLOAT)
    x = network(g, controller.actor, x, "")
    if controller.actor.odd:  # (g(o) - g(-o)) / 2
        mirrored = network(
            g, controller.actor, g.node("Neg", ["network_input"], "mirrored_input"), "mirrored_"
        )
        difference = g.node("Sub", [x, mirrored], "odd_difference")
        x = g.node("Mul", [difference, g.constant("one_half", 0.5, np.float32)], "odd_action")
    x = squashed(g, controller.actor, x)
    action = g.clip(g.node("Cast", [x], "network_action", to=DOUBLE), -1.0, 1.0, output="policy_action")
    if controller.prior is not None:
        estimate = g.columns(stored, layout.estimate.start, layout.estimate.stop, "prior_estimate")
        feedback = g.affine(estimate, controller.prior.feedback, "prior_feedback")
        feedforward = g.node(
            "Mul", [ground, g.constant("prior_gain", controller.prior.feedforward[None])], "prior_ff"
        )
        prior = g.node("Neg", [g.node("Add", [feedback, feedforward], "prior_sum")], "prior_action")
        action = g.clip(g.node("Add", [action, prior], "residual_sum"), -1.0, 1.0, output="action")
    supervisor = experiment.supervisor
    trigger = supervisor is not None and supervisor.trigger is not None
    measured, assurance = [], []
    if supervisor is not None:
        action, peak, measured = _supervised(g, plant, stored, action, size + 1 + trigger)
        if supervisor.assurance is not None:
            action, assurance = assured(
                g, plant, stored, action, start=size + 1 + trigger + fallback_state_size(plant)
            )
    force = g.node("Mul", [action, g.constant("force_limits", plant.force_limits[None])], "force")
    observation_before_action = g.columns(observation, 0, layout.action.start, "observation_head")
    kept = [observation_before_action, action]
    if layout.actions.stop > layout.action.stop:  # older actions shift by one
        kept.append(g.columns(observation, layout.action.start, layout.actions.stop - m, "older_actions"))
    g.node(
        "Concat", [*kept, "ground", *([peak] if trigger else []), *measured, *assurance], "next_state", axis=1
    )

    state_size = size + 1 + trigger + fallback_state_size(plant) + assurance_state_size(plant)
    graph = helper.make_graph(
        g.nodes,
        "rlcontroller",
        [
            helper.make_tensor_value_info("readings", DOUBLE, ["batch", p]),
            helper.make_tensor_value_info("ground", DOUBLE, ["batch", 1]),
            helper.make_tensor_value_info("state", DOUBLE, ["batch", state_size]),
        ],
        [
            helper.make_tensor_value_info(force, DOUBLE, ["batch", m]),
            helper.make_tensor_value_info("next_state", DOUBLE, ["batch", state_size]),
        ],
        initializer=g.constants,
    )
    model = helper.make_model(
        graph, opset_imports=[helper.make_opsetid("", OPSET)], producer_name="rlcontroller"
    )
    model.ir_version = 8
    model.doc_string = __doc__
    metadata = {
        "control_dt_s": repr(plant.control_dt),
        "readings": "; ".join(_reading_names(plant)),
        "actuator_stories": ", ".join(experiment.command_labels()),
        "force_limits_N": ", ".join(repr(float(f)) for f in plant.force_limits),
        "outputs": "force (N) per actuator and active mass driver"
        + (
            "; per semi-active damper its command in [-1, 1] (-1: least voltage or damping, +1: most)"
            if plant.building.dampers
            else ""
        ),
        "state_size": str(state_size),
        "supervisor": _supervisor_text(plant),
        "source": source,
    }
    helper.set_model_props(model, metadata)
    return model


def _supervised(
    g: Graph, plant: Plant, stored: str, action: str, column: int
) -> tuple[str, str | None, list[str]]:
    """The supervisor's action, the new peak ground reading (None without a trigger) and the next state's
    measured stroke velocities and fallback latch (state columns from `column` on), computed as
    `control.supervisor` does from the observation as the env stores it (`stored`: float32)."""
    layout, supervisor, n = plant.layout, plant.experiment.supervisor, plant.building.n_dofs
    measured = measured_velocity(g, plant, stored, column) if supervisor.measured else None
    if supervisor.dissipative == "measured":
        stroke = measured
    elif supervisor.dissipative:
        velocity = g.columns(
            stored, layout.estimate.start + n, layout.estimate.start + 2 * n, "velocity_estimate"
        )
        stroke = g.node(
            "MatMul",
            [velocity, g.constant("actuator_matrix", plant.building.actuator_matrix)],
            "stroke_velocity",
        )
    if supervisor.dissipative:
        feeds = g.node(
            "Greater",
            [g.node("Mul", [action, stroke], "stroke_power"), g.constant("zero", 0.0)],
            "feeds_energy",
        )
        # m/s measured, scaled as the estimate is, like `control.supervisor`
        if supervisor.fade_velocity > 0.0:
            fade = supervisor.fade_velocity / (1.0 if measured is stroke else layout.estimate_scale[n])
            speed = g.node(
                "Div", [g.node("Abs", [stroke], "stroke_speed"), g.constant("fade", fade)], "fade_ratio"
            )
            kept = g.clip(
                g.node("Sub", [g.constant("one", 1.0), speed], "fade_left"), 0.0, 1.0, output="fade_factor"
            )
            blocked = g.node("Mul", [action, kept], "faded_action")
        else:
            blocked = g.constant("no_action", 0.0)
        action = g.node("Where", [feeds, blocked, action], "dissipative_action")
    kept = [] if measured is None else [measured]
    if supervisor.fallback is not None:
        m = plant.building.n_actuators
        action, latched = fallen_back(g, plant, stored, action, velocity=measured, start=column + m)
        kept.append(latched)
    if supervisor.trigger is None:
        return action, None, kept
    indices, scales = trigger_readings(plant)
    readings = g.node(
        "Gather", [stored, g.constant("trigger_indices", indices, np.int64)], "trigger_stored", axis=1
    )
    magnitude = g.node(
        "Abs",
        [g.node("Mul", [readings, g.constant("trigger_scales", scales)], "trigger_readings")],
        "trigger_magnitude",
    )
    ground = g.node("ReduceMax", [magnitude], "ground_magnitude", axes=[1], keepdims=1)
    previous_peak = g.columns("state", layout.size + 1, layout.size + 2, "previous_peak_ground")
    peak = g.node("Max", [previous_peak, ground], "peak_ground")
    start, full = supervisor.trigger
    if full == start:
        on = g.node("GreaterOrEqual", [peak, g.constant("trigger_full", full)], "on")
        gain = g.node("Cast", [on], "gain", to=DOUBLE)
    else:
        rise = g.node("Sub", [peak, g.constant("trigger_start", start)], "above_start")
        ramp = g.node("Div", [rise, g.constant("trigger_span", full - start)], "ramp")
        gain = g.clip(ramp, 0.0, 1.0, output="gain")
    return g.node("Mul", [action, gain], "supervised_action"), peak, kept


def _supervisor_text(plant: Plant) -> str:
    if (supervisor := plant.experiment.supervisor) is None:
        return "none"
    parts = []
    if supervisor.trigger is not None:
        # what the trigger reads, as it reads it
        floors = list(trigger_readings(plant)[0]) != [plant.layout.ground]
        watched = "floor acceleration readings" if floors else "ground reading"
        parts.append(
            f"trigger {supervisor.trigger[0]:g}-{supervisor.trigger[1]:g} m/s^2 on the peak {watched}"
        )
    if (assurance := supervisor.assurance) is not None:
        parts.append(
            "runtime assurance against the fail-safe twin "
            f"(release {assurance.release:g}, engage {assurance.engage:g})"
        )
    velocity = "measured " if supervisor.dissipative == "measured" else ""
    if supervisor.dissipative and (fade := supervisor.fade_velocity) > 0.0:
        parts.append(f"forces feeding energy in faded out by {fade:g} m/s of {velocity}stroke velocity")
    elif supervisor.dissipative:
        parts.append("dissipative forces only" + (" (measured stroke velocity)" if velocity else ""))
    if supervisor.fallback is not None:
        parts.append(
            f"past {supervisor.fallback.drift:g} m of estimated story drift, dampers on measured stroke "
            f"velocity ({', '.join(f'{c:g}' for c in supervisor.fallback.damping)} N s/m)"
        )
    return "; ".join(parts) or "none"


def _kalman(g: Graph, plant: Plant, held: str) -> str:
    """The scaled estimate after this step's readings: the env's own filter (Kalman or integration), in the
    folded form the env applies (`KalmanFilter.update_matrices`: prediction and correction in one affine map),
    so that the graph and Python round alike."""
    layout, kalman = plant.layout, observation_filter(plant)
    free, action_gain, measured_gain, ground_gain = kalman.update_matrices
    previous = g.columns("state", layout.estimate.start, layout.estimate.stop, "previous_scaled_estimate")
    estimate = g.node(
        "Mul", [previous, g.constant("estimate_scale", layout.estimate_scale)], "previous_estimate"
    )
    measured = (
        g.node("Concat", ["readings", "ground"], "measured", axis=1) if kalman.measures_ground else "readings"
    )
    new = g.node(
        "Add",
        [
            g.node("MatMul", [estimate, g.constant("filter_free", free)], "free_response"),
            g.node("MatMul", [held, g.constant("filter_action", action_gain)], "action_response"),
        ],
        "predicted_free",
    )
    new = g.node(
        "Add",
        [new, g.node("MatMul", [measured, g.constant("filter_measured", measured_gain)], "correction")],
        "corrected",
    )
    if kalman.known_ground:
        previous_ground = g.columns("state", layout.size, layout.size + 1, "previous_ground")
        ground_response = g.affine(previous_ground, ground_gain[:, None], "ground_response")
        new = g.node("Add", [new, ground_response], "estimate")
    return g.node("Div", [new, "estimate_scale"], "scaled_estimate")


def _reading_names(plant: Plant) -> list[str]:
    units = {"absolute_acceleration": "m/s^2", "displacement": "m", "velocity": "m/s", "drift": "m"}
    names = []
    for measurement in plant.experiment.sensors.measurements:
        floors = measurement.floors or list(range(1, plant.building.n_floors + 1))
        unit = units.get(measurement.quantity, "SI")
        names += [f"{measurement.quantity} floor {floor} ({unit})" for floor in floors]
    return names


def export_onnx(folder: Path, model: str, out: Path) -> Path:
    """Write the saved policy `model` (best or final) of a run or model folder as ONNX at `out`. The
    metadata names its source by folder name and the SHA-256 of its weights, never a local path."""
    import onnx

    plant = Plant(load_experiment(folder / "config.yaml", self_contained=True))
    controller = read_policy(folder, model, plant)
    if controller.mpc is not None:
        raise ConfigError(
            f"{folder}: an MPC controller solves a quadratic program every step, which is not an ONNX graph "
            "(its learned imitation exports: studies/mpc)"
        )
    _, weights = policy_paths(folder, model)
    digest = hashlib.sha256(weights.read_bytes()).hexdigest()
    graph = controller_graph(
        plant, controller, source=f"{folder.resolve().name}/{weights.name} (sha256 {digest})"
    )
    onnx.checker.check_model(graph, full_check=True)
    serialized = graph.SerializeToString()
    deviation, _ = graph_deviation(plant, controller, serialized)
    if not deviation <= FAITHFUL:
        raise ConfigError(
            f"{folder}: its ONNX graph's forces differ from the Python controller's by {deviation:.3g} of "
            f"their peak on a generated load (at most {FAITHFUL:g} accepted): this controller is not "
            "exported"
        )
    atomic_write(out, serialized)
    return out
