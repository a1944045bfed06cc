"""An OpenSees finite-element model as the plant, and the reduced model controllers are designed on.

A model file is code (not data: `docs/opensees.md`, "The trust boundary"), Python or Tcl. A Python file defines
a function (default `build_model`) that takes the `openseespy.opensees` module, builds the model in its domain
(nodes, masses, elements, damping) and returns what `rlc` needs of it (`physics.fe_description`: floors,
direction, story heights, damping, units, solver options). A Tcl file (`.tcl`, a published model run
unmodified) is sourced, from its own folder, in OpenSees' own Tcl interpreter (the `opensees` package, STAIRlab's
xara build, whose `opensees.openseespy` module drives the same domain), and what `rlc` needs of it is in the YAML
file beside it of the same name. The solver options default to `["Transformation"]`, `["UmfPack"]`,
`["NormDispIncr", 1e-10, 30]` and `["Newton"]`: any model (a model whose only multi-point constraints are
`equalDOF` may take `["Plain"]`, one whose tangent is symmetric `["SparseSYM"]`; docs/opensees.md, "Speed").
Everything `rlc` passes in or reads out is converted between SI and the model's units.

`rlc` owns the time loop (`OpenSeesIntegrator`): each control step the ground acceleration enters as a
uniform excitation (its samples over the step, linear between them), the actuator forces as nodal loads
held over the step (on the floors the design building's actuator matrix puts them), and the model's own analysis
advances Newmark average-acceleration steps of at most `analysis_dt` (s), on every ground sample, with the
model's algorithm (Newton-Raphson by default), falling back to Newton, modified Newton on the initial tangent,
Newton with line search, then smaller steps; a step that still does not converge raises
`NonConvergence` (the evaluation reports the record, never a silent zero).

The reduced model (`reduced_building`): the floor masses, the lateral stiffness condensed statically to the
control nodes (the inverse of the flexibility under unit floor loads), and the file's damping matched
mode by mode at the FE model's frequencies.
"""

from __future__ import annotations

import atexit
import importlib.util
import math
import os
import re
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

import numpy as np

from rlcontroller.config.base import read_yaml
from rlcontroller.errors import ConfigError, ModelError
from rlcontroller.physics.fe_description import LENGTHS, FEDescription

MISSING = (
    'the OpenSees plant needs openseespy: pip install -e ".[opensees]" (on Linux also the system\'s BLAS and '
    "LAPACK: apt-get install libblas3 liblapack3)"
)
MISSING_TCL = 'a Tcl model needs OpenSees\' Tcl interpreter, the opensees package: pip install -e ".[opensees]"'
HALVINGS = 4  # after the algorithms, a step is retried in halves, down to 1/16
GROUND_SERIES, GROUND_PATTERN, FORCE_SERIES, FORCE_PATTERN = 101, 101, 102, 102


class NonConvergence(ModelError):
    """The FE model's analysis failed at a control step with every fallback."""


def opensees():
    """The OpenSees module of the model last built in this process (`build_model`): `openseespy.opensees`,
    or for a Tcl model the `opensees` package's module of the same commands; one line saying what to install."""
    if _TCL:
        return _TCL[0]
    _one_library("opensees.tcl", "a Tcl model")
    try:
        import openseespy.opensees as ops
    except ImportError as error:  # also "libblas.so.3: cannot open shared object file"
        raise ConfigError(f"{MISSING} ({error})") from None
    _quiet_at_exit()
    return ops


def _use(tcl: bool) -> None:
    """The models built from now on in this process are Tcl (OpenSees' own interpreter) or Python ones."""
    _TCL.clear()
    if tcl:
        _one_library("openseespylinux", "an OpenSeesPy (Python) model")
        try:
            import opensees.openseespy as ops
        except ImportError as error:
            raise ConfigError(f"{MISSING_TCL} ({error})") from None
        _TCL.append(ops)
        _quiet_at_exit()


