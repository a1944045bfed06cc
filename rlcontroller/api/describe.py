"""What an experiment is: the text of `rlc info`."""

from __future__ import annotations

import hashlib

import numpy as np
import yaml

from rlcontroller.config import Experiment

SHOWN_MODES = 10  # rows of a mode table unless in full
SHOWN_VALUES = 12  # entries of a long list unless in full


def describe(experiment: Experiment, full: bool = False) -> str:
    """The resolved config, natural periods and modal damping ratios (of the design model, and of the
    simulated plant when there is a plant part), the actuator layout and the devices; matrices summarised
    (shape, source, digest), long lists and mode tables shortened, unless `full`."""
    from rlcontroller.physics.plant import Plant

    plant = Plant(experiment)
    rows = None if full else SHOWN_MODES
    lines = ["# resolved configuration", resolved_text(experiment, full)]
    floors_only = " (floors only, without the devices)" if experiment.devices else ""
    buildings = [(f"design model{floors_only}", plant.design.bare.building)]
    if plant.fe_model is None and experiment.plant is not None:
        buildings.append(
            (f"simulated plant (the plant part, elastic){floors_only}", plant.elastic.bare.building)
        )
    for title, building in buildings:
        lines += mode_lines(title, building.periods(), building.modal_damping_ratios(), rows=rows)
    if plant.fe_model is not None:
        from rlcontroller.physics.fe.build import fe_modes

        design = plant.design.bare.building.periods()
        fe_periods, ratios = fe_modes(plant.fe_model.path, plant.fe_model.function, len(design))
        title = f"simulated plant (OpenSees model {plant.fe_model.path.name})"
        lines += mode_lines(title, fe_periods, ratios, design=design, rows=rows)
        from rlcontroller.simulation.kept import check_moves

        moved = check_moves(plant)  # a model that stands still is one line here, before any run
        lines.append(
            f"under a unit ground pulse its peak drift is {moved:.3f} of its design model's: it moves"
        )
    lines.append("\n# actuators")
    for index, actuator in enumerate(experiment.actuators):
        floors = f"floor {actuator.story}"
        if actuator.mount == "inter_story":
            floors = f"+u on floor {actuator.story}, -u on " + (
                f"floor {actuator.story - 1}" if actuator.story > 1 else "the ground"
            )
        lines.append(
            f"{index + 1}: story {actuator.story}, {actuator.mount}, limit {actuator.force_limit / 1e3:g} kN "
            f"({floors})"
        )
    if experiment.devices:
        lines.append("\n# devices (mass devices tuned on the design model)")
        lines += [
            f"{index}: {line}"
            for index, line in enumerate(device_lines(experiment, plant.design.building), 1)
        ]
    return "\n".join(lines)


def mode_lines(title: str, periods, ratios, *, design=None, rows: int | None = None) -> list[str]:
    """A table of modes: period (s), frequency (Hz), damping ratio, and with `design` (its periods, s) the
    design model's period error in each; the first `rows` modes and a line counting the others (all: None)."""
    error = "  design model's period error" if design is not None else ""
    lines = [
        f"# modes of the {title}",
        f"{'mode':>4}  {'period (s)':>10}  {'frequency (Hz)':>14}  {'damping ratio':>13}{error}",
    ]
    for mode, (period, ratio) in enumerate(zip(periods, ratios, strict=True), 1):
        line = f"{mode:>4}  {period:>10.3f}  {1 / period:>14.3f}  {ratio:>13.4f}"
        if design is not None:
            line += f"  {design[mode - 1] / period - 1.0:>+27.2%}"
        lines.append(line)
    if rows is not None and len(lines) > rows + 2:
        lines = lines[: rows + 2] + [
            f"   ... {len(lines) - rows - 2} more modes (rlc info --full lists them)"
        ]
    return lines


