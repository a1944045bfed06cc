"""Fuzzed input files for the surfaces added with devices, wind, matrix buildings, scenarios and
plant randomisation: every leaf value of a valid file replaced by each of a set of bad values. Each
case must end either in success or in one line naming the file, with exit code 2 — never a
traceback, a hang or a half-written output folder. The expected messages of the hand-written cases
are in test_bad_input.py; this checks the property on every combination."""

import copy
import signal
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from rlcontroller.cli import app

BAD_VALUES = ("-1", "0", ".inf", "-.inf", ".nan", "1.0e+300", "'text'", "[]", "{}", "null", "[1, [2]]")

BASES = {
    "mr": {
        "actuators": [],
        "devices": [{"type": "mr_damper", "story": 1, "capacity": 1.0e5, "max_voltage": 2.25}],
        "sensors": {"measurements": [{"quantity": "force", "scale": 1.0e5, "noise_std": 100.0}]},
    },
    "variable_damper": {
        "actuators": [],
        "devices": [
            {
                "type": "variable_damper",
                "story": 2,
                "damping_min": 0.0,
                "damping_max": 1.0e6,
                "capacity": 1.0e5,
            }
        ],
    },
    "amd": {
        "devices": [
            {
                "type": "active_mass",
                "floor": 5,
                "mode": 1,
                "mass_ratio": 0.02,
                "force_limit": 1.0e4,
                "stroke_limit": 1.0,
            }
        ],
        "sensors": {"measurements": [{"quantity": "stroke", "scale": 1.0, "noise_std": 0.001}]},
    },
    "tmd": {
        "devices": [
            {"type": "tuned_mass", "floor": 3, "mode": 2, "mass_ratio": 0.05, "frequency_ratio": 0.97}
        ]
    },
    "wind_generator": {
        "excitation": {
            "generator": {
                "kind": "wind",
                "dt": 0.02,
                "duration": [5.0, 8.0],
                "speed": [10.0, 30.0],
                "reference_height": 10.0,
                "roughness": 0.3,
                "drag_coefficient": 1.3,
                "width": 20.0,
                "cutoff": 5.0,
            },
            "validation_motions": 2,
        }
    },
    "randomisation": {
        "plant_randomization": {
            "stiffness": {"low": 0.8, "high": 1.2},
            "mass": {"low": 0.9, "high": 1.1, "log": True},
            "damping": {"low": 0.5, "high": 2.0},
            "noise_factor": {"low": 1.0, "high": 3.0},
        }
    },
    "plant": {
        "plant": {
            "stiffness": 0.9,
            "mass": 1.1,
            "damping": 0.8,
            "damage": [{"story": 2, "stiffness": -0.3}],
            "actuators": {"time_constant": 0.02, "delay_steps": 1},
            "sensors": {"noise_factor": 2.0, "dead_floors": [3], "bias": [{"floor": 2, "value": 0.01}]},
        }
    },
}


def leaves(tree, path=()):
    """Every (path, value) of a nested mapping/list whose value is a number, text or boolean."""
    if isinstance(tree, dict):
        for key, value in tree.items():
            yield from leaves(value, (*path, key))
    elif isinstance(tree, list):
        for index, value in enumerate(tree):
            yield from leaves(value, (*path, index))
    else:
        yield path, tree


def replaced(tree, path, text):
    tree = copy.deepcopy(tree)
    node = tree
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = yaml.safe_load(text)
    return tree


CASES = [
    (f"{name}:{'.'.join(map(str, path))}={bad}", name, path, bad)
    for name, base in BASES.items()
    for path, value in leaves(base)
    if not (isinstance(value, str) and path[-1] in ("type", "kind", "quantity"))
    for bad in BAD_VALUES
]


class Hang(Exception):
    pass


def _alarm(signum, frame):
    raise Hang


