"""What an experiment is: the text of `rlc info`."""

from __future__ import annotations

from rlcontroller.config import Experiment


def describe(experiment: Experiment) -> str:
    """The resolved config, natural periods and modal damping ratios (of the design model, and of the
    simulated plant when there is a plant part), the actuator layout and the devices."""
    from rlcontroller.physics.plant import Plant

    plant = Plant(experiment)
    lines = ["# resolved configuration", resolved_text(experiment)]
    floors_only = " (floors only, without the devices)" if experiment.devices else ""
    buildings = [(f"design model{floors_only}", plant.design.bare.building)]
    if plant.fe_model is None and experiment.plant is not None:
        buildings.append((f"simulated plant (the plant part, elastic){floors_only}", plant.elastic.bare.building))
    for title, building in buildings:
        lines += mode_lines(title, building.periods(), building.modal_damping_ratios())
    if plant.fe_model is not None:
        from rlcontroller.physics.opensees import fe_modes

        design = plant.design.bare.building.periods()
        fe_periods, ratios = fe_modes(plant.fe_model.path, plant.fe_model.function, len(design))
        lines += mode_lines(f"simulated plant (OpenSees model {plant.fe_model.path.name})", fe_periods, ratios, design)
    lines.append("\n# actuators")
    for index, actuator in enumerate(experiment.actuators):
        floors = f"floor {actuator.story}"
        if actuator.mount == "inter_story":
            floors = f"+u on floor {actuator.story}, -u on " + (
                f"floor {actuator.story - 1}" if actuator.story > 1 else "the ground"
            )
        lines.append(
            f"{index + 1}: story {actuator.story}, {actuator.mount}, limit {actuator.force_limit / 1e3:g} kN ({floors})"
        )
    if experiment.devices:
        lines.append("\n# devices (mass devices tuned on the design model)")
        lines += [f"{index}: {line}" for index, line in enumerate(device_lines(experiment, plant.design.building), 1)]
    return "\n".join(lines)


def mode_lines(title: str, periods, ratios, design=None) -> list[str]:
    """A table of modes: period (s), frequency (Hz), damping ratio, and with `design` (its periods, s) the
    design model's period error in each."""
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
    return lines


def hardware_label(experiment: Experiment) -> str:
    """What a controller is made for, in a few words: "paper five-story under ground motion, actuators on
    stories 1, 2, 3, 4, 5", "... mr_damper on stories 1, 3, 5", "... active_mass on floor 5" (`Experiment.hardware`)."""
    where: dict[str, list[int]] = {}
    if experiment.actuators:
        where["actuators on story"] = [actuator.story for actuator in experiment.actuators]
    for device in experiment.devices:
        story = getattr(device, "story", None)
        where.setdefault(f"{device.type} on {'floor' if story is None else 'story'}", []).append(story or device.floor)
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


def resolved_text(experiment: Experiment) -> str:
    """The resolved experiment as YAML, a building's matrices shown by their size and source."""
    import yaml

    raw = experiment.model_dump(mode="json")
    building = raw["building"]
    for key in ("mass_matrix", "stiffness_matrix", "damping_matrix"):
        if building.get(key) is not None:
            size = len(building[key])
            building[key] = f"({size} x {size}, SI, from {building.get('source') or 'the config'})"
    return yaml.safe_dump(raw, sort_keys=False)


def device_lines(experiment: Experiment, building) -> list[str]:
    """One line per device of `experiment` as built in `building` (the design model), in config order."""
    import numpy as np

    total = float(np.sum(building.floor_masses))
    labels = experiment.command_labels()
    masses = iter(building.devices)
    lines = []
    for config in experiment.devices:
        line = config.describe(None if config.semi_active else next(masses), total)
        label = config.command_label()
        lines.append(line if label is None else f"{line} (command {labels.index(label) + 1})")
    return lines
