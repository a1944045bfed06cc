"""What `rlc` must know of a finite-element model that the model itself does not say (`physics.opensees`).

A Python model file's function returns it as a mapping; a Tcl model (a published OpenSees model, run unmodified)
has it in a YAML file beside it, of the same name (`benchmark_9st_model.tcl` -> `benchmark_9st_model.yaml`):

- `floors`: per floor from the first up, the nodes of its level (the first is its control node: where the
  actuators push and the sensors read; the masses of all are the floor's mass);
- `direction`: the degree of freedom of the lateral direction (1 = x);
- `story_heights`: per story, in the model's length unit;
- `modal_damping` (ratios per mode, the last repeated) or `rayleigh` ([a0, a1], C = a0 M + a1 K): the
  damping the file gave the model, for the reduced model to match; or for a published model that leaves its
  damping to an analysis script, `rayleigh_modes` ([[mode, ratio], [mode, ratio]]): Rayleigh damping that `rlc`
  gives the model once built, with those ratios at those modes of the FE model (as such scripts do);
- optionally `units: {length: m | cm | mm | ft | in, force: N | kN | MN | kip | lbf}` (default m and N; mass
  is force / (length / s^2), time is s): many published models are in kip and inch or foot, `rlc` in SI;
- optionally `constraints`, `system`, `test` and `algorithm`: OpenSees' arguments for the time steps.
"""

from __future__ import annotations

from dataclasses import dataclass

from rlcontroller.errors import ModelError

FALLBACKS = (("Newton",), ("ModifiedNewton", "-initial"), ("NewtonLineSearch",))
LENGTHS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "ft": 0.3048, "in": 0.0254}  # m per unit
FORCES = {"N": 1.0, "kN": 1.0e3, "MN": 1.0e6, "kip": 4448.2216152605, "lbf": 4.4482216152605}  # N per unit


@dataclass(frozen=True)
class FEDescription:
    """What `rlc` needs of a model built in the OpenSees domain (module docstring); `length` and `force` are
    the model's units in m and N."""

    floors: tuple[tuple[int, ...], ...]
    direction: int
    story_heights: tuple[float, ...]  # in the model's length unit
    modal_damping: tuple[float, ...] | None = None
    rayleigh: tuple[float, float] | None = None
    rayleigh_modes: tuple[tuple[int, float], tuple[int, float]] | None = None  # given by rlc once built
    length: float = 1.0
    force: float = 1.0
    constraints: tuple[str | float, ...] = ("Transformation",)
    system: tuple[str | float, ...] = ("UmfPack",)
    test: tuple[str | float, ...] = ("NormDispIncr", 1e-10, 30)
    algorithm: tuple[str | float, ...] = FALLBACKS[0]

    @property
    def algorithms(self) -> tuple[tuple[str | float, ...], ...]:
        """The model's algorithm, then the fallbacks for a step it does not converge."""
        return (self.algorithm, *(fallback for fallback in FALLBACKS if fallback != self.algorithm))

    @property
    def control_nodes(self) -> list[int]:
        return [nodes[0] for nodes in self.floors]

    @property
    def mass(self) -> float:
        """kg per unit of the model's mass."""
        return self.force / self.length

    @classmethod
    def of(cls, raw: object, where: str) -> FEDescription:
        if not isinstance(raw, dict):
            raise ModelError(f"{where}: expected a mapping (floors, direction, story_heights, ...), "
                             f"got {type(raw).__name__}")  # fmt: skip
        missing = sorted({"floors", "direction", "story_heights"} - set(raw))
        if missing:
            raise ModelError(f"{where}: the mapping lacks {', '.join(missing)}")
        try:
            floors = tuple(tuple(int(n) for n in ([f] if isinstance(f, int) else f)) for f in raw["floors"])
            heights = tuple(float(h) for h in raw["story_heights"])
        except (TypeError, ValueError):
            raise ModelError(f"{where}: expected floors as lists of node tags and story_heights as numbers") from None
        if not floors or any(not nodes for nodes in floors) or len(heights) != len(floors):
            raise ModelError(f"{where}: expected one list of nodes and one story height per floor")
        damping = [key for key in ("modal_damping", "rayleigh", "rayleigh_modes") if raw.get(key) is not None]
        if len(damping) != 1:
            raise ModelError(f"{where}: give exactly one of modal_damping and rayleigh (the damping the model has) "
                             "or rayleigh_modes (the damping rlc gives it)")  # fmt: skip
        modal, rayleigh = raw.get("modal_damping"), raw.get("rayleigh")
        solver = ("constraints", "system", "test", "algorithm")
        options = {key: _arguments(raw[key], f"{where}: {key}") for key in solver if key in raw}
        return cls(
            floors=floors,
            direction=int(raw["direction"]),
            story_heights=heights,
            modal_damping=None if modal is None else tuple(float(r) for r in modal),
            rayleigh=None if rayleigh is None else (float(rayleigh[0]), float(rayleigh[1])),
            rayleigh_modes=_modes(raw.get("rayleigh_modes"), f"{where}: rayleigh_modes"),
            **_units(raw.get("units", {}), f"{where}: units"),
            **options,
        )


def _modes(raw: object, where: str) -> tuple[tuple[int, float], tuple[int, float]] | None:
    if raw is None:
        return None
    try:
        (i, zeta_i), (j, zeta_j) = raw
        pairs = ((int(i), float(zeta_i)), (int(j), float(zeta_j)))
    except (TypeError, ValueError):
        pairs = None
    if pairs is None or not 1 <= pairs[0][0] < pairs[1][0] or not all(0.0 < zeta < 1.0 for _, zeta in pairs):
        raise ModelError(f"{where}: expected [[mode, ratio], [mode, ratio]], two modes in rising order, got {raw!r}")
    return pairs


def _units(raw: object, where: str) -> dict[str, float]:
    if not isinstance(raw, dict) or set(raw) - {"length", "force"}:
        raise ModelError(f"{where}: expected {{length: ..., force: ...}}, got {raw!r}")
    length, force = raw.get("length", "m"), raw.get("force", "N")
    if length not in LENGTHS or force not in FORCES:
        expected = f"length in {', '.join(LENGTHS)} and force in {', '.join(FORCES)}"
        raise ModelError(f"{where}: expected {expected}, got {raw!r}")
    return {"length": LENGTHS[length], "force": FORCES[force]}


def _arguments(raw: object, where: str) -> tuple[str | float, ...]:
    """An OpenSees command's arguments: a name, then names or numbers."""
    if not isinstance(raw, list | tuple) or not raw or not isinstance(raw[0], str):
        raise ModelError(f"{where}: expected OpenSees' arguments, a list starting with a name, got {raw!r}")
    if not all(isinstance(a, str | int | float) and not isinstance(a, bool) for a in raw):
        raise ModelError(f"{where}: expected names and numbers, got {raw!r}")
    return tuple(raw)