def _error(ops) -> type[BaseException]:
    """What the module raises for a command OpenSees refuses (openseespy's OpenSeesError; the Tcl build's own)."""
    error = getattr(ops, "OpenSeesError", None)
    return error if isinstance(error, type) and issubclass(error, BaseException) else Exception


def _one_library(other: str, what: str) -> None:
    """ConfigError (one line) when this process already loaded the other OpenSees library (`other` in its
    modules): the two builds abort a process that steps both."""
    if other in sys.modules:
        raise ConfigError(f"this process already ran {what}: OpenSeesPy and OpenSees' Tcl build cannot share a "
                          "process; run Python and Tcl models in processes of their own")  # fmt: skip


def _quiet_at_exit() -> None:
    if not _QUIET_EXIT:
        atexit.register(_quiet_exit)
        _QUIET_EXIT.append(True)


_QUIET_EXIT: list[bool] = []
EXITED = "rlc: the model called exit"
# Tcl's exit would end the process (rlc with it, exit code 0): in the interpreter that builds models it is an error.
EXIT_AS_ERROR = (
    "if {[info commands ::rlc_tcl_exit] eq {}} {rename ::exit ::rlc_tcl_exit; "
    f'proc ::exit {{args}} {{error "{EXITED}"}}}}'
)
_TCL: list = []


def _quiet_exit() -> None:
    """OpenSees' library prints "Process 0 Terminating" to stderr as the interpreter ends, after every
    atexit handler: the standard error is closed for it (nothing of rlc's is left to say by then)."""
    sys.stderr.flush()
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 2)


def model_function(path: Path, function: str) -> Callable:
    """The model file's function (the file runs here: only ever for a file the user named)."""
    spec = importlib.util.spec_from_file_location(f"rlc_opensees_model_{abs(hash(str(path)))}", path)
    if spec is None or spec.loader is None:
        raise ModelError(f"{path}: not a Python file")
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
    except SystemExit:
        raise ModelError(f"{path}: the model file calls exit as it is loaded") from None
    except Exception as error:
        raise ModelError(f"{path}: {type(error).__name__}: {error}") from None
    if not callable(getattr(module, function, None)):
        raise ModelError(f"{path}: no function {function!r}")
    return getattr(module, function)


def build_model(path: Path, function: str) -> FEDescription:
    """Wipe the OpenSees domain and build the model of `path` in it (a Tcl file: sourced from its folder, its
    description read beside it)."""
    _use(path.suffix == ".tcl")
    if path.suffix == ".tcl":
        return _build_tcl_model(path)
    ops = opensees()
    ops.wipe()
    try:
        built = model_function(path, function)(ops)
    except ModelError:
        raise
    except SystemExit:  # exit() would end rlc itself, silently and with its code
        raise ModelError(f"{path}: {function}: the model calls exit; return its description instead") from None
    except Exception as error:  # the user's code: whatever it raises is a fault of the model
        raise ModelError(f"{path}: {function}: {type(error).__name__}: {error}") from None
    description = FEDescription.of(built, f"{path}: {function}")
    check_in_domain(description, f"{path}: {function}")
    return description


