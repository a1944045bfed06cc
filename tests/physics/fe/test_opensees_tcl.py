"""A Tcl OpenSees model as the plant (`physics.fe.opensees`, OpenSees' own Tcl interpreter from the `opensees`
package): the five-story building written in Tcl in kip and foot units reduces to the paper's building in SI
and moves as rlc's exact integration of it; what a Tcl model lacks or gets wrong is one line naming the file.

OpenSeesPy and OpenSees' Tcl build abort a process that steps both, so every Tcl model here runs in a process
of its own (as `rlc` itself runs one model per process), and this module's own process loads neither."""

import json
import shutil
import subprocess
import sys
from importlib.util import find_spec
from pathlib import Path

import numpy as np
import pytest

from rlcontroller.config import Experiment
from tests.conftest import NO_SYSTEM_BLAS, OPENSEES_MISSING

pytestmark = pytest.mark.skipif(find_spec("opensees") is None, reason="a Tcl model needs the opensees extra")

REPOSITORY = Path(__file__).resolve().parents[3]
TCL_MODEL = REPOSITORY / "configs" / "opensees" / "five_story_shear_kip_ft.tcl"
TCL_EXPERIMENT = REPOSITORY / "studies" / "opensees" / "five_story_tcl.yaml"


def in_own_process(code: str) -> dict:
    """`code` run in a fresh interpreter; what it prints last, read as JSON."""
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=600, cwd=REPOSITORY
    )
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def model_error_in_own_process(call: str) -> subprocess.CompletedProcess:
    """`call` (build_model, pushover, ...) in a fresh interpreter: the ModelError it raises printed on
    stdout."""
    code = (
        "import numpy as np; from pathlib import Path; from rlcontroller.errors import ModelError\n"
        "from rlcontroller.physics.fe.build import build_model; from rlcontroller.physics.fe.pushover import "
        f"pushover\ntry: {call}\nexcept ModelError as error: print(error)"
    )
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)


def test_a_tcl_model_in_kip_and_foot_reduces_to_the_paper_building_in_si():
    """Masses (kip s^2/ft -> kg), the condensed stiffness (kip/ft -> N/m), story heights (ft -> m) and the
    damping matched mode by mode (1 % in mode 1, 5 % in mode 5): the paper's building, from a Tcl file sourced
    unmodified."""
    reduced = in_own_process(
        "import json; from pathlib import Path; from rlcontroller.physics.fe.build import reduced_building; "
        f"print(json.dumps(reduced_building(Path({str(TCL_MODEL)!r}), 'build_model')))"
    )
    paper = Experiment().building  # configs/buildings/five_story.yaml
    k, n = np.asarray(paper.stiffnesses), 5
    drift = np.eye(n) - np.eye(n, k=-1)
    np.testing.assert_allclose(np.diag(reduced["mass_matrix"]), paper.masses, rtol=1e-12)
    np.testing.assert_allclose(
        reduced["stiffness_matrix"], drift.T @ np.diag(k) @ drift, rtol=1e-9, atol=1e-3
    )
    assert reduced["modal_damping"][0] == pytest.approx(0.01, rel=1e-9)
    assert reduced["modal_damping"][4] == pytest.approx(0.05, rel=1e-9)
    np.testing.assert_allclose(reduced["story_heights"], [3.0] * 5, rtol=1e-9)


def test_a_tcl_models_pushover_is_the_linear_building_in_si_and_never_yields():
    """The first-mode pushover through the Tcl interpreter, in kip and foot: the story stiffnesses are the
    paper's (N/m), shear over drift stays there to the end (a linear model), so no story yields."""
    pushed = in_own_process(
        "import json; import numpy as np; from pathlib import Path; "
        "from rlcontroller.physics.fe.pushover import pushover; "
        "from rlcontroller.physics.fe.build import reduced_building; "
        f"r = reduced_building(Path({str(TCL_MODEL)!r}), 'build_model'); "
        f"p = pushover(Path({str(TCL_MODEL)!r}), 'build_model', np.array(r['mass_matrix']), "
        "np.array(r['stiffness_matrix'])); "
        "print(json.dumps({'k': p.stiffness.tolist(), 'yielded': p.yielded.tolist(), "
        "'secant': (p.shear[-1] / p.drift[-1]).tolist()}))"
    )
    np.testing.assert_allclose(pushed["k"], Experiment().building.stiffnesses, rtol=1e-9)
    np.testing.assert_allclose(pushed["secant"], Experiment().building.stiffnesses, rtol=1e-6)
    assert not any(pushed["yielded"])