@pytest.mark.slow
@pytest.mark.parametrize(("name", "path", "bad"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_a_fuzzed_experiment_part_is_accepted_or_refused_in_one_line(tmp_path, name, path, bad):
    config = tmp_path / "experiment.yaml"
    config.write_text(yaml.safe_dump(replaced(BASES[name], path, bad)))
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(60)
    try:
        result = CliRunner().invoke(app, ["info", str(config)])
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    assert "Traceback" not in result.output
    if result.exit_code == 0:
        return
    assert result.exit_code == 2 and isinstance(result.exception, SystemExit), result.output
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {config}"), result.output


def test_the_fuzzer_covers_at_least_150_cases_and_most_are_refused():
    assert len(CASES) >= 150


MATRIX_BAD = {
    "nan": lambda m: np.where(np.eye(len(m), dtype=bool) & (np.arange(len(m))[:, None] == 1), np.nan, m),
    "inf": lambda m: m + np.diag([np.inf] + [0.0] * (len(m) - 1)),
    "negative_diagonal": lambda m: m - 2.0 * np.diag(np.diag(m)),
    "asymmetric": lambda m: m + np.triu(np.ones_like(m), 1) * 1e3,
    "one_row_short": lambda m: m[:-1],
    "wrong_size": lambda m: m[:-1, :-1],
    "zeros": lambda m: np.zeros_like(m),
    "huge": lambda m: m * 1e300,
    "one_dimensional": lambda m: np.diag(m),
    "complex": lambda m: m.astype(complex) * 1j,
    "text": lambda m: np.array([["a"] * len(m)] * len(m)),
    "empty": lambda m: np.zeros((0, 0)),
}


@pytest.mark.slow
@pytest.mark.parametrize("array", ["M", "K", "C"])
@pytest.mark.parametrize("change", list(MATRIX_BAD))
def test_a_fuzzed_matrix_file_is_refused_in_one_line(tmp_path, array, change):
    n = 5
    mass = np.diag(np.full(n, 20.0))
    stiffness = 4e4 * (2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1))
    stiffness[-1, -1] = 4e4
    arrays = {"M": mass, "K": stiffness, "C": 0.01 * stiffness}
    arrays[array] = MATRIX_BAD[change](arrays[array])
    np.savez(tmp_path / "building.npz", **arrays)
    building = {"matrices": "building.npz", "units": {"mass": "t", "force": "kN", "length": "m"}}
    (tmp_path / "experiment.yaml").write_text(yaml.safe_dump({"building": building}))
    result = CliRunner().invoke(app, ["info", str(tmp_path / "experiment.yaml")])
    assert "Traceback" not in result.output and result.exit_code == 2, result.output
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.output
    assert "building" in lines[0], lines[0]


WIND_SUITE = {
    "kind": "wind",
    "speeds": [20.0],
    "records_per_speed": 1,
    "duration": 10.0,
    "dt": 0.1,
    "cutoff": 1.0,
}
WIND_CASES = [
    (f"{key}={bad}", key, bad)
    for key in ("speeds", "records_per_speed", "duration", "dt", "cutoff", "roughness", "width", "seed")
    for bad in BAD_VALUES
]


@pytest.mark.slow
@pytest.mark.parametrize(("key", "bad"), [c[1:] for c in WIND_CASES], ids=[c[0] for c in WIND_CASES])
def test_a_fuzzed_wind_suite_is_accepted_or_refused_in_one_line(tmp_path, key, bad):
    suite = dict(WIND_SUITE) | {key: yaml.safe_load(bad)}
    (tmp_path / "wind.yaml").write_text(yaml.safe_dump(suite))
    out = tmp_path / "out"
    smoke = Path(__file__).resolve().parents[1] / "configs" / "testing" / "smoke.yaml"
    arguments = [
        "compare",
        "lqg",
        "--config",
        str(smoke),
        "--records",
        str(tmp_path / "wind.yaml"),
        "--out",
        str(out),
    ]
    result = CliRunner().invoke(app, arguments)
    assert "Traceback" not in result.output
    if result.exit_code == 0:
        assert (out / "metrics.csv").is_file()
        return
    assert result.exit_code == 2 and isinstance(result.exception, SystemExit), result.output
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "wind.yaml" in lines[0], result.output
    assert not out.exists()


def _policy_cases():
    from conftest import MPC_POLICY, NETWORK_POLICY

    cases = []
    for folder in (NETWORK_POLICY, MPC_POLICY):  # a learned file, a classical one (MPC: its own section too)
        description = yaml.safe_load((folder / "best_policy.yaml").read_text())
        for path, _ in leaves(description):
            cases += [
                (f"{folder.name}:{'.'.join(map(str, path))}={bad}", folder, path, bad) for bad in BAD_VALUES
            ]
    return cases


POLICY_CASES = _policy_cases()


@pytest.mark.slow
@pytest.mark.parametrize(
    ("folder", "path", "bad"), [c[1:] for c in POLICY_CASES], ids=[c[0] for c in POLICY_CASES]
)
def test_a_fuzzed_controller_file_is_read_or_refused_naming_it(tmp_path, folder, path, bad):
    """A controller file from someone else: any field changed, it is read as data or refused with a
    `ConfigError` naming the file (a one-line error at the command line) — never another exception."""
    import shutil

    from rlcontroller.config import ConfigError, load_experiment
    from rlcontroller.control.policy_file import read_policy
    from rlcontroller.physics.plant import Plant

    copy_ = tmp_path / "model"
    shutil.copytree(folder, copy_)
    description = yaml.safe_load((copy_ / "best_policy.yaml").read_text())
    (copy_ / "best_policy.yaml").write_text(yaml.safe_dump(replaced(description, path, bad)))
    plant = Plant(load_experiment(copy_ / "config.yaml", self_contained=True))
    try:
        controller = read_policy(copy_, "best", plant)
    except ConfigError as error:
        assert str(error).startswith(str(copy_)) and "\n" not in str(error)
        return
    action = controller.act(np.zeros(plant.layout.size))
    assert np.all(np.isfinite(action)) and np.all(np.abs(action) <= 1.0)


@pytest.mark.slow
@pytest.mark.parametrize("fraction", [0.0, 0.01, 0.1, 0.25, 0.5, 0.75, 0.9, 0.99])
@pytest.mark.parametrize("name", ["best_policy.npz", "best_policy.yaml"])
def test_a_truncated_controller_file_is_refused_naming_it(tmp_path, name, fraction):
    import shutil

    from conftest import NETWORK_POLICY

    from rlcontroller.config import ConfigError, load_experiment
    from rlcontroller.control.policy_file import read_policy
    from rlcontroller.physics.plant import Plant

    copy_ = tmp_path / "model"
    shutil.copytree(NETWORK_POLICY, copy_)
    content = (copy_ / name).read_bytes()
    (copy_ / name).write_bytes(content[: int(fraction * len(content))])
    plant = Plant(load_experiment(copy_ / "config.yaml", self_contained=True))
    with pytest.raises(ConfigError) as error:
        read_policy(copy_, "best", plant)
    assert str(error.value).startswith(str(copy_)) and "\n" not in str(error.value)


SCENARIOS = {
    "scenarios": [
        {"name": "nominal"},
        {"name": "softer", "plant": {"stiffness": 0.85, "mass": 1.1, "damping": 0.5}},
        {"name": "damaged", "plant": {"damage": [{"story": 1, "stiffness": -0.4}]}},
        {"name": "late", "plant": {"actuators": {"time_constant": 0.02, "delay_steps": 1}}},
        {"name": "sensors", "plant": {"sensors": {"noise_factor": 5.0, "dead_floors": [3]}}},
    ]
}
SCENARIO_CASES = [
    (f"{'.'.join(map(str, path))}={bad}", path, bad) for path, _ in leaves(SCENARIOS) for bad in BAD_VALUES
]


@pytest.mark.slow
@pytest.mark.parametrize(("path", "bad"), [c[1:] for c in SCENARIO_CASES], ids=[c[0] for c in SCENARIO_CASES])
def test_a_fuzzed_scenario_file_is_read_or_refused_naming_it(tmp_path, path, bad):
    from rlcontroller.config import ConfigError, Experiment, load_scenarios
    from rlcontroller.physics.plant import Plant

    file = tmp_path / "scenarios.yaml"
    file.write_text(yaml.safe_dump(replaced(SCENARIOS, path, bad)))
    experiment = Experiment()
    try:
        scenarios = load_scenarios(file, experiment)
    except ConfigError as error:
        assert str(error).startswith(str(file)) and "\n" not in str(error)
        return
    for scenario in scenarios:  # accepted: every plant can be built
        Plant(experiment.model_copy(update={"plant": scenario.plant}))


SEARCH = {
    "algorithm.kwargs.learning_rate": {"low": 1.0e-5, "high": 1.0e-3, "log": True},
    "algorithm.kwargs.n_steps": {"choices": [128, 256]},
    "algorithm.kwargs.n_epochs": {"low": 1, "high": 5, "integer": True},
}
SEARCH_CASES = [(f"{'.'.join(map(str, p))}={bad}", p, bad) for p, _ in leaves(SEARCH) for bad in BAD_VALUES]


@pytest.mark.slow
@pytest.mark.parametrize(("path", "bad"), [c[1:] for c in SEARCH_CASES], ids=[c[0] for c in SEARCH_CASES])
def test_a_fuzzed_search_space_is_accepted_or_refused_in_one_line(tmp_path, path, bad):
    base = {"algorithm": {"name": "PPO", "search": SEARCH}}
    config = tmp_path / "experiment.yaml"
    config.write_text(yaml.safe_dump(replaced(base, ("algorithm", "search", *path), bad)))
    result = CliRunner().invoke(app, ["info", str(config)])
    assert "Traceback" not in result.output
    if result.exit_code != 0:
        lines = result.output.strip().splitlines()
        assert result.exit_code == 2 and len(lines) == 1 and lines[0].startswith(f"error: {config}"), (
            result.output
        )


SET_VALUES = (
    *("", "=", "x=", "=1", "algorithm.kwargs.gamma=", "algorithm.kwargs.gamma=.nan", "seed=-1", "seed=3"),
    *("algorithm.kwargs.gamma=[1,", "nothing.here=1", "algorithm.total_steps=0", "building.masses=[1]"),
    *("algorithm.kwargs.gamma=0.9,,0.99", "simulation.control_dt=1e300", "name=../../x", "algorithm=7"),
)


@pytest.mark.parametrize("text", SET_VALUES)
def test_a_bad_sweep_setting_is_refused_before_any_run(tmp_path, text):
    from rlcontroller.config import ConfigError, Experiment
    from rlcontroller.multirun.sweep import parse_setting, plan

    with pytest.raises(ConfigError) as error:
        plan(Experiment(), [0], [parse_setting(text)], tmp_path / "out")
    assert "\n" not in str(error.value) and not (tmp_path / "out").exists()


AGGREGATE_FILES = {
    "empty": "",
    "header_only": "controller,record,metric,index,value\n",
    "missing_column": "controller,record,metric,value\nRL,a,J1,0.5\n",
    "text_value": "controller,record,metric,index,value\nRL,a,J1,1,abc\n",
    "nan_value": "controller,record,metric,index,value\nRL,a,J1,1,nan\n",
    "binary": "\x00\x01\x02",
    "ragged": "controller,record,metric,index,value\nRL,a,J1\n",
}


@pytest.mark.parametrize("name", list(AGGREGATE_FILES))
def test_a_damaged_metrics_file_stops_aggregate_in_one_line(tmp_path, name):
    (tmp_path / "run" / "evaluation").mkdir(parents=True)
    (tmp_path / "run" / "evaluation" / "metrics.csv").write_text(AGGREGATE_FILES[name])
    out = tmp_path / "out"
    result = CliRunner().invoke(app, ["aggregate", str(tmp_path / "run"), "--out", str(out)])
    lines = result.output.strip().splitlines()
    assert result.exit_code == 2 and "Traceback" not in result.output, result.output
    assert len(lines) == 1 and lines[0].startswith("error: ") and "metrics.csv" in lines[0], result.output
    assert not out.exists()


def _npy(shape: str, descr: str = "<f8", body: bytes = b"") -> bytes:
    """A version-1 .npy member whose header declares `shape` of `descr`, followed by `body`."""
    header = f"{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}"
    header += " " * (117 - len(header)) + "\n"
    return b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header.encode() + body


def _members(folder):
    import zipfile

    with zipfile.ZipFile(folder / "best_policy.npz") as archive:
        return {name: archive.read(name) for name in archive.namelist()}


POLICY_DAMAGE = {
    # a 200-byte file whose header declares 745 GiB: refused from the header, nothing allocated
    "a header declaring 10^11 values": (
        "npz",
        {"layer0_weight.npy": _npy("(100000000000,)")},
        "header declares",
    ),
    "an array of another shape": (
        "npz",
        {"layer0_weight.npy": _npy("(5, 56)", "<f4", bytes(5 * 56 * 4))},
        r"layer0_weight is \(5, 56\) of float32, the policy declares \(5, 57\)",
    ),
    "integer weights": ("npz", {"layer0_bias.npy": _npy("(5,)", "<i8", bytes(40))}, "floating-point"),
    "an object array": ("npz", {"layer0_bias.npy": _npy("(5,)", "|O", bytes(40))}, "expected numbers"),
    "an unknown array": ("npz", {"extra.npy": _npy("(3,)", "<f8", bytes(24))}, "unknown array extra"),
    "a member that is no array": ("npz", {"notes.txt": b"hello"}, "notes.txt: not an array"),
    "an unknown key": ("yaml", "bogus_key: 1\n", "unknown key bogus_key"),
    "an unknown network key": ("yaml", None, "unknown key network.width"),
    "an anchor and an alias": (
        "yaml",
        "extra: &big [1, 2]\nmore: *big\n",
        "anchors and aliases are not accepted",
    ),
}


@pytest.mark.parametrize("case", list(POLICY_DAMAGE))
def test_a_controller_file_is_checked_before_its_data_is_read(tmp_path, case):
    """The policy YAML is read with no anchors, aliases or unknown keys; each array's shape and dtype come
    from its .npy header and must be what the YAML declares before any data is read."""
    import shutil
    import zipfile

    from conftest import REPOSITORY

    from rlcontroller.config import ConfigError, load_experiment
    from rlcontroller.control.policy_file import read_policy
    from rlcontroller.physics.plant import Plant

    folder = tmp_path / "model"
    shutil.copytree(REPOSITORY / "models" / "five_story_every_story", folder)
    kind, change, message = POLICY_DAMAGE[case]
    if kind == "npz":
        members = _members(folder) | change
        with zipfile.ZipFile(folder / "best_policy.npz", "w") as archive:
            for name, data in members.items():
                archive.writestr(name, data)
    elif change is None:
        text = (folder / "best_policy.yaml").read_text()
        (folder / "best_policy.yaml").write_text(text.replace("network:\n", "network:\n  width: 64\n"))
    else:
        (folder / "best_policy.yaml").write_text((folder / "best_policy.yaml").read_text() + change)
    plant = Plant(load_experiment(folder / "config.yaml", self_contained=True))
    with pytest.raises(ConfigError, match=message) as error:
        read_policy(folder, "best", plant)
    assert str(error.value).startswith(str(folder)) and "\n" not in str(error.value)
