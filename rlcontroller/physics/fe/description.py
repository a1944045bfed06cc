"""What `rlc` must know of a finite-element model that the model itself does not say (`physics.fe.build`).

A Python model file's function returns it as a mapping; a Tcl model (a published OpenSees model, run
unmodified) has it in a YAML file beside it, of the same name (`benchmark_9st_model.tcl` ->
`benchmark_9st_model.yaml`):

- `floors`: per floor from the first up, the nodes of its level (the first is its control node: where the
  actuators push and the sensors read; the masses of all are the floor's mass);
- `direction`: the degree of freedom of the lateral direction (1 = x);
- `story_heights`: per story, in the model's length unit;
- `modal_damping` (ratios per mode, the last repeated) or `rayleigh` ([a0, a1], C = a0 M + a1 K): the
  damping the file gave the model, for the reduced model to match; or for a published model that leaves its
  damping to an analysis script, `rayleigh_modes` ([[mode, ratio], [mode, ratio]]): Rayleigh damping that
  `rlc` gives the model once built, with those ratios at those modes of the FE model (as such scripts do);
- optionally `units: {length: m | cm | mm | ft | in, force: N | kN | MN | kip | lbf}` (default m and N; mass
  is force / (length / s^2), time is s): many published models are in kip and inch or foot, `rlc` in SI;
- optionally `build_until` (a Tcl script): `loadConst` (the default), the model as it stands when the script
  holds its gravity loads with `loadConst`, what follows (its own pushover or time history, `wipe`) skipped;
  or `end`;
- optionally `constraints`, `system`, `test` and `algorithm`: OpenSees' arguments for the time steps; the
  test's tolerance in SI (m for NormDispIncr and the other displacement tests, N for force tests, J for energy
  ones), converted into the model's units (default NormDispIncr 1e-10 m).
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass

import numpy as np

from rlcontroller.errors import ModelError

FALLBACKS = (("Newton",), ("ModifiedNewton", "-initial"), ("NewtonLineSearch",))
LENGTHS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "ft": 0.3048, "in": 0.0254}  # m per unit
FORCES = {"N": 1.0, "kN": 1.0e3, "MN": 1.0e6, "kip": 4448.2216152605, "lbf": 4.4482216152605}  # N per unit


DESCRIPTION_KEYS = (
    "floors",
    "direction",
    "story_heights",
    "modal_damping",
    "rayleigh",
    "rayleigh_modes",
    "build_until",
    "units",
    "constraints",
    "system",
    "test",
    "algorithm",
)


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
    build_until: str = "loadConst"  # a Tcl script: the model as it stands at its loadConst, or at its end
    loads_held_by_rlc: bool = False  # a Tcl script that never called loadConst: rlc held its loads once built

    @property
    def algorithms(self) -> tuple[tuple[str | float, ...], ...]:
        """The model's algorithm, then the fallbacks for a step it does not converge."""
        return (self.algorithm, *(fallback for fallback in FALLBACKS if fallback != self.algorithm))

    @property
    def test_in_model_units(self) -> tuple[str | float, ...]:
        """The convergence test with its tolerance, given in SI (m for displacement norms, N for force norms,
        J for energy), in the model's own units."""
        name, *rest = self.test
        unit = {"Disp": self.length, "Unbalance": self.force, "Energy": self.force * self.length}
        scale = next((value for key, value in unit.items() if key in str(name)), 1.0)
        if rest and isinstance(rest[0], int | float):
            rest[0] = rest[0] / scale
        return (name, *rest)

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
            raise ModelError(
                f"{where}: expected a mapping (floors, direction, story_heights, ...), "
                f"got {type(raw).__name__}"
            )
        unknown = [key for key in raw if key not in DESCRIPTION_KEYS]
        if unknown:  # a typo (unit: for units:) would otherwise read a kip-foot model in metres and newtons
            close = difflib.get_close_matches(str(unknown[0]), DESCRIPTION_KEYS, n=1)
            hint = f"did you mean {close[0]}? " if close else ""
            raise ModelError(
                f"{where}: unknown key {unknown[0]!r}: {hint}expected {', '.join(DESCRIPTION_KEYS)}"
            )
        missing = sorted({"floors", "direction", "story_heights"} - set(raw))
        if missing:
            raise ModelError(f"{where}: the mapping lacks {', '.join(missing)}")
        floors = _floors(raw["floors"], f"{where}: floors")
        try:
            heights = tuple(float(h) for h in raw["story_heights"])
        except (TypeError, ValueError):
            heights_given = raw["story_heights"]
            raise ModelError(
                f"{where}: story_heights: expected a list of numbers, got {heights_given!r}"
            ) from None
        if len(heights) != len(floors) or not all(np.isfinite(h) and h > 0.0 for h in heights):
            raise ModelError(
                f"{where}: story_heights: expected one positive height per floor ({len(floors)}), "
                f"got {list(heights)}"
            )
        direction = raw["direction"]
        if not isinstance(direction, int) or isinstance(direction, bool) or not 1 <= direction <= 3:
            raise ModelError(
                f"{where}: direction: expected the lateral degree of freedom as a number, 1 (x), 2 (y) "
                f"or 3 (z), got {direction!r}"
            )
        damping = [key for key in ("modal_damping", "rayleigh", "rayleigh_modes") if raw.get(key) is not None]
        if len(damping) != 1:
            raise ModelError(
                f"{where}: give exactly one of modal_damping and rayleigh (the damping the model has) "
                "or rayleigh_modes (the damping rlc gives it)"
            )
        modal, rayleigh = raw.get("modal_damping"), raw.get("rayleigh")
        build_until = raw.get("build_until", "loadConst")
        if build_until not in ("loadConst", "end"):
            raise ModelError(
                f"{where}: build_until: expected loadConst (the model as it stands after its gravity "
                f"analysis) or end (the whole script), got {build_until!r}"
            )
        solver = ("constraints", "system", "test", "algorithm")
        options = {key: _arguments(raw[key], f"{where}: {key}") for key in solver if key in raw}
        return cls(
            floors=floors,
            direction=direction,
            build_until=build_until,
            story_heights=heights,
            modal_damping=None if modal is None else _ratios(modal, f"{where}: modal_damping"),
            rayleigh=None if rayleigh is None else _rayleigh(rayleigh, f"{where}: rayleigh"),
            rayleigh_modes=_modes(raw.get("rayleigh_modes"), f"{where}: rayleigh_modes", len(floors)),
            **_units(raw.get("units", {}), f"{where}: units"),
            **options,
        )


