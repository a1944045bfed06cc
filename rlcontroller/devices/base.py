"""What every device type tells the rest of rlc: the contract the registry's types keep.

A device is its configuration schema with a few class-level facts and methods on it: whether it
is a semi-active damper (a command column of Gamma, force from its own law) or a mass device (a
degree of freedom), whether and where it takes a command, its command when a controller fails
safe, and one line that describes it.
"""

from __future__ import annotations

from typing import Any, ClassVar

from rlcontroller.schema import StrictModel


class Device(StrictModel):
    """A device on the building (subclasses add the `type` literal and their fields)."""

    # a damper commanded in [-1, 1]; else a mass device (a degree of freedom)

    semi_active: ClassVar[bool] = False
    # its action when the controller fails safe; None: no command
    fail_safe_action: ClassVar[float | None] = None

    def command_label(self) -> str | None:
        """Its column's label in the action ("AMD 5", "MR 1"), None when it takes no command."""
        return None

    def describe(self, built: Any, total_mass: float) -> str:
        """One line: what it is and where, as built (`built`: its `MassDevice`, None for a damper)."""
        raise NotImplementedError


class Damper(Device):
    """A semi-active damper on a story (subclasses declare `story` and `capacity`, N: the force
    clipped-optimal control designs with); its force resists the drift velocity. Its law is a branch
    of the compiled `physics.integrators.damper_step`, numbered `kernel`, reading `kernel_row`."""

    semi_active: ClassVar[bool] = True
    fail_safe_action: ClassVar[float | None] = -1.0  # the minimum command: passive-off
    short: ClassVar[str]  # its label's prefix
    kernel: ClassVar[int]

    def command_label(self) -> str:
        return f"{self.short} {self.story}"

    def kernel_row(self) -> list[float]:
        """The 13 parameters its branch of the compiled step reads (SI)."""
        raise NotImplementedError

    def scaled(self, factor: float) -> Damper:
        """This damper with its force times `factor` (a robustness variation)."""
        raise NotImplementedError