PUBLISHED_TAIL = """
vup 0 1 0 ;# the display commands of OpenSees' own build
vrp 0 0 0
recorder Node -file disp.out -time -node 5 -dof 1 disp
pattern Plain 1 Linear { load 5 0.0 } ;# the script's own gravity analysis
constraints Plain; numberer RCM; system BandGeneral; test NormDispIncr 1e-8 10; algorithm Newton
integrator LoadControl 0.1; analysis Static; analyze 10
loadConst -time 0.0
pattern Plain 2 Linear { load 5 1.0 } ;# then its own pushover, which rlc skips
integrator DisplacementControl 5 1 0.01; analyze 100
wipe all
"""


def test_a_published_script_runs_unmodified_as_it_stands_after_gravity(tmp_path):
    """Display commands, a recorder, the script's gravity analysis, then its own pushover and a wipe: rlc
    takes the model at loadConst (the same reduced model as the bare file), and nothing is written beside the
    model."""
    shutil.copy(TCL_MODEL.with_suffix(".yaml"), tmp_path)
    (tmp_path / TCL_MODEL.name).write_text(TCL_MODEL.read_text() + PUBLISHED_TAIL)
    model = tmp_path / TCL_MODEL.name
    reduce = (
        "import json; from pathlib import Path; from rlcontroller.physics.fe.build import "
        "reduced_building; "
        "print(json.dumps(reduced_building(Path({!r}), 'build_model')['stiffness_matrix']))"
    )
    published, bare = (in_own_process(reduce.format(str(path))) for path in (model, TCL_MODEL))
    np.testing.assert_allclose(published, bare, rtol=1e-9)
    assert sorted(path.name for path in tmp_path.iterdir()) == sorted(
        [TCL_MODEL.name, TCL_MODEL.stem + ".yaml"]
    )


def test_a_script_run_to_its_end_that_wipes_its_model_is_one_line(tmp_path):
    (tmp_path / TCL_MODEL.with_suffix(".yaml").name).write_text(
        TCL_MODEL.with_suffix(".yaml").read_text() + "build_until: end\n"
    )
    (tmp_path / TCL_MODEL.name).write_text(TCL_MODEL.read_text() + PUBLISHED_TAIL)
    done = model_error_in_own_process(f"build_model(Path({str(tmp_path / TCL_MODEL.name)!r}), 'build_model')")
    assert done.stdout.strip().endswith(
        "no model is left in the domain once the file has run (does it end "
        "with wipe? a Tcl script's description may say build_until: loadConst)"
    )


def test_a_missing_tcl_package_is_one_line_naming_it_and_tcllibpath(tmp_path):
    shutil.copy(TCL_MODEL.with_suffix(".yaml"), tmp_path)
    (tmp_path / TCL_MODEL.name).write_text("package require math::nosuchpackage\n" + TCL_MODEL.read_text())
    done = model_error_in_own_process(f"build_model(Path({str(tmp_path / TCL_MODEL.name)!r}), 'build_model')")
    assert "needs the Tcl package math::nosuchpackage, which OpenSees' interpreter lacks" in done.stdout, (
        done.stderr
    )
    assert "TCLLIBPATH" in done.stdout and len(done.stdout.strip().splitlines()) == 1