def _build_tcl_model(path: Path) -> FEDescription:
    sidecar = path.with_suffix(".yaml")
    if not sidecar.is_file():
        raise ModelError(f"{path}: a Tcl model needs {sidecar.name} beside it (its floors, direction, story heights, "
                         "damping and units: docs/opensees.md)")  # fmt: skip
    description = FEDescription.of(read_yaml(sidecar), str(sidecar))
    ops, folder = opensees(), os.getcwd()
    ops.wipe()
    try:
        os.chdir(path.parent)  # a published model sources its neighbours by relative names
        ops.eval(EXIT_AS_ERROR)
        # code, like a Python model file: it runs only for an experiment the user named (a run or model folder
        # that names a model file is refused at loading, `config.loading.UNTRUSTED_MODEL`)
        with _quiet():
            ops.eval(f"source {{{path.name}}}")
    except Exception as error:  # the model's own Tcl: whatever it raises is a fault of the model
        message = " ".join(str(error).split())
        if EXITED in message:
            line = re.search(rf'file "{re.escape(path.name)}" line (\d+)', message)
            where = f" (line {line.group(1)})" if line else ""
            raise ModelError(f"{path}: the model calls exit{where}, which would end rlc: remove it") from None
        raise ModelError(f"{path}: Tcl error: {message}") from None
    finally:
        os.chdir(folder)
    check_in_domain(description, str(sidecar))
    if description.rayleigh_modes is not None:  # what the model's own analysis script would give it
        (i, zeta_i), (j, zeta_j) = description.rayleigh_modes
        w_i, w_j = 2.0 * np.pi / periods(j, path)[[i - 1, j - 1]]
        a1 = 2.0 * (zeta_j * w_j - zeta_i * w_i) / (w_j**2 - w_i**2)  # zeta = a0 / (2 w) + a1 w / 2 at both
        a0 = 2.0 * zeta_i * w_i - a1 * w_i**2
        ops.rayleigh(a0, 0.0, a1, 0.0)
        description = replace(description, rayleigh=(float(a0), float(a1)))
    return description


def check_in_domain(description: FEDescription, where: str) -> None:
    """ModelError (one line) unless every floor node is in the domain, `direction` is one of the degrees of
    freedom of every one and every floor has mass in it (a fixed base node has none)."""
    ops = opensees()
    nodes = set(ops.getNodeTags())
    for floor, tags in enumerate(description.floors, start=1):
        missing = [tag for tag in tags if tag not in nodes]
        if missing:
            raise ModelError(f"{where}: floors: floor {floor} names node {missing[0]}, which the model does not have")
        freedoms = min(int(np.atleast_1d(ops.getNDF(tag))[0]) for tag in tags)
        if not 1 <= description.direction <= freedoms:
            raise ModelError(
                f"{where}: direction {description.direction}: expected a degree of freedom of the floor nodes, "
                f"1 to {freedoms}"
            )
    for floor, mass in enumerate(floor_masses(description), start=1):
        if not mass > 0.0:
            raise ModelError(
                f"{where}: floors: floor {floor} (nodes {list(description.floors[floor - 1])}) has no mass in "
                f"direction {description.direction}: a floor is a level with mass (a fixed base node has none)"
            )


def floor_masses(description: FEDescription) -> np.ndarray:
    """Each floor's mass in the lateral direction (kg): the sum over its nodes."""
    ops = opensees()
    masses = [sum(ops.nodeMass(n, description.direction) for n in nodes) for nodes in description.floors]
    return np.array(masses) * description.mass


def periods(count: int, path: Path) -> np.ndarray:
    """The first `count` natural periods (s) of the model in the domain; a ModelError naming `path` where it has
    fewer modes with stiffness and mass (no element, or a floor nothing holds)."""
    ops = opensees()
    ops.wipeAnalysis()  # an eigen analysis of its own (one the model file ran may be left over)
    with _quiet():
        try:
            eigenvalues = ops.eigen(count)
        except _error(ops):  # ARPACK wants more equations than modes: a model of as many as asked
            eigenvalues = ops.eigen("-fullGenLapack", count)
    eigenvalues = np.asarray(eigenvalues, dtype=float)
    if eigenvalues.size < count or not np.all(np.isfinite(eigenvalues) & (eigenvalues > 0.0)):
        raise ModelError(
            f"{path}: the eigen analysis finds {int(np.sum(eigenvalues > 0.0))} of {count} modes with stiffness and "
            "mass: an element missing, or a floor nothing holds"
        )
    return 2.0 * np.pi / np.sqrt(eigenvalues)


