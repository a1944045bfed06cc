"""Building an FE model in the OpenSees domain, and its reduced model (the design model controllers are
designed on).

A model file is code (not data: `docs/opensees.md`, "The trust boundary"), Python or Tcl. A Python file
defines a function (default `build_model`) that takes the `openseespy.opensees` module, builds the model in
its domain (nodes, masses, elements, damping) and returns what `rlc` needs of it (`physics.fe.description`:
floors, direction, story heights, damping, units, solver options). A Tcl file (`.tcl`, a published model run
unmodified) is sourced, from its own folder, in OpenSees' own Tcl interpreter (the `opensees` package,
STAIRlab's xara build, whose `opensees.openseespy` module drives the same domain), and what `rlc` needs of it
is in the YAML file beside it of the same name. A model that calls `exit` is refused in one line (it would end
rlc).

The reduced model (`reduced_building`): the floor masses, the lateral stiffness condensed statically to the
control nodes, and the file's damping matched mode by mode at the FE model's frequencies.
"""

from __future__ import annotations

import importlib.util
import os
import re
import sys
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np

from rlcontroller.config.base import read_yaml
from rlcontroller.errors import ModelError
from rlcontroller.physics.fe.description import FEDescription
from rlcontroller.physics.fe.opensees import (
    check_in_domain,
    condensed_stiffness,
    damping_ratios,
    floor_masses,
    opensees,
    periods,
    quiet,
    use_library,
    warn_story_heights,
)

EXITED, BUILT = "rlc: the model called exit", "rlc: the model stands after gravity (loadConst)"
# What a published script does beyond building its model, made harmless in the interpreter that builds it:
# `exit` (it would end rlc, exit code 0) is an error; `recorder` writes nothing (rlc reads the domain itself;
# the files went into the model's folder, from every worker); the display commands of OpenSees' own build are
# no-ops; and `loadConst`, which holds the gravity loads before the script's own analyses, ends the build
# there (unless the description's build_until is end). OpenSees registers its commands anew at `model` and
# `wipe`: wrapped again. A script that never holds its loads would leave a Linear pattern growing with rlc's
# time: rlc holds them itself (`loadConst -time 0.0`, where they stand) and says so.
TCL_PRELUDE = """
proc ::rlc_wrap {name body} {
    if {[info commands ::$name] eq {} || [info procs ::$name] ne {}} { return }
    if {[info commands ::rlc_tcl_$name] ne {}} { rename ::rlc_tcl_$name {} }
    rename ::$name ::rlc_tcl_$name
    proc ::$name {args} $body
}
proc ::rlc_prelude {} {
    rlc_wrap wipe {::rlc_tcl_wipe {*}$args; ::rlc_prelude}
    rlc_wrap model {::rlc_tcl_model {*}$args; ::rlc_prelude}
    rlc_wrap loadConst {
        ::rlc_tcl_loadConst {*}$args; set ::rlc_held 1
        if {$::rlc_stop_at_load_const} {error "BUILT"}
    }
    rlc_wrap recorder {}
    rlc_wrap exit {error "EXITED"}
    foreach name {vup vrp vpn prp viewWindow plane port projection fill display} {
        if {[info commands ::$name] eq {}} { proc ::$name {args} {} }
    }
}
::rlc_prelude
""".replace("BUILT", BUILT).replace("EXITED", EXITED)


