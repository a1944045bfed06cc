"""OpenSees in this process: its library (OpenSeesPy, or OpenSees' own Tcl interpreter for a Tcl model) and
what rlc reads of a model built in its domain: the floors' masses, the periods, the stiffness condensed to the
floors (the inverse of the flexibility under unit floor loads, about the gravity state) and the damping in
each mode.

Building a model is `physics.fe.build` (a model file is code: docs/opensees.md, "The trust boundary");
stepping it `physics.fe.integrator`. Everything rlc passes in or reads out is converted between SI and the
model's units.
"""

from __future__ import annotations

import atexit
import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from rlcontroller.errors import ConfigError, ModelError
from rlcontroller.physics.fe.description import LENGTHS, FEDescription

MISSING = (
    'the OpenSees plant needs openseespy: pip install -e ".[opensees]" (on Linux also the system\'s BLAS and '
    "LAPACK: apt-get install libblas3 liblapack3)"
)
MISSING_TCL = (
    'a Tcl model needs OpenSees\' Tcl interpreter, the opensees package: pip install -e ".[opensees]"'
)
HALVINGS = 4  # after the algorithms, a step is retried in halves, down to 1/16
GROUND_SERIES, GROUND_PATTERN, FORCE_SERIES, FORCE_PATTERN = 101, 101, 102, 102


class NonConvergence(ModelError):
    """The FE model's analysis failed at a control step with every fallback."""


def opensees():
    """The OpenSees module of the model last built in this process (`build_model`): `openseespy.opensees`,
    or for a Tcl model the `opensees` package's module of the same commands; one line saying what to
    install."""
    if _TCL:
        return _TCL[0]
    _one_library("opensees.tcl", "a Tcl model")
    try:
        import openseespy.opensees as ops
    except (
        ImportError,
        RuntimeError,
    ) as error:  # "libblas.so.3: cannot open ..."; "Failed to import openseespy"
        raise ConfigError(f"{MISSING} ({error})") from None
    _quiet_at_exit()
    return ops


def use_library(tcl: bool) -> None:
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


def refusal(ops) -> type[BaseException]:
    """What the module raises for a command OpenSees refuses (openseespy's OpenSeesError; the Tcl build's
    own)."""
    error = getattr(ops, "OpenSeesError", None)
    return error if isinstance(error, type) and issubclass(error, BaseException) else Exception


def _one_library(other: str, what: str) -> None:
    """ConfigError (one line) when this process already loaded the other OpenSees library (`other` in its
    modules): the two builds abort a process that steps both."""
    if other in sys.modules:
        raise ConfigError(
            f"this process already ran {what}: OpenSeesPy and OpenSees' Tcl build cannot share a "
            "process; run Python and Tcl models in processes of their own"
        )


def _quiet_at_exit() -> None:
    if not _QUIET_EXIT:
        atexit.register(_quiet_exit)
        _QUIET_EXIT.append(True)


_QUIET_EXIT: list[bool] = []
_TCL: list = []


def _quiet_exit() -> None:
    """OpenSees' library prints "Process 0 Terminating" to stderr as the interpreter ends, after every
    atexit handler: the standard error is closed for it (nothing of rlc's is left to say by then)."""
    sys.stderr.flush()
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 2)


def check_in_domain(description: FEDescription, where: str) -> None:
    """ModelError (one line) unless every floor node is in the domain, `direction` is one of the degrees of
    freedom of every one and every floor has mass in it (a fixed base node has none)."""
    ops = opensees()
    try:
        with quiet():
            nodes = set(np.atleast_1d(ops.getNodeTags()).tolist())
    except Exception:  # the Tcl build raises TclError where no model is left (the script ended with wipe)
        nodes = set()
    if not nodes:
        raise ModelError(
            f"{where}: no model is left in the domain once the file has run (does it end with wipe? "
            "a Tcl script's description may say build_until: loadConst)"
        )
    for floor, tags in enumerate(description.floors, start=1):
        missing = [tag for tag in tags if tag not in nodes]
        if missing:
            raise ModelError(
                f"{where}: floors: floor {floor} names node {missing[0]}, which the model does not have"
            )
        freedoms = min(int(np.atleast_1d(ops.getNDF(tag))[0]) for tag in tags)
        if not 1 <= description.direction <= freedoms:
            raise ModelError(
                f"{where}: direction {description.direction}: expected a degree of freedom of the floor "
                f"nodes, 1 to {freedoms}"
            )
    for floor, mass in enumerate(floor_masses(description), start=1):
        if not mass > 0.0:
            raise ModelError(
                f"{where}: floors: floor {floor} (nodes {list(description.floors[floor - 1])}) has no mass "
                f"in direction {description.direction}: a floor is a level with mass (a fixed base node has "
                "none)"
            )


def floor_masses(description: FEDescription) -> np.ndarray:
    """Each floor's mass in the lateral direction (kg): the sum over its nodes."""
    ops = opensees()
    masses = [sum(ops.nodeMass(n, description.direction) for n in nodes) for nodes in description.floors]
    return np.array(masses) * description.mass


def periods(count: int, path: Path) -> np.ndarray:
    """The first `count` natural periods (s) of the model in the domain; a ModelError naming `path` where it
    has fewer modes with stiffness and mass (no element, or a floor nothing holds)."""
    ops = opensees()
    ops.wipeAnalysis()  # an eigen analysis of its own (one the model file ran may be left over)
    with quiet():
        try:
            eigenvalues = ops.eigen(count)
        except refusal(ops):  # ARPACK wants more equations than modes: a model of as many as asked
            eigenvalues = ops.eigen("-fullGenLapack", count)
    eigenvalues = np.asarray(eigenvalues, dtype=float)
    if eigenvalues.size < count or not np.all(np.isfinite(eigenvalues) & (eigenvalues > 0.0)):
        raise ModelError(
            f"{path}: the eigen analysis finds {int(np.sum(eigenvalues > 0.0))} of {count} modes with "
            "stiffness and mass: an element missing, or a floor nothing holds"
        )
    return 2.0 * np.pi / np.sqrt(eigenvalues)


@contextmanager
def quiet() -> Iterator[None]:
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
        with quiet():
            failed = ops.analyze(1) != 0
        if failed:
            raise ModelError(
                f"{path}: a unit load on floor {j + 1} (node {node}, direction {dof}) finds no static "
                "equilibrium: no element holds that floor, or the model is a mechanism"
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


# m: a story's height in buildings; far outside it, the length unit is likely wrong
PLAUSIBLE_STORY = (1.5, 12.0)


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