@contextmanager
def _quiet() -> Iterator[None]:
    """OpenSees' own messages (on the standard error, or the output in the Tcl build) silenced: a failed first
    try that has a fallback."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved, devnull = [os.dup(1), os.dup(2)], os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.dup2(devnull, 2)
    try:
        yield
    finally:
        for stream, kept in zip((1, 2), saved, strict=True):
            os.dup2(kept, stream)
            os.close(kept)
        os.close(devnull)


def condensed_stiffness(description: FEDescription, path: Path) -> np.ndarray:
    """The lateral stiffness at the control nodes (N/m): the inverse of the flexibility measured by a
    static analysis under a unit load at each (small: an elastic response of a yielding model), about the
    model's gravity state (its P-Delta included). A floor nothing holds is a ModelError naming it."""
    ops = opensees()
    nodes, dof = description.control_nodes, description.direction
    ndf = np.atleast_1d(ops.nodeDisp(nodes[0])).size
    at_rest = np.array([ops.nodeDisp(n, dof) for n in nodes])  # under the model's gravity loads
    flexibility = np.zeros((len(nodes), len(nodes)))
    ops.timeSeries("Linear", FORCE_SERIES)
    for j, node in enumerate(nodes):
        ops.pattern("Plain", FORCE_PATTERN, FORCE_SERIES)
        ops.load(node, *[1.0 if d == dof else 0.0 for d in range(1, ndf + 1)])
        _static_analysis(ops)
        with _quiet():
            failed = ops.analyze(1) != 0
        if failed:
            raise ModelError(
                f"{path}: a unit load on floor {j + 1} (node {node}, direction {dof}) finds no static equilibrium: "
                "no element holds that floor, or the model is a mechanism"
            )
        flexibility[:, j] = np.array([ops.nodeDisp(n, dof) for n in nodes]) - at_rest
        ops.remove("loadPattern", FORCE_PATTERN)
        ops.wipeAnalysis()
        ops.reset()  # back to the unloaded model: the next analysis takes the held gravity loads again
        ops.setTime(0.0)
    stiffness = np.linalg.inv(flexibility) * description.force / description.length  # N/m
    return 0.5 * (stiffness + stiffness.T)


def _static_analysis(ops) -> None:
    ops.constraints("Transformation")
    ops.numberer("RCM")
    ops.system("UmfPack")
    ops.test("NormDispIncr", 1e-12, 20)
    ops.algorithm("Newton")
    ops.integrator("LoadControl", 1.0)
    ops.analysis("Static")


def damping_ratios(description: FEDescription, circular_frequencies: np.ndarray) -> list[float]:
    """The model's damping ratio in each mode: its own modal ratios, or its Rayleigh pair's at the FE
    model's frequencies (rad/s)."""
    if description.modal_damping is not None:
        ratios = list(description.modal_damping)
        return (ratios + [ratios[-1]] * len(circular_frequencies))[: len(circular_frequencies)]
    a0, a1 = description.rayleigh
    return [float(a0 / (2.0 * w) + a1 * w / 2.0) for w in circular_frequencies]


PLAUSIBLE_STORY = (1.5, 12.0)  # m: a story's height in buildings; far outside it, the length unit is likely wrong


def warn_story_heights(description: FEDescription, path: Path) -> None:
    """A warning on the standard error where a story height, in m, is outside `PLAUSIBLE_STORY`."""
    heights = [height * description.length for height in description.story_heights]
    low, high = PLAUSIBLE_STORY
    if min(heights) < low or max(heights) > high:
        unit = next(name for name, metres in LENGTHS.items() if metres == description.length)
        print(
            f"warning: {path}: story heights {min(heights):.3g} to {max(heights):.3g} m, read in {unit} "
            f"(units.length), are outside {low:g} to {high:g} m: is the model's length unit {unit}?",
            file=sys.stderr,
        )


def fe_modes(path: Path, function: str, count: int) -> tuple[np.ndarray, list[float]]:
    """The first `count` periods (s) of the FE model in `path` and its damping ratio in each."""
    description = build_model(path, function)
    fe_periods = periods(count, path)
    opensees().wipe()
    return fe_periods, damping_ratios(description, 2.0 * np.pi / fe_periods)


