"""An exported controller run by onnxruntime, and how faithful its graph is to the Python controller it
came from."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rlcontroller.control.policy_controller import PolicyController
from rlcontroller.deployment.assurance_graph import assurance_state_size, assurance_values
from rlcontroller.physics.plant import Plant

FAITHFUL = 1e-3  # an exported graph's largest force difference from Python's, of the peak force
CHECKED_STEPS = 400  # control steps of the generated load the graph is checked on at export


def graph_deviation(
    plant: Plant, controller: PolicyController, graph: bytes, *, seed: int = 0, steps: int = CHECKED_STEPS
) -> tuple[float, float]:
    """The largest difference between the commands (N) of the serialised `graph` and those of the Python
    controller, over the first `steps` control steps of a load drawn from the experiment's own generator, as a
    fraction of the peak command (0 when the controller never acts), and that peak. The Python controller
    drives the building in the env; the graph reads the same sensors and is told, after each step, the command
    the building received (its held action, as a deployed controller's actuators would report it). Step by
    step, not two closed loops side by side: an LQG controller may be unstable on its own, and a controller
    that saturates may be chaotic in closed loop, so two faithful copies of it drift apart from the last
    bit."""
    from rlcontroller.learning.env import BuildingEnv
    from rlcontroller.physics.motions.loads import generate

    load = generate(plant.experiment.excitation.generator, np.random.default_rng(seed), plant.building)
    env, layout, exported = BuildingEnv(plant), plant.layout, OnnxController(graph)
    assurance = assurance_state_size(plant)
    controller.reset()
    observation, info = env.reset(seed=seed, options={"motion": load})
    python, onnx_commands = [], []
    for _ in range(min(info["steps"], steps)):
        readings = observation[layout.readings].astype(float) * layout.reading_scale
        ground = np.array([[float(observation[layout.ground]) * layout.ground_scale]])
        onnx_commands.append(exported.step(readings[None], ground)[0])
        observation, *_ = env.step(controller.act(observation))
        python.append(env.command)
        exported.state[0, layout.action] = env.command / plant.force_limits  # the held action, as applied
        if assurance:  # and the twin's difference it drove (a last-bit flip of the switch is not a fault)
            exported.state[0, -assurance:] = assurance_values(env.supervisor)
    peak = float(np.max(np.abs(python)))
    deviation = float(np.max(np.abs(np.subtract(onnx_commands, python))))
    return (deviation / peak if peak > 0.0 else 0.0), peak


class OnnxController:
    """An exported controller run by onnxruntime, one control step per call, for `batch` buildings."""

    def __init__(self, path: Path | bytes, batch: int = 1, threads: int = 1) -> None:
        import onnxruntime

        options = onnxruntime.SessionOptions()
        options.intra_op_num_threads = threads
        options.inter_op_num_threads = 1
        model = path if isinstance(path, bytes) else str(path)
        self.session = onnxruntime.InferenceSession(model, options, providers=["CPUExecutionProvider"])
        self.metadata = self.session.get_modelmeta().custom_metadata_map
        self.state = np.zeros((batch, int(self.metadata["state_size"])))

    def reset(self) -> None:
        self.state[:] = 0.0

    def step(self, readings: np.ndarray, ground: np.ndarray) -> np.ndarray:
        """Forces (N) for the readings (SI, (batch, p)) and ground accelerations (m/s^2, (batch, 1))."""
        force, self.state = self.session.run(
            None, {"readings": readings, "ground": ground, "state": self.state}
        )
        return force
