"""An FE model stepped one control step at a time (`physics.protocol.Integrator`).

`rlc` owns the time loop: each control step the ground acceleration enters as a uniform excitation (its
samples over the step, linear between them), the actuator forces as nodal loads held over the step (on the
floors the design building's actuator matrix puts them), and the model's own analysis advances Newmark
average-acceleration steps of at most `analysis_dt` (s), on every ground sample, with the model's algorithm
(Newton-Raphson by default), falling back to Newton, modified Newton on the initial tangent, Newton with line
search, then smaller steps; a step that still does not converge raises `NonConvergence` (the evaluation
reports the record, never a silent zero). The solver options default to `["Transformation"]`, `["UmfPack"]`,
`["NormDispIncr", 1e-10, 30]` (its tolerance in SI, converted) and `["Newton"]`: any model (a model whose only
multi-point constraints are `equalDOF` may take `["Plain"]`, one whose tangent is symmetric `["SparseSYM"]`;
docs/opensees.md, "Speed").
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from rlcontroller.errors import ModelError
from rlcontroller.physics.fe.build import build_model
from rlcontroller.physics.fe.connections import connection_probes, read_connections
from rlcontroller.physics.fe.description import FEDescription
from rlcontroller.physics.fe.opensees import (
    FORCE_PATTERN,
    FORCE_SERIES,
    GROUND_PATTERN,
    GROUND_SERIES,
    HALVINGS,
    NonConvergence,
    opensees,
    quiet,
    refusal,
)


class OpenSeesIntegrator:
    """The FE model stepped one control step at a time (`physics.protocol.Integrator`).

    Its state x is [floor displacements; floor velocities (relative to the ground); floor absolute
    accelerations] at the control nodes (m, m/s, m/s^2): every output `rlc` reads is linear in it. One
    OpenSees domain per process: it steps one run at a time, starting afresh from a zero state.
    """

    def __init__(
        self, path: Path, function: str, analysis_dt: float, placement: np.ndarray, force_limits: np.ndarray
    ):
        self.path, self.function, self.analysis_dt = path, function, analysis_dt
        # the floor forces of a unit command (the design building's actuator matrix)
        self.placement = placement
        self.force_limits = force_limits
        self._last: np.ndarray | None = None
        self.description: FEDescription | None = None
        self.record_connections = False  # read the member ends each control step (`connection_history`)
        self._connections: list[np.ndarray] = []

    def __getstate__(self) -> dict:  # a copy in another process builds its own domain
        return self.__dict__ | {"_last": None, "description": None, "_connections": []}

    def connection_history(self) -> np.ndarray | None:
        """With `record_connections`: the member ends of the run stepped last (`physics.fe.connections`),
        (control steps + 1, connections, 3), row 0 the state after gravity; else None."""
        return np.array(self._connections) if self.record_connections else None

    def reset(self) -> None:
        self.description = build_model(self.path, self.function)
        check_floors(self.description, self.placement.shape[0], self.path)
        ops = opensees()  # the module of the model just built
        ops.timeSeries("Constant", FORCE_SERIES)
        # the ground's series of the last step (each its own: the Tcl build removes none)
        self.series = GROUND_SERIES
        ops.numberer("RCM")
        set_solver(self.description, self.path)
        ops.integrator("Newmark", 0.5, 0.25)
        ops.analysis("Transient")
        self.ndf = np.atleast_1d(ops.nodeDisp(self.description.control_nodes[0])).size
        if self.record_connections:
            self._probes = connection_probes(ops)
            self._connections = [read_connections(ops, self._probes)]

    def step(
        self, state: np.ndarray, action: np.ndarray, ground: np.ndarray, control_dt: float
    ) -> np.ndarray:
        """The state after one control step with the forces `action` * force limits (N) held and `ground`
        the ground accelerations (m/s^2) over the step (its first and last sample at its ends)."""
        continuing = self._last is not None and np.array_equal(state, self._last)
        if not continuing and not np.any(state):
            self.reset()
        elif not continuing:
            raise RuntimeError("the OpenSees plant steps one run at a time (one domain per process)")
        ops, description = opensees(), self.description
        time = ops.getTime()
        ops.remove("loadPattern", GROUND_PATTERN)
        self.series += 1000
        values = np.asarray(ground, dtype=float) / description.length  # in the model's units
        # the last sample held beyond the step: the analysis' time may pass its end by a rounding
        interval = control_dt / (values.size - 1)
        ops.timeSeries(
            "Path", self.series, "-dt", interval, "-values", *values, "-startTime", time, "-useLast"
        )
        ops.pattern("UniformExcitation", GROUND_PATTERN, description.direction, "-accel", self.series)
        ops.remove("loadPattern", FORCE_PATTERN)
        ops.pattern("Plain", FORCE_PATTERN, FORCE_SERIES)
        nodes = description.control_nodes
        # per floor
        floor_forces = self.placement @ (np.asarray(action) * self.force_limits) / description.force
        for node, force in zip(nodes, floor_forces, strict=True):
            if force != 0.0:
                ops.load(
                    node,
                    *[float(force) if d == description.direction else 0.0 for d in range(1, self.ndf + 1)],
                )
        intervals = values.size - 1
        steps = intervals * math.ceil(interval / self.analysis_dt - 1e-9)  # on every ground sample
        for _ in range(steps):
            _advance(ops, control_dt / steps, description.algorithms, HALVINGS)
        dof = description.direction
        state = np.array(
            [ops.nodeDisp(n, dof) * description.length for n in nodes]
            + [ops.nodeVel(n, dof) * description.length for n in nodes]
            + [ops.nodeAccel(n, dof) * description.length + float(ground[-1]) for n in nodes]
        )
        self._last = state
        if self.record_connections:
            self._connections.append(read_connections(ops, self._probes))
        return state


def check_floors(description: FEDescription, floors: int, path: Path) -> None:
    """ModelError unless the FE model has the design building's number of floors."""
    if len(description.floors) != floors:
        raise ModelError(
            f"{path}: the model has {len(description.floors)} floors, the experiment's building {floors}: "
            "name no building (the design model is then the FE model's reduced one) or one with as many "
            "floors"
        )


def set_solver(description: FEDescription, path: Path) -> None:
    """The description's constraints, system, test and algorithm set in the domain; one OpenSees does not take
    is a ModelError naming it."""
    ops = opensees()
    for command in ("constraints", "system", "test", "algorithm"):
        arguments = description.test_in_model_units if command == "test" else getattr(description, command)
        try:
            with quiet():
                getattr(ops, command)(*arguments)
        except refusal(ops):
            raise ModelError(f"{path}: {command} {list(arguments)}: OpenSees does not take it") from None


def _advance(ops, step: float, algorithms: tuple, halvings: int) -> None:
    """One analysis step of `step` (s), with each algorithm in turn (the first stays set); where all fail,
    two steps of half the size, `halvings` times at most; then `NonConvergence`."""
    start = ops.getTime()
    if ops.analyze(1, step) == 0:
        return
    for algorithm in algorithms[1:]:  # a failed step has been undone (the domain at its last commit)
        ops.setTime(start)
        ops.algorithm(*algorithm)
        converged = ops.analyze(1, step) == 0
        ops.algorithm(*algorithms[0])
        if converged:
            return
    ops.setTime(start)
    if halvings == 0:
        raise NonConvergence(f"the FE model did not converge at t = {start:.3f} s")
    _advance(ops, step / 2.0, algorithms, halvings - 1)
    _advance(ops, step / 2.0, algorithms, halvings - 1)
