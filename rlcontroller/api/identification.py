"""Buildings known from measurements: `simulate_test` (a vibration test run on an experiment's simulated
plant, recorded as its sensors would) and `identify` (a building's state-space model from such recordings,
written as a building part)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from rlcontroller.api.common import QUIET, Report, load
from rlcontroller.bounds import MAX_MASS
from rlcontroller.config import ConfigError, display_path
from rlcontroller.files import atomic_write, check_new_folder, new_folder


def simulate_test(
    config: Path,
    out: Path,
    *,
    duration: float = 600.0,
    ambient_rms: float = 0.1,
    record: Path | None = None,
    shake: float = 0.05,
    seed: int = 0,
    report: Report = QUIET,
) -> Path:
    """A test of `duration` s on the plant of the experiment `config`: white-noise ground of `ambient_rms`
    (m/s^2), or the ground motion `record`; with `shake` > 0 every actuator driven by white noise of that RMS
    (a fraction of its force limit). Written as a recording CSV to the new file `out`. Returns `out`."""
    from rlcontroller.identification.recording import ambient_ground, simulate_test
    from rlcontroller.physics.motions.excitation import read_motion
    from rlcontroller.physics.plant import Plant

    if out.exists():
        raise ConfigError(f"--out {out}: exists; a recording is never overwritten (choose another --out)")
    if not 0.0 <= shake <= 1.0:
        raise ConfigError(f"--shake {shake:g}: expected a fraction of the force limits in [0, 1]")
    experiment = load(config)
    plant = Plant(experiment.model_copy(update={"supervisor": None}))  # shakers drive the actuators directly
    if record is not None:
        ground, what = read_motion(record), f"the record {record}"
    else:
        if not (0.0 < ambient_rms <= 10.0 and 0.0 < duration <= 36000.0):
            raise ConfigError("--ambient-rms in (0, 10] m/s^2 and --duration in (0, 36000] s, expected")
        ground = ambient_ground(ambient_rms, duration, plant.control_dt, seed)
        what = f"ambient white-noise ground of {ambient_rms:g} m/s^2 RMS"
    recording = simulate_test(plant, ground, duration=shake, ambient_rms=seed)
    shaking = (
        f"actuators shaking at {shake:g} of their force limits (RMS)" if shake > 0 else "actuators at rest"
    )
    comment = (
        f"rlc simulate-test {config} (seed {seed}): {what}, {recording.duration:g} s, {shaking}; sensors as "
        f"the experiment's (noise on); sampled every {recording.dt:g} s; SI units"
    )
    atomic_write(out, recording.to_csv(comment))
    report.line(f"wrote {out}: {recording.duration:g} s, {len(recording.floors)} floors, {shaking}")
    return out


def identify(
    recordings: list[Path],
    out: Path,
    *,
    modes: int | None = None,
    band: float = 20.0,
    masses: list[float] | None = None,
    report: Report = QUIET,
) -> Path:
    """The state-space model of `modes` modes (default: one per floor) below `band` Hz identified from the
    `recordings` (one set of sensors), written to the new folder `out` as a building part (building.yaml with
    model.npz) and its report (identification.md: the modes with their standard errors). With the floor
    `masses` (kg, floor 1 first: from drawings) the model also gives story shears. Returns `out`."""
    from rlcontroller.identification.recording import read_recording
    from rlcontroller.identification.subspace import identify as identify_model
    from rlcontroller.physics.state_space import state_space_outputs

    check_new_folder(out, "identification")
    if not 0.0 < band <= 1000.0:
        raise ConfigError(f"--band {band:g}: expected a frequency in (0, 1000] Hz")
    tests = [read_recording(path) for path in recordings]
    floors = len(tests[0].floors)
    asked = floors if modes is None else modes
    if not 1 <= asked <= 2 * floors:
        raise ConfigError(f"--modes {asked}: expected 1..{2 * floors} for {floors} floors")
    if masses is not None and (len(masses) != floors or not all(0.0 < m <= MAX_MASS for m in masses)):
        raise ConfigError(f"--masses: expected {floors} floor masses in (0, {MAX_MASS:g}] kg, floor 1 first")
    identified = identify_model(
        tests, asked, band, None if masses is None else np.asarray(masses, dtype=float)
    )
    actuators = list(tests[0].actuators)
    part = {
        "name": f"identified from {', '.join(path.name for path in recordings)}",
        "state_space": "model.npz",
        "state": "physical" if identified.physical else "abstract",
        "inputs": {"actuators": list(range(len(actuators))), "ground": len(actuators)},
        "outputs": {  # the rows `identify` writes, story shears only with the masses
            name: rows
            for name, rows in state_space_outputs(floors).items()
            if rows[-1] < identified.arrays["C"].shape[0]
        },
    }
    header = (
        f"# Identified by rlc identify (N4SID, {asked} modes below {band:g} Hz): identification.md\n"
        f"# inputs.actuators are the forces on stories {', '.join(actuators) or '(none: an ambient test)'}, "
        "in that order: list the experiment's actuators so\n"
    )
    with new_folder(out, "identification") as staging:
        with open(staging / "model.npz", "wb") as file:
            np.savez(file, **identified.arrays)
        atomic_write(staging / "building.yaml", header + yaml.safe_dump(part, sort_keys=False))
        atomic_write(staging / "identification.md", identification_report(identified, recordings, band))
    for line in mode_lines(identified):
        report.line(line)
    report.line(f"wrote {out}: building.yaml (a building part), model.npz, identification.md")
    return out


SHEARS = {
    False: "Story shears are not identified (no floor masses given): J3 and J4 are unavailable on this "
    "model.",
    True: "Story shears are the floors' inertia forces above each story, from the floor masses given "
    "(--masses).",
}


def mode_lines(identified) -> list[str]:
    """One line per mode: frequency and damping ratio with their standard errors."""
    lines = []
    for number, mode in enumerate(identified.modes, 1):
        lines.append(
            f"mode {number}: {mode.frequency:.4f} ± {mode.frequency_error:.4f} Hz, damping "
            f"{mode.damping:.2%} ± {mode.damping_error:.2%}, shape {np.array2string(mode.shape, precision=3)}"
        )
    return lines


def identification_report(identified, recordings: list[Path], band: float) -> str:
    """identification.md: what was identified from what, the modes with their uncertainty, the fit."""
    floors = identified.explained.size
    shapes = [
        f"| {n} | {m.frequency:.4f} ± {m.frequency_error:.4f} | {m.damping:.2%} ± {m.damping_error:.2%} | "
        + " ".join(f"{v:+.3f}±{e:.3f}" for v, e in zip(m.shape, m.shape_error, strict=False))
        + " |"
        for n, m in enumerate(identified.modes, 1)
    ]
    return "\n".join(
        [
            "# Identified building model",
            "",
            f"From {', '.join(str(path) for path in recordings)}: N4SID (nfoursid) with the ground and the "
            f"actuators' forces as inputs and the {floors} floors' absolute accelerations as outputs, "
            + (
                f"low-passed and decimated by {identified.decimation} to a sample every "
                f"{identified.sample_time:g} s"
                if identified.decimation > 1
                else f"at their own sample rate (every {identified.sample_time:g} s)"
            )
            + f" (band {band:g} Hz), {identified.block_rows} block rows. "
            f"State: {'physical ([x; v])' if identified.physical else 'abstract'}; displacement, velocity "
            "and drift rows derived through the model (x = C_a A^-2 z). Standard errors from four equal "
            "segments.",
            "",
            "| mode | frequency (Hz) | damping ratio | shape (floor 1 first, largest 1) |",
            "|---|---|---|---|",
            *shapes,
            "",
            "Share of each floor's acceleration variance the model's response to the measured inputs "
            "explains: "
            + ", ".join(f"floor {i + 1} {v:.1%}" for i, v in enumerate(identified.explained))
            + ".",
            "",
            "The model's direct feed-through from the ground to the accelerations "
            f"({identified.dropped_feedthrough:.3g} at most, m/s^2 per m/s^2: the sampling's share of the "
            "ground within a step) is dropped: a structure's absolute accelerations in relative coordinates "
            "have "
            "none. " + SHEARS[identified.arrays["C"].shape[0] > 4 * floors],
            "",
        ]
    )


def reduce(
    config: Path, out: Path, *, fit_motions: int = 8, test_motions: int = 8, report: Report = QUIET
) -> Path:
    """The nonlinear reduced model of the FE plant of the experiment `config`: its design model's stories made
    Bouc-Wen springs, or its floors' beams yielding hinges on a column line (a fishbone), whichever fits the
    FE model's own responses on `fit_motions` generated strong motions better, judged on `test_motions` others
    (`identification.reduction`). Written to the new folder `out`: config.yaml (the experiment with the
    reduced model as its plant: rlc train, evaluate and check take it), accuracy.csv (per story, the median
    errors of peak and residual drift of both models and the linear reduced model) and calibration.md. Returns
    `out`."""
    from rlcontroller.identification.reduction import MODELS, calibrate, nonlinear_reduced_experiment
    from rlcontroller.physics.plant import Plant

    check_new_folder(out, "reduced model")
    if not (1 <= fit_motions <= 200 and 1 <= test_motions <= 200):
        raise ConfigError(f"--fit {fit_motions}, --test {test_motions}: expected 1..200 motions each")
    experiment = load(config)
    if experiment.plant is None or experiment.plant.opensees is None:
        raise ConfigError(
            f"{config}: plant.opensees: expected an FE plant to calibrate a nonlinear reduced model from"
        )
    plant = Plant(experiment)
    calibration = calibrate(plant, fit_motions, test_motions, on_progress=report.line)
    reduced = nonlinear_reduced_experiment(plant, calibration.hysteresis)
    model = display_path(Path(experiment.plant.opensees.model))
    # the matrices' file, as the user sees it
    building = reduced.building.model_copy(update={"source": model})
    reduced = reduced.model_copy(update={"building": building})
    header = (
        f"# The nonlinear reduced model of {model}, {MODELS[calibration.chosen]}, calibrated by rlc reduce "
        f"({fit_motions} motions fitted, {test_motions} judged): calibration.md\n"
    )
    with new_folder(out, "reduced model") as staging:
        atomic_write(staging / "config.yaml", header + reduced.to_yaml())
        atomic_write(staging / "accuracy.csv", calibration.accuracy.to_csv(float_format="%.6g"))
        atomic_write(
            staging / "calibration.md", calibration_report(config, calibration, fit_motions, test_motions)
        )
    for line in accuracy_lines(calibration.accuracy, calibration.chosen):
        report.line(line)
    report.line(
        f"wrote {out}: config.yaml (the experiment on the reduced model), accuracy.csv, calibration.md"
    )
    return out


def accuracy_lines(table, chosen: str) -> list[str]:
    """The accuracy table as aligned lines: per story the median errors (%) of the model kept, the other and
    the linear one."""
    from rlcontroller.identification.reduction import MODELS

    labels = (chosen, *(key for key in MODELS if key != chosen), "linear")
    lines = [f"story  peak drift error % ({' / '.join(labels)})  residual drift error % (the same)"]
    for story, row in table.iterrows():
        peaks = " / ".join(f"{100 * row[f'peak_drift_error_{label}']:.1f}" for label in labels)
        residuals = " / ".join(f"{100 * row[f'residual_drift_error_{label}']:.1f}" for label in labels)
        lines.append(f"{story:>5}  {peaks:>24}  {residuals:>24}")
    return lines


def calibration_report(config: Path, calibration, fit_motions: int, test_motions: int) -> str:
    """calibration.md: what was fitted to what, the parameters of the model kept, and both models' accuracy on
    other motions."""
    import pandas as pd

    from rlcontroller.evaluation.tables import markdown_table
    from rlcontroller.identification.hysteretic import COLLAPSE_DRIFT_RATIO, FIT_SEED, TEST_SEED
    from rlcontroller.identification.reduction import MODELS

    hysteresis, pushed, fits = calibration.hysteresis, calibration.pushover, calibration.fits
    costs = "; ".join(
        f"{MODELS[key]} {fit.cost:.4g} after {fit.evaluations} evaluations" for key, fit in fits.items()
    )
    per_story = {
        "post-yield ratio": (hysteresis.post_yield_ratio, ".3f"),
        "exponent": (hysteresis.exponent, ".2f"),
        "beta": (hysteresis.beta, ".3f"),
        "collapse (mm)": (1e3 * np.asarray(hysteresis.collapse_drift), ".0f"),
    }
    if calibration.chosen == "fishbone":
        columns = {
            "column EI, story below (GN m²)": (np.asarray(hysteresis.column_stiffness) / 1e9, ".3g"),
            "beams (GN m/rad)": (np.asarray(hysteresis.beam_stiffness) / 1e9, ".3g"),
            "yield rotation (mrad)": (1e3 * np.asarray(hysteresis.yield_rotation), ".2f"),
            "story yield drift, pushover (mm)": (1e3 * pushed.yield_drift, ".1f"),
        } | per_story
        note = f"\n\nThe base's rotational spring: {hysteresis.base_stiffness / 1e9:.3g} GN m/rad."
    else:
        columns = {
            "pushover: d_y (mm)": (1e3 * pushed.yield_drift, ".1f"),
            "pushover: post-yield ratio": (pushed.post_yield_ratio, ".3f"),
            "fit: d_y (mm)": (1e3 * np.asarray(hysteresis.yield_drift), ".1f"),
        } | per_story
        note = ""
    n = len(pushed.yield_drift)
    parameters = pd.DataFrame(
        {
            name: [format(v, spec) for v in np.broadcast_to(values, n)]
            for name, (values, spec) in columns.items()
        },
        index=pd.RangeIndex(1, n + 1, name="floor, story"),
    )
    labels = {"story_springs": "story springs", "fishbone": "fishbone", "linear": "linear"}
    errors = pd.DataFrame(
        {
            f"{what} drift error %, {name}": 100 * calibration.accuracy[f"{what}_drift_error_{key}"]
            for what in ("peak", "residual")
            for key, name in labels.items()
        }
        | {
            "FE peak (mm)": 1e3 * calibration.accuracy["fe_peak_drift_m"],
            "FE residual (mm)": 1e3 * calibration.accuracy["fe_residual_drift_m"],
        }
    )
    return f"""# Nonlinear reduced model of {config}

Two reduced models on the FE model's condensed stiffness, each started from the FE model's first-mode pushover
(`physics.fe.pushover`) and fitted by least squares to its story drift histories and residual drifts on
{fit_motions} generated Kanai-Tajimi motions of 0.3-1.2 g (seed {FIT_SEED}): Bouc-Wen story springs
(`physics.hysteresis`) and a fishbone (`physics.fishbone`: an elastic column line, each floor's beams one
yielding rotational spring, P-Delta from the floors' weights). Every story collapses past
{COLLAPSE_DRIFT_RATIO:.0%} of its height, and the reduced model then stays as it lies (reported as collapsed).

Costs: {costs}.

**Kept: {MODELS[calibration.chosen]}**, the lower cost on the fitted motions. Both are judged on
{test_motions} others (seed {TEST_SEED}): medians over the judged motions of |model - FE| / FE (the residual's
against 1 % of the FE peak drift where the FE residual is smaller).

{markdown_table(parameters, digits=3)}{note}

{markdown_table(errors, digits=1)}
"""
