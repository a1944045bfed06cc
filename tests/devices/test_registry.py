"""The device registry: every type parses from its `type`, says what the rest of rlc asks of it,
and a damper's `scaled` scales every force of its law and nothing else."""

import numpy as np
import pytest
from pydantic import TypeAdapter

from rlcontroller.devices import DEVICE_TYPES, DeviceConfig
from rlcontroller.devices.mr_damper import FORCE_PARAMETERS, PARAMETERS

EXAMPLES = {
    "tuned_mass": {"floor": 5, "mass_ratio": 0.02},
    "active_mass": {"floor": 5, "mass_ratio": 0.02, "force_limit": 1.0e5, "stroke_limit": 0.5},
    "variable_damper": {"story": 1, "damping_min": 1.0e4, "damping_max": 1.0e6, "capacity": 1.0e5},
    "mr_damper": {"story": 1, "capacity": 1.0e5},
}


@pytest.mark.parametrize(
    "device_type", DEVICE_TYPES, ids=lambda t: t.model_fields["type"].annotation.__args__[0]
)
def test_each_registered_type_parses_to_itself_and_keeps_the_contract(device_type):
    name = device_type.model_fields["type"].annotation.__args__[0]
    device = TypeAdapter(DeviceConfig).validate_python({"type": name, **EXAMPLES[name]})
    assert type(device) is device_type
    label = device.command_label()
    assert (label is None) == (device.fail_safe_action is None)
    if device.fail_safe_action is not None:
        assert -1.0 <= device.fail_safe_action <= 1.0
    if device.semi_active:
        assert len(device.kernel_row()) == 13
        assert label.endswith(f" {device.story}")


def test_registered_types_have_distinct_names_labels_and_kernels():
    names = [t.model_fields["type"].annotation.__args__[0] for t in DEVICE_TYPES]
    assert sorted(names) == sorted(EXAMPLES)
    dampers = [t for t in DEVICE_TYPES if t.semi_active]
    assert len({t.kernel for t in dampers}) == len({t.short for t in dampers}) == len(dampers)


def test_the_fail_safe_commands_are_the_passive_states():
    adapter = TypeAdapter(DeviceConfig)
    driver, mr, variable = (
        adapter.validate_python({"type": n, **EXAMPLES[n]})
        for n in ("active_mass", "mr_damper", "variable_damper")
    )
    assert driver.fail_safe_action == 0.0  # no force: the tuned mass it was built as
    assert mr.fail_safe_action == variable.fail_safe_action == -1.0  # the minimum command: passive-off


def test_a_scaled_mr_damper_scales_its_force_parameters_only():
    mr = TypeAdapter(DeviceConfig).validate_python({"type": "mr_damper", **EXAMPLES["mr_damper"]})
    base, double = np.array(mr.kernel_row()), np.array(mr.scaled(2.0).kernel_row())
    force = np.isin(PARAMETERS + ("V_max", "eta"), FORCE_PARAMETERS)
    np.testing.assert_allclose(double[force], 2.0 * base[force], rtol=1e-15)
    np.testing.assert_array_equal(double[~force], base[~force])


def test_a_scaled_variable_damper_scales_its_damping_range():
    damper = TypeAdapter(DeviceConfig).validate_python(
        {"type": "variable_damper", **EXAMPLES["variable_damper"]}
    )
    scaled = damper.scaled(0.5)
    assert (scaled.damping_min, scaled.damping_max) == (0.5e4, 0.5e6)
    # the design force is what the designer assumed, not what was built
    assert scaled.capacity == damper.capacity


def test_commands_and_their_fail_safe_actions_follow_the_action_s_order():
    """Actuators first, then mass drivers, then dampers, whatever order the devices are listed in."""
    from rlcontroller.config import ConfigError, Experiment, build_experiment

    driver = {
        "type": "active_mass",
        "floor": 5,
        "mass_ratio": 0.02,
        "force_limit": 1.0e5,
        "stroke_limit": 0.5,
    }
    damper = {"type": "mr_damper", "story": 3, "capacity": 1.0e5}
    tuned = {"type": "tuned_mass", "floor": 4, "mass_ratio": 0.01}
    raw = {"actuators": [{"story": 2}], "devices": [damper, tuned, driver]}
    experiment = Experiment.model_validate(raw)  # unchecked: the order alone
    assert experiment.command_labels() == ["2", "AMD 5", "MR 3"]
    assert experiment.fail_safe_actions() == [0.0, 0.0, -1.0]
    # a driver has a housing; its stops are not modelled beside dampers, and that is said
    with pytest.raises(ConfigError, match=r"devices\[2\]\.stroke_limit: end-stops with semi-active dampers"):
        build_experiment(raw)
