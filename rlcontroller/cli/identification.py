"""Commands for a building known from measurements or from its FE model: `rlc simulate-test`, `rlc identify`
and `rlc reduce`."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rlcontroller.cli.app import Printed, app, user_errors
from rlcontroller.errors import ConfigError


def parsed_list(text: str | None, option: str) -> list[float] | None:
    """'25e3, 20e3' as numbers; anything else a one-line error naming the option."""
    if text is None:
        return None
    try:
        return [float(value) for value in text.split(",")]
    except ValueError:
        raise ConfigError(f"{option} {text!r}: expected comma-separated numbers") from None


@app.command("simulate-test", short_help="A vibration test on an experiment's plant, recorded as a CSV.")
@user_errors
def simulate_test(
    *,
    config: Annotated[
        Path, typer.Argument(help="Experiment YAML whose plant is tested (its plant part included).")
    ],
    out: Annotated[Path, typer.Option(help="New recording CSV; never overwritten.")],
    duration: Annotated[float, typer.Option(help="Length of an ambient test (s).")] = 600.0,
    ambient_rms: Annotated[float, typer.Option(help="RMS of the ambient white-noise ground (m/s^2).")] = 0.1,
    record: Annotated[
        Path | None, typer.Option(help="A ground-motion file to test with instead of ambient.")
    ] = None,
    shake: Annotated[
        float,
        typer.Option(
            help="RMS of each actuator's white-noise force, a fraction of its force limit (0: none)."
        ),
    ] = 0.05,
    seed: Annotated[int, typer.Option(help="Fixes the ground, the shaking and the sensor noise.")] = 0,
) -> None:
    """Run a vibration test on the experiment's simulated plant and record it as its sensors would (floor
    absolute accelerations and the ground with their noise, the actuators' forces): the input of `rlc
    identify`, so the whole loop from measurements to a controller can be run and checked."""
    from rlcontroller import api

    api.simulate_test(
        config,
        out,
        duration=duration,
        ambient_rms=ambient_rms,
        record=record,
        shake=shake,
        seed=seed,
        report=Printed(),
    )


@app.command(short_help="A building's state-space model from its test recordings.")
@user_errors
def identify(
    *,
    recordings: Annotated[
        list[Path], typer.Argument(help="Recording CSVs of one set of sensors (rlc simulate-test).")
    ],
    out: Annotated[Path, typer.Option(help="New folder for building.yaml, model.npz and identification.md.")],
    modes: Annotated[int | None, typer.Option(help="Modes to identify (default: one per floor).")] = None,
    band: Annotated[
        float, typer.Option(help="The modes' band (Hz): the recordings are decimated to 2.5 times it.")
    ] = 20.0,
    masses: Annotated[
        str | None, typer.Option(help="Floor masses (kg, floor 1 first, comma-separated): story shears too.")
    ] = None,
) -> None:
    """Identify the building's state-space model (N4SID: the ground and actuator forces in, the floors'
    accelerations out), print its modes with their standard errors, and write it as a building part that
    rlc train, compare lqg and evaluate accept (building: FOLDER/building.yaml)."""
    from rlcontroller import api

    api.identify(
        recordings, out, modes=modes, band=band, masses=parsed_list(masses, "--masses"), report=Printed()
    )


@app.command(short_help="A nonlinear reduced model of an FE plant, calibrated from it.")
@user_errors
def reduce(
    config: Annotated[
        Path, typer.Argument(help="Experiment YAML with an FE plant (plant.opensees; its model runs).")
    ],
    out: Annotated[Path, typer.Option(help="New folder for config.yaml, accuracy.csv and calibration.md.")],
    fit: Annotated[int, typer.Option(help="Generated strong motions the FE model runs to fit.")] = 8,
    test: Annotated[int, typer.Option(help="Other motions the fit is judged on.")] = 8,
) -> None:
    """Run the FE model on generated motions strong enough to yield it, fit two reduced models on its
    condensed stiffness to its drift histories (Bouc-Wen story springs; a fishbone: a column line whose
    floors' beams yield), keep the one with the lower cost there, and print per story how well both hold on
    other motions beside the linear reduced model. config.yaml is the experiment with the kept model as its
    plant: train on it in seconds where the FE model takes hours (docs/opensees.md)."""
    from rlcontroller import api

    api.reduce(config, out, fit_motions=fit, test_motions=test, report=Printed())
