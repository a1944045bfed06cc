"""Diagnostic: does the field's classical answer for an experiment's devices pass the safety check?

Usage: python studies/devices/check_classical.py CONFIG [--standard STANDARD.yaml]

Runs the safety check's suite and at-rest criteria (`rlc check`'s own code, `evaluation.safety`) on
every classical controller of the experiment (`classical_controllers`: the LQGs for actuators and
active mass drivers, passive-off, passive-on and clipped-optimal for semi-active dampers; with active
mass drivers also the drivers without a command, the tuned masses they are), on the experiment's
plant, and prints each verdict in one line per criterion. A learned controller that fails
where every classical one fails too is held to a bound the device cannot meet; docs/devices.md says
which.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from rlcontroller.config import ConfigError, load_experiment
from rlcontroller.config.scenarios import load_safety_check, safety_standard
from rlcontroller.control.controllers import ConstantCommand
from rlcontroller.evaluation.evaluation import classical_controllers
from rlcontroller.evaluation.safety import Verdict, safety_check
from rlcontroller.physics.plant import Plant


def classical_verdicts(config: Path, standard: Path | None = None) -> list[Verdict]:
    """The safety-check verdict of each classical controller of the experiment in `config`, under `standard`
    (default: the project's for the experiment, `configs/checks/standard.yaml` or under wind `wind.yaml`)."""
    plant = Plant(load_experiment(config))
    check = load_safety_check(standard or safety_standard(plant.experiment))
    controllers = classical_controllers(plant)
    if plant.building.devices and not plant.building.dampers:  # active mass drivers: the passive masses too
        controllers.append(ConstantCommand(0.0, plant.building.n_actuators, "drivers off (tuned masses)"))
    return [safety_check(plant, controller, check, scenarios=[]) for controller in controllers]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("config", type=Path, help="an experiment YAML")
    parser.add_argument(
        "--standard", type=Path, default=None, help="default: the experiment's (ground or wind)"
    )
    arguments = parser.parse_args()
    try:
        verdicts = classical_verdicts(arguments.config, arguments.standard)
    except ConfigError as error:
        sys.exit(f"error: {error}")
    for verdict in verdicts:
        print("\n".join(verdict.lines()))


if __name__ == "__main__":
    main()
