"""The uncontrolled responses of an FE plant, computed once and kept between commands.

Every controller is judged against the building uncontrolled on the same motions (J1-J4, the safety check's
fail-safe reference of a building without devices or supervisor): on an FE model those runs are half of
`rlc check`'s work and never depend on the controller. They are kept in one file per FE model and suite,
named by the sha256 of everything they depend on: the model's folder (every .py, .tcl and .yaml file in it:
a model sources its neighbours), the function that builds it, the analysis and control steps, whether member
ends are read, every motion's samples, and rlc's version. A change to any of them names another file; a file
that does not read back is computed again. The folder is $RLC_CACHE, else $XDG_CACHE_HOME/rlcontroller, else
~/.cache/rlcontroller; deleting it costs only the runs. A model that stands still under the ground (its peak
drift under 1 % of its design model's under the same motion: its masses do not feel the ground) is refused
before any run (`check_moves`: a unit ground pulse, in this process, a fraction of a second of analysis) and,
should a motion find what the pulse did not, before anything is kept or judged.
"""

from __future__ import annotations

import hashlib
import io
import os
import zipfile
from collections.abc import Callable
from dataclasses import fields
from pathlib import Path

import numpy as np

from rlcontroller.errors import ModelError
from rlcontroller.files import atomic_write
from rlcontroller.physics.motions.excitation import Load
from rlcontroller.physics.plant import Plant
from rlcontroller.physics.response import Response
from rlcontroller.simulation.rollout import uncontrolled_responses

MODEL_SUFFIXES = (".py", ".tcl", ".yaml")
# of the design model's peak drift under the same motion: an FE model moving less stands still
STANDING_STILL = 0.01


def cache_folder() -> Path:
    """Where kept responses live (module docstring)."""
    if os.environ.get("RLC_CACHE"):
        return Path(os.environ["RLC_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "rlcontroller"


def reference_key(plant: Plant, motions: list[Load]) -> str:
    """The sha256 of everything the uncontrolled responses of the FE plant `plant` on `motions` depend on."""
    from rlcontroller import __version__

    fe = plant.fe_model
    digest = hashlib.sha256(
        f"rlc {__version__}; {fe.function}; {fe.analysis_dt!r}; {plant.control_dt!r}".encode()
    )
    if fe.record_connections:  # the member ends too
        digest.update(b"connections")
    folder = Path(fe.path).parent
    for path in sorted(p for p in folder.iterdir() if p.suffix in MODEL_SUFFIXES and p.is_file()):
        digest.update(path.name.encode() + b"\0" + path.read_bytes())
    for motion in motions:
        digest.update(f"{motion.name}; {motion.dt!r}".encode())
        digest.update(np.ascontiguousarray(motion.acceleration, dtype=float).tobytes())
        if motion.floor_forces is not None:
            digest.update(np.ascontiguousarray(motion.floor_forces, dtype=float).tobytes())
    return digest.hexdigest()


PULSE_S = 1.0  # the stand-still test: a ground pulse of one control step at 1 m/s^2, then this long at rest


def check_moves(plant: Plant) -> float:
    """The FE plant's peak drift under a unit ground pulse over its design model's (stepped here, in this
    process: the model is built once more); ModelError, one line, before any run, when it stands still."""
    steps = max(2, round(PULSE_S / plant.control_dt))
    ground = np.zeros(steps + 1)
    ground[1] = 1.0  # m/s^2: up over the first step, down over the second
    fe, state, peak = plant.fe_model, np.zeros(plant.n_state), 0.0
    drift = plant.building.drift_matrix()[:, : plant.building.n_floors]
    for k in range(steps):
        state = fe.step(state, np.zeros(plant.force_limits.size), ground[k : k + 2], plant.control_dt)
        peak = max(peak, float(np.max(np.abs(drift @ state[: plant.building.n_floors]))))
    pulse = Load("a unit ground pulse", plant.control_dt, ground, synthetic=True)
    expected = float(np.max(np.abs(uncontrolled_responses(plant.design.bare, [pulse])[0].drift)))
    _refuse_standing_still(plant, "a unit ground pulse", peak, expected)
    return peak / expected


def _refuse_standing_still(plant: Plant, what: str, peak: float, expected: float) -> None:
    if peak < STANDING_STILL * expected:
        raise ModelError(
            f"{plant.fe_model.path}: the model stands still under {what} (peak drift {peak:.1e} m, its "
            f"design model {expected:.1e} m): its masses do not feel the ground; masses on nodes tied by "
            "equalDOF under the "
            'Transformation handler do not (docs/opensees.md, "A Tcl model"): try constraints: [Plain]'
        )


def uncontrolled(
    plant: Plant, motions: list[Load], on_motions: Callable[[int], None] | None = None
) -> list[Response]:
    """`uncontrolled_responses(plant, motions)`, kept for an FE plant (module docstring); an FE plant's runs
    are reported to `on_motions` as each is done (all at once when kept)."""
    if plant.fe_model is None:
        return uncontrolled_responses(plant, motions)
    path = cache_folder() / f"uncontrolled-{reference_key(plant, motions)}.npz"
    kept = _read(path, len(motions))
    if kept is not None:
        if on_motions is not None:
            on_motions(len(motions))
        return kept
    check_moves(plant)
    responses = uncontrolled_responses(plant, motions, on_motions)
    designed = uncontrolled_responses(plant.design, motions)  # the reduced (or named) design model, in numpy
    for motion, response, design in zip(motions, responses, designed, strict=True):
        peak, expected = np.max(np.abs(response.drift)), np.max(np.abs(design.drift))
        _refuse_standing_still(plant, f"{motion.name}'s ground motion", peak, expected)
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(path, _packed(responses))
    return responses


def _packed(responses: list[Response]) -> bytes:
    arrays = {
        f"{i}/{field.name}": getattr(response, field.name)
        for i, response in enumerate(responses)
        for field in fields(Response)
        if getattr(response, field.name) is not None
    }
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    return buffer.getvalue()


def _read(path: Path, count: int) -> list[Response] | None:
    """The responses kept at `path`, or None if there are none or they do not read back whole."""
    if not path.is_file():
        return None
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {name: data[name] for name in data.files}
        parts: list[dict] = [{} for _ in range(count)]
        for name, array in arrays.items():
            index, field = name.split("/", 1)
            parts[int(index)][field] = array
        return [Response(**part) for part in parts]
    except (OSError, ValueError, TypeError, IndexError, KeyError, zipfile.BadZipFile):
        return None