def _floors(raw: object, where: str) -> tuple[tuple[int, ...], ...]:
    """Per floor its node tags (whole numbers; a floor of one node may be the tag alone), no node twice."""
    if not isinstance(raw, list) or not raw:
        raise ModelError(f"{where}: expected a list with the nodes of each floor, got {raw!r}")
    floors = [[tags] if _is_tag(tags) else tags for tags in raw]
    for floor, tags in enumerate(floors, start=1):
        if not isinstance(tags, list) or not tags or not all(_is_tag(tag) for tag in tags):
            raise ModelError(
                f"{where}: floor {floor}: expected node tags (whole numbers), got {raw[floor - 1]!r}"
            )
    seen: dict[int, int] = {}
    for floor, tags in enumerate(floors, start=1):
        for tag in tags:
            if tag in seen:
                raise ModelError(f"{where}: node {tag} is named twice (floor {seen[tag]} and floor {floor})")
            seen[tag] = floor
    return tuple(tuple(tags) for tags in floors)


def _is_tag(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _ratios(raw: object, where: str) -> tuple[float, ...]:
    if not isinstance(raw, list) or not raw or not all(_is_number(r) and 0.0 <= r < 1.0 for r in raw):
        raise ModelError(
            f"{where}: expected damping ratios in [0, 1) per mode (the last repeated), got {raw!r}"
        )
    return tuple(float(r) for r in raw)


def _rayleigh(raw: object, where: str) -> tuple[float, float]:
    if not isinstance(raw, list) or len(raw) != 2 or not all(_is_number(a) and a >= 0.0 for a in raw):
        raise ModelError(f"{where}: expected [a0, a1], two coefficients >= 0 of C = a0 M + a1 K, got {raw!r}")
    return float(raw[0]), float(raw[1])


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and np.isfinite(value)


def _modes(raw: object, where: str, floors: int) -> tuple[tuple[int, float], tuple[int, float]] | None:
    """Two (mode, ratio) pairs: modes in rising order among the model's `floors` lateral modes."""
    if raw is None:
        return None
    try:
        (i, zeta_i), (j, zeta_j) = raw
        pairs = ((int(i), float(zeta_i)), (int(j), float(zeta_j)))
    except (TypeError, ValueError):
        pairs = None
    if pairs is None or not 1 <= pairs[0][0] < pairs[1][0] or not all(0.0 < zeta < 1.0 for _, zeta in pairs):
        raise ModelError(
            f"{where}: expected [[mode, ratio], [mode, ratio]], two modes in rising order, got {raw!r}"
        )
    if pairs[1][0] > floors:
        raise ModelError(
            f"{where}: mode {pairs[1][0]}: a model of {floors} floors has {floors} lateral modes"
        )
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