def test_a_wrong_but_valid_length_unit_warns_with_the_unit(tmp_path):
    """The kip-foot model read as kip-inch is 12 times too stiff per metre and its stories 0.25 m high."""
    shutil.copy(TCL_MODEL, tmp_path)
    sidecar = TCL_MODEL.with_suffix(".yaml").read_text().replace("length: ft", "length: in")
    (tmp_path / TCL_MODEL.with_suffix(".yaml").name).write_text(sidecar)
    model = tmp_path / TCL_MODEL.name
    done = subprocess.run(
        [
            sys.executable,
            "-c",
            "from pathlib import Path; from rlcontroller.physics.fe.build import "
            "reduced_building; "
            f"reduced_building(Path({str(model)!r}), 'build_model')",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    assert (
        f"warning: {model}: story heights 0.25 to 0.25 m, read in in (units.length), are outside 1.5 to 12 m"
        in (done.stderr)
    )


def test_a_pushover_given_a_system_opensees_does_not_take_is_one_line(tmp_path):
    shutil.copy(TCL_MODEL, tmp_path)
    sidecar = TCL_MODEL.with_suffix(".yaml").read_text() + "system: [NoSuchSolver]\n"
    (tmp_path / TCL_MODEL.with_suffix(".yaml").name).write_text(sidecar)
    model = tmp_path / TCL_MODEL.name
    call = f"pushover(Path({str(model)!r}), 'build_model', np.eye(5) * 1e5, np.eye(5) * 1e8)"
    done = model_error_in_own_process(call)
    assert done.stdout.strip() == f"{model}: system ['NoSuchSolver']: OpenSees does not take it", done.stderr


@pytest.mark.slow
def test_a_tcl_plant_in_kip_and_foot_moves_as_rlc_integrates_the_building(records):
    """The ground (m/s^2 -> ft/s^2), the actuators' forces (N -> kip) and the floors' response (ft -> m):
    under a record and held pushes, the Tcl plant's drifts and absolute accelerations are those of rlc's exact
    integration of the paper's building (a wrong unit or sign is tens of per cent)."""
    errors = in_own_process(
        "import json, numpy as np\n"
        "from rlcontroller import api\n"
        "from rlcontroller.control.controllers import ConstantCommand\n"
        "from rlcontroller.physics.plant import Plant\n"
        "from rlcontroller.physics.motions.records import load_records\n"
        "from rlcontroller.simulation.rollout import batch_rollout\n"
        f"plant = Plant(api.load({str(TCL_EXPERIMENT)!r}).model_copy(update={{'supervisor': None}}))\n"
        f"motion = load_records({str(records)!r})[0][3]\n"
        "push = ConstantCommand(np.array([0.5, -0.3, 0.2, 0.0, 1.0]), 5, 'push')\n"
        "((fe, _),) = batch_rollout(plant, [motion], [push])[0]\n"
        "((exact, _),) = batch_rollout(plant.design, [motion], [push])[0]\n"
        "peak = lambda run, q: np.abs(getattr(run, q)).max(axis=0)\n"
        "rms = lambda a, b: np.sqrt(np.mean((a - b) ** 2) / np.mean(b**2))\n"
        "print(json.dumps({q: [float(np.max(np.abs(peak(fe, q) / peak(exact, q) - 1.0))),\n"
        "                      float(rms(getattr(fe, q), getattr(exact, q))), float(peak(exact, q).max())]\n"
        "                  for q in ('drift', 'absolute_acceleration')}))"
    )
    for quantity, (peak_error, rms_error, peak) in errors.items():
        assert peak > (1e-2 if quantity == "drift" else 1.0), quantity  # it moves (m, m/s^2)
        assert peak_error <= 1e-3, quantity  # peaks as the Python model's (test_opensees_plant.py)
        # Newmark's period error, 2.5 ms
        assert rms_error <= (2e-3 if quantity == "drift" else 5e-3), quantity


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (None, "five_story_shear_kip_ft.tcl: a Tcl model needs five_story_shear_kip_ft.yaml beside it"),
        ("units: {length: furlong, force: kip}", "units: expected length in m, cm, mm, ft, in and force in"),
        ("floors: [[1], [2], [3], [4], [9]]", "floors: floor 5 names node 9, which the model does not have"),
        ("tcl: node 1 oops", "Tcl error: expected"),
        ("tcl: exit", "the model calls exit (line 27), which would end rlc: remove it"),
        (
            "direction: x",
            "direction: expected the lateral degree of freedom as a number, 1 (x), 2 (y) or 3 (z)",
        ),
        (
            "rayleigh: [0.0145]",
            "rayleigh: expected [a0, a1], two coefficients >= 0 of C = a0 M + a1 K, got [0.0145]",
        ),
        (
            "floors: [[1], [2], [3], [4], [1.5]]",
            "floors: floor 5: expected node tags (whole numbers), got [1.5]",
        ),
        ("floors: [[1], [2], [3], [4], [4]]", "floors: node 4 is named twice (floor 4 and floor 5)"),
        ("floors: [[0], [2], [3], [4], [5]]", "floors: floor 1 (nodes [0]) has no mass in direction 1"),
        (
            "rayleigh: null\nrayleigh_modes: [[1, 0.02], [9, 0.02]]",
            "rayleigh_modes: mode 9: a model of 5 floors has 5",
        ),
        (
            "story_heights: [3, 3, 3, 3]",
            "story_heights: expected one positive height per floor (5), got [3.0, 3.0",
        ),
    ],
)
def test_what_a_tcl_model_lacks_or_gets_wrong_is_one_line_naming_the_file(tmp_path, change, message):
    shutil.copy(TCL_MODEL, tmp_path)
    sidecar = TCL_MODEL.with_suffix(".yaml").read_text()
    if change is not None and change.startswith("tcl: "):
        (tmp_path / TCL_MODEL.name).write_text(TCL_MODEL.read_text() + change[5:] + "\n")
    elif change is not None:
        key = change.split(":")[0]
        sidecar = "\n".join(change if line.startswith(f"{key}:") else line for line in sidecar.splitlines())
    if change is not None:
        (tmp_path / TCL_MODEL.with_suffix(".yaml").name).write_text(sidecar)
    experiment = tmp_path / "five_story_tcl.yaml"
    experiment.write_text(
        TCL_EXPERIMENT.read_text()
        .replace("../../configs/opensees/five_story_shear_kip_ft.tcl", str(tmp_path / TCL_MODEL.name))
        .replace("../../configs/", f"{REPOSITORY}/configs/")
    )
    done = subprocess.run(
        [sys.executable, "-m", "rlcontroller", "info", str(experiment)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    lines = done.stderr.strip().splitlines()
    assert done.returncode != 0 and len(lines) == 1 and message in lines[0], done.stderr
    assert str(tmp_path / TCL_MODEL.name.replace(".tcl", "")) in lines[0]
    if change == "tcl: node 1 oops":
        line = len(TCL_MODEL.read_text().splitlines()) + 1
        assert f'"node 1 oops" (file "five_story_shear_kip_ft.tcl" line {line})' in lines[0]


@pytest.mark.skipif(NO_SYSTEM_BLAS, reason=OPENSEES_MISSING)
def test_a_process_that_ran_a_python_model_refuses_a_tcl_one_in_one_line():
    """The two OpenSees builds abort a process that steps both: the second is refused before it loads."""
    outcome = in_own_process(
        "import json; from pathlib import Path; from rlcontroller.errors import ConfigError\n"
        "from rlcontroller.physics.fe.build import reduced_building\n"
        f"reduced_building(Path({str(REPOSITORY / 'configs' / 'opensees' / 'five_story_shear.py')!r}), "
        f"'build_model')\ntry: reduced_building(Path({str(TCL_MODEL)!r}), 'build_model')\n"
        "except ConfigError as error: print(json.dumps({'error': str(error)}))"
    )
    assert outcome["error"].startswith(
        "this process already ran an OpenSeesPy (Python) model: OpenSeesPy and"
    )


NEVER_HELD_TAIL = """
pattern Plain 1 Linear { load 5 1.0 } ;# a lateral load of 1 kip, applied by a static analysis, never held
constraints Plain; numberer RCM; system BandGeneral; test NormDispIncr 1e-8 10; algorithm Newton
integrator LoadControl 0.1; analysis Static; analyze 10
"""


def test_a_script_that_never_holds_its_loads_has_them_held_where_they_stand_and_is_told(tmp_path):
    """A script that applies a load with a Linear pattern and never calls loadConst: rlc holds it (loadConst
    -time 0.0) and says so in one line; through 4 s of motion the roof stays where the held load put it (a
    Linear pattern left on would push it 1 kip more each second: about 0.5 mm a second on this building)."""
    shutil.copy(TCL_MODEL.with_suffix(".yaml"), tmp_path)
    model = tmp_path / TCL_MODEL.name
    model.write_text(TCL_MODEL.read_text() + NEVER_HELD_TAIL)
    code = (
        "import json, numpy as np\n"
        "from pathlib import Path\n"
        "from rlcontroller.physics.fe.build import reduced_building\n"
        "from rlcontroller.physics.fe.integrator import OpenSeesIntegrator\n"
        f"path = Path({str(model)!r})\n"
        "reduced_building(path, 'build_model')\n"
        "plant = OpenSeesIntegrator(path, 'build_model', 0.005, np.zeros((5, 1)), np.ones(1))\n"
        "state, roof = np.zeros(15), []\n"
        "for _ in range(200):\n"
        "    state = plant.step(state, np.zeros(1), np.zeros(2), 0.02)\n"
        "    roof.append(state[4])\n"
        "print(json.dumps([min(roof), max(roof)]))"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=300, cwd=REPOSITORY
    )
    assert done.returncode == 0, done.stderr[-2000:]
    low, high = json.loads(done.stdout.strip().splitlines()[-1])
    assert high - low < 1e-6  # m: held, not growing (25 mm more over the 4 s were it left on)
    notes = [line for line in done.stderr.splitlines() if "never holds its loads" in line]
    assert len(notes) == 1 and "loadConst -time 0.0" in notes[0]