def reduced_building(path: Path, function: str) -> dict:
    """The design model of the FE model in `path`: a building part of matrices (SI) with its floors'
    masses, the condensed stiffness and the model's damping matched mode by mode, and the FE model's
    first periods (s) for `rlc info`."""
    description = build_model(path, function)
    n = len(description.floors)
    fe_periods = periods(n, path)
    masses = floor_masses(description)
    stiffness = condensed_stiffness(description, path)
    ratios = damping_ratios(description, 2.0 * np.pi / fe_periods)
    opensees().wipe()
    warn_story_heights(description, path)
    return {
        "name": f"reduced from {path.name}",
        "source": str(path),
        "mass_matrix": np.diag(masses).tolist(),
        "stiffness_matrix": stiffness.tolist(),
        "modal_damping": ratios,
        "story_heights": [height * description.length for height in description.story_heights],
    }


class OpenSeesIntegrator:
    """The FE model stepped one control step at a time (`physics.protocol.Integrator`).

    Its state x is [floor displacements; floor velocities (relative to the ground); floor absolute
    accelerations] at the control nodes (m, m/s, m/s^2): every output `rlc` reads is linear in it. One
    OpenSees domain per process: it steps one run at a time, starting afresh from a zero state.
    """

    def __init__(self, path: Path, function: str, analysis_dt: float, placement: np.ndarray, force_limits: np.ndarray):
        self.path, self.function, self.analysis_dt = path, function, analysis_dt
        self.placement = placement  # the floor forces of a unit command (the design building's actuator matrix)
        self.force_limits = force_limits
        self._last: np.ndarray | None = None
        self.description: FEDescription | None = None

    def __getstate__(self) -> dict:  # a copy in another process builds its own domain
        return self.__dict__ | {"_last": None, "description": None}

    def reset(self) -> None:
        self.description = build_model(self.path, self.function)
        check_floors(self.description, self.placement.shape[0], self.path)
        ops = opensees()  # the module of the model just built
        ops.timeSeries("Constant", FORCE_SERIES)
        self.series = GROUND_SERIES  # the ground's series of the last step (each its own: the Tcl build removes none)
        ops.numberer("RCM")
        set_solver(self.description, self.path)
        ops.integrator("Newmark", 0.5, 0.25)
        ops.analysis("Transient")
        self.ndf = np.atleast_1d(ops.nodeDisp(self.description.control_nodes[0])).size

    def step(self, state: np.ndarray, action: np.ndarray, ground: np.ndarray, control_dt: float) -> np.ndarray:
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
        ops.timeSeries("Path", self.series, "-dt", interval, "-values", *values, "-startTime", time, "-useLast")
        ops.pattern("UniformExcitation", GROUND_PATTERN, description.direction, "-accel", self.series)
        ops.remove("loadPattern", FORCE_PATTERN)
        ops.pattern("Plain", FORCE_PATTERN, FORCE_SERIES)
        nodes = description.control_nodes
        floor_forces = self.placement @ (np.asarray(action) * self.force_limits) / description.force  # per floor
        for node, force in zip(nodes, floor_forces, strict=True):
            if force != 0.0:
                ops.load(node, *[float(force) if d == description.direction else 0.0 for d in range(1, self.ndf + 1)])
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
        return state


def check_floors(description: FEDescription, floors: int, path: Path) -> None:
    """ModelError unless the FE model has the design building's number of floors."""
    if len(description.floors) != floors:
        raise ModelError(
            f"{path}: the model has {len(description.floors)} floors, the experiment's building {floors}: name no "
            "building (the design model is then the FE model's reduced one) or one with as many floors"
        )


def set_solver(description: FEDescription, path: Path) -> None:
    """The description's constraints, system, test and algorithm set in the domain; one OpenSees does not take
    is a ModelError naming it."""
    ops = opensees()
    for command in ("constraints", "system", "test", "algorithm"):
        arguments = description.test_in_model_units if command == "test" else getattr(description, command)
        try:
            with _quiet():
                getattr(ops, command)(*arguments)
        except _error(ops):
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