def hardware_label(experiment: Experiment) -> str:
    """What a controller is made for, in a few words: "paper five-story under ground motion, actuators on
    stories 1, 2, 3, 4, 5", "... mr_damper on stories 1, 3, 5", "... active_mass on floor 5"
    (`Experiment.hardware`)."""
    where: dict[str, list[int]] = {}
    if experiment.actuators:
        where["actuators on story"] = [actuator.story for actuator in experiment.actuators]
    for device in experiment.devices:
        story = getattr(device, "story", None)
        where.setdefault(f"{device.type} on {'floor' if story is None else 'story'}", []).append(
            story or device.floor
        )
    parts = [
        f"{key.replace('story', 'stories') if len(places) > 1 else key} {', '.join(map(str, places))}"
        for key, places in where.items()
    ] or ["no actuators or devices"]
    plant = experiment.plant
    simulated = (
        ""
        if plant is None
        else " (OpenSees model)"
        if plant.opensees is not None
        else " (yielding stories)"
        if plant.hysteresis is not None
        else " (its plant part)"
    )
    return f"{experiment.building.name}{simulated} under {experiment.load_kind}, {'; '.join(parts)}"


def resolved_text(experiment: Experiment, full: bool = False) -> str:
    """The resolved experiment as YAML. Unless `full`: a matrix as its shape, source and digest, a long list
    as its first and last entries and its length (a building of 76 floors fits on a screen)."""

    raw = experiment.model_dump(mode="json")
    if full:
        return yaml.safe_dump(raw, sort_keys=False)
    source = raw["building"].get("source") or "the config"

    class Dumper(yaml.SafeDumper):
        """Lists and mappings of numbers and names on one line (wrapped)."""

    def flat(data) -> bool:
        return not any(isinstance(item, dict) or (isinstance(item, list) and not flat(item)) for item in data)

    def sequence(dumper, data):
        return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=flat(data))

    def mapping(dumper, data):
        # a matrix: a line each
        short = not any(isinstance(item, str) and len(item) > 40 for item in data.values())
        return dumper.represent_mapping(
            "tag:yaml.org,2002:map", data, flow_style=flat(data.values()) and short
        )

    Dumper.add_representer(list, sequence)
    Dumper.add_representer(dict, mapping)
    return yaml.dump(_summarised(raw, source), Dumper=Dumper, sort_keys=False, width=120)


def _summarised(value, source: str):
    """`value` with every matrix (a list of lists) and long list replaced by a line saying what it is, and
    numbers to 6 significant digits."""

    if isinstance(value, dict):
        return {key: _summarised(item, source) for key, item in value.items()}
    if isinstance(value, float):
        return float(f"{value:.6g}")
    if not isinstance(value, list):
        return value
    if value and all(isinstance(row, list) for row in value):
        try:
            matrix = np.array(value, dtype=float)
        except ValueError:  # rows of other lengths or not numbers: not a matrix
            return [_summarised(row, source) for row in value]
        digest = hashlib.sha256(matrix.tobytes()).hexdigest()[:12]
        return f"({' x '.join(map(str, matrix.shape))} matrix, SI, from {source}, sha256 {digest})"
    if len(value) > SHOWN_VALUES and all(isinstance(item, int | float) for item in value):
        if len(set(value)) == 1:
            return f"{len(value)} x {value[0]:.6g}"
        head = ", ".join(f"{item:.6g}" for item in value[:3])
        return f"[{head}, ..., {value[-1]:.6g}] ({len(value)} values)"
    return [_summarised(item, source) for item in value]


def device_lines(experiment: Experiment, building) -> list[str]:
    """One line per device of `experiment` as built in `building` (the design model), in config order."""

    total = float(np.sum(building.floor_masses))
    labels = experiment.command_labels()
    masses = iter(building.devices)
    lines = []
    for config in experiment.devices:
        line = config.describe(None if config.semi_active else next(masses), total)
        label = config.command_label()
        lines.append(line if label is None else f"{line} (command {labels.index(label) + 1})")
    return lines