def _tcl_error(path: Path, message: str) -> ModelError:
    """The model's Tcl error in one line: an exit, a missing package, or the interpreter's own words."""
    if EXITED in message:
        line = re.search(rf'file "{re.escape(path.name)}" line (\d+)', message)
        where = f" (line {line.group(1)})" if line else ""
        return ModelError(f"{path}: the model calls exit{where}, which would end rlc: remove it")
    package = re.search(r"can't find package (\S+)", message)
    if package:
        return ModelError(
            f"{path}: the model needs the Tcl package {package.group(1)}, which OpenSees' interpreter lacks: "
            "install it (e.g. tcllib) and name the folder that holds it in TCLLIBPATH"
        )
    return ModelError(f"{path}: Tcl error: {message}")


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
    use_library(path.suffix == ".tcl")
    if path.suffix == ".tcl":
        return _build_tcl_model(path)
    ops = opensees()
    ops.wipe()
    try:
        built = model_function(path, function)(ops)
    except ModelError:
        raise
    except SystemExit:  # exit() would end rlc itself, silently and with its code
        raise ModelError(
            f"{path}: {function}: the model calls exit; return its description instead"
        ) from None
    except Exception as error:  # the user's code: whatever it raises is a fault of the model
        raise ModelError(f"{path}: {function}: {type(error).__name__}: {error}") from None
    description = FEDescription.of(built, f"{path}: {function}")
    check_in_domain(description, f"{path}: {function}")
    return description


def _build_tcl_model(path: Path) -> FEDescription:
    sidecar = path.with_suffix(".yaml")
    if not sidecar.is_file():
        raise ModelError(
            f"{path}: a Tcl model needs {sidecar.name} beside it (its floors, direction, story heights, "
            "damping and units: docs/opensees.md)"
        )
    description = FEDescription.of(read_yaml(sidecar), str(sidecar))
    ops, folder = opensees(), os.getcwd()
    ops.wipe()
    try:
        os.chdir(path.parent)  # a published model sources its neighbours by relative names
        ops.eval(TCL_PRELUDE + f"set ::rlc_stop_at_load_const {int(description.build_until == 'loadConst')}")
        ops.eval("set ::rlc_held 0")
        # code, like a Python model file: it runs only for an experiment the user named (a run or model folder
        # that names a model file is refused at loading, `config.loading.UNTRUSTED_MODEL`)
        with quiet():
            ops.eval(f"source {{{path.name}}}")
    except Exception as error:  # the model's own Tcl: whatever it raises is a fault of the model
        message = " ".join(str(error).split())
        if BUILT not in message:
            raise _tcl_error(path, message) from None
    finally:
        os.chdir(folder)
    check_in_domain(description, str(sidecar))
    # its loads would grow with rlc's time: held where they stand
    if str(ops.eval("set ::rlc_held")).strip() != "1":
        held = (
            "::rlc_tcl_loadConst"
            if str(ops.eval("info commands ::rlc_tcl_loadConst")).strip()
            else "loadConst"
        )
        ops.eval(f"{held} -time 0.0")  # the model's own command, not rlc's wrapper (which ends a build)
        description = replace(description, loads_held_by_rlc=True)
    if description.rayleigh_modes is not None:  # what the model's own analysis script would give it
        (i, zeta_i), (j, zeta_j) = description.rayleigh_modes
        w_i, w_j = 2.0 * np.pi / periods(j, path)[[i - 1, j - 1]]
        a1 = 2.0 * (zeta_j * w_j - zeta_i * w_i) / (w_j**2 - w_i**2)  # zeta = a0 / (2 w) + a1 w / 2 at both
        a0 = 2.0 * zeta_i * w_i - a1 * w_i**2
        ops.rayleigh(a0, 0.0, a1, 0.0)
        description = replace(description, rayleigh=(float(a0), float(a1)))
    return description


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
    if description.loads_held_by_rlc:
        print(
            f"note: {path} never holds its loads with loadConst: rlc holds them where they stand once it has "
            "run (loadConst -time 0.0), or a Linear pattern would grow with time through the motion",
            file=sys.stderr,
        )
    return {
        "name": f"reduced from {path.name}",
        "source": str(path),
        "mass_matrix": np.diag(masses).tolist(),
        "stiffness_matrix": stiffness.tolist(),
        "modal_damping": ratios,
        "story_heights": [height * description.length for height in description.story_heights],
    }
