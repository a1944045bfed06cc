"""Loads: the ground-motion generators (noise + impulses, Kanai-Tajimi, near-fault, site-based, mixtures) and
the suites they draw; suites of generated wind loads."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

from pydantic import (
    Field,
    model_validator,
)

from rlcontroller.config.base import (
    AccelerationRange,
    DurationRange,
    IntRange,
    Range,
    Seed,
    StrictModel,
    TimeStep,
    bounded_range,
    read_model,
)


class NoiseImpulsesConfig(StrictModel):
    """The paper's training motions: white noise plus random half-sine impulses (m/s^2, s)."""

    kind: Literal["noise_impulses"] = "noise_impulses"
    dt: TimeStep = 0.02
    duration: DurationRange = (10.0, 20.0)
    noise_std: AccelerationRange = (0.2, 1.5)
    impulses: IntRange = (0, 4)
    impulse_amplitude: AccelerationRange = (1.0, 5.0)
    impulse_duration: DurationRange = (0.05, 0.5)


class KanaiTajimiConfig(StrictModel):
    """Kanai-Tajimi filtered white noise with a rise-plateau-decay envelope, scaled to a PGA."""

    kind: Literal["kanai_tajimi"] = "kanai_tajimi"
    dt: TimeStep = 0.02
    duration: DurationRange = (15.0, 30.0)
    ground_frequency: bounded_range(0.0, 1000.0, low_open=True) = (8.0, 25.0)  # rad/s
    ground_damping: bounded_range(0.0, 10.0, low_open=True) = (0.3, 0.7)
    pga: AccelerationRange = (1.0, 6.0)
    pga_log: bool = False  # draw the PGA log-uniformly in `pga` (suites spanning weak to strong motions)
    rise_time: DurationRange = (1.0, 3.0)
    strong_duration: Range = (4.0, 12.0)
    decay_rate: Range = (0.2, 0.6)

    @model_validator(mode="after")
    def _positive_for_log(self) -> KanaiTajimiConfig:
        if self.pga_log and self.pga[0] <= 0.0:
            raise ValueError("pga_log needs pga low > 0")
        return self


class NearFaultConfig(StrictModel):
    """A near-fault motion: a Kanai-Tajimi background (`background`, its PGA ignored) plus a
    Mavroeidis-Papageorgiou (2003) velocity pulse of period `pulse_period` (s), `pulse_cycles`
    (their gamma, > 1) and a random phase, whose peak acceleration is `pulse_ratio` times the
    background's; the sum is scaled to a random PGA (m/s^2)."""

    kind: Literal["near_fault"] = "near_fault"
    dt: TimeStep = 0.02
    background: KanaiTajimiConfig = KanaiTajimiConfig()
    pulse_period: bounded_range(0.0, 100.0, low_open=True) = (0.5, 4.0)
    pulse_cycles: bounded_range(1.0, 20.0, low_open=True) = (1.5, 3.0)
    pulse_ratio: bounded_range(0.0, 100.0, low_open=True) = (1.0, 3.0)
    pga: AccelerationRange = (1.0, 6.0)
    pga_log: bool = False

    @model_validator(mode="after")
    def _consistent(self) -> NearFaultConfig:
        if self.background.dt != self.dt:
            raise ValueError("background.dt must equal dt")
        if self.pga_log and self.pga[0] <= 0.0:
            raise ValueError("pga_log needs pga low > 0")
        return self


class SiteBasedConfig(StrictModel):
    """Motions of Rezaeian & Der Kiureghian's (2010) site-based stochastic model
    (`physics.motions.site_motions`) for scenarios drawn uniformly in moment `magnitude`, log-uniformly in
    rupture `distance` (km), uniformly in `vs30` (m/s), reverse faulting with probability `reverse_share`
    (else strike-slip), a high-pass corner drawn log-uniformly in `corner_frequency` (Hz); each scaled to a
    random PGA (m/s^2). The defaults stay inside the records the model was fitted to: far-field (R >= 10 km)
    strong motions of M 6-7.5 on firm ground."""

    kind: Literal["site_based"] = "site_based"
    dt: TimeStep = 0.02
    magnitude: bounded_range(5.0, 8.0) = (6.0, 7.5)
    distance: bounded_range(1.0, 300.0) = (10.0, 100.0)  # km
    vs30: bounded_range(150.0, 2000.0) = (360.0, 1000.0)  # m/s: NEHRP site classes C and B
    reverse_share: Annotated[float, Field(ge=0.0, le=1.0)] = 0.5
    corner_frequency: bounded_range(0.0, 1.0, low_open=True) = (0.05, 0.2)  # Hz
    pga: AccelerationRange = (1.0, 6.0)
    pga_log: bool = False

    @model_validator(mode="after")
    def _positive_for_log(self) -> SiteBasedConfig:
        if self.pga_log and self.pga[0] <= 0.0:
            raise ValueError("pga_log needs pga low > 0")
        return self


SourceConfig = Annotated[
    NoiseImpulsesConfig | KanaiTajimiConfig | NearFaultConfig | SiteBasedConfig, Field(discriminator="kind")
]


class MixtureComponent(StrictModel):
    weight: Annotated[float, Field(gt=0.0, le=1.0e6)]
    generator: SourceConfig


class MixtureConfig(StrictModel):
    """Each motion comes from one component, drawn with probability proportional to its weight."""

    kind: Literal["mixture"] = "mixture"
    components: list[MixtureComponent] = Field(min_length=1, max_length=50)


class WindSiteConfig(StrictModel):
    """Where wind loads a building: the mean speed's `reference_height` (m), the terrain's roughness
    length `roughness` (m: about 0.01 open sea, 0.03 open country, 0.3 suburbs, 1 city centres),
    Davenport's coherence `decay`, and the forces' `drag_coefficient` on a facade `width` (m) wide."""

    reference_height: Annotated[float, Field(gt=0.0, le=1000.0)] = 10.0
    roughness: Annotated[float, Field(gt=0.0, le=5.0)] = 0.3
    drag_coefficient: Annotated[float, Field(gt=0.0, le=5.0)] = 1.3
    width: Annotated[float, Field(gt=0.0, le=1000.0)] = 20.0
    decay: Annotated[float, Field(gt=0.0, le=100.0)] = 10.0

    @model_validator(mode="after")
    def _rough_below_reference(self) -> WindSiteConfig:
        if self.roughness >= self.reference_height:
            raise ValueError(
                "roughness must be below reference_height (the log law's zero is at the roughness length)"
            )
        return self

    @model_validator(mode="after")
    def _cutoff_below_nyquist(self) -> WindSiteConfig:
        """Loads sampled every dt hold nothing above 1 / (2 dt): a higher cutoff would be silently aliased."""
        dt, cutoff = getattr(self, "dt", None), getattr(self, "cutoff", None)
        if dt is not None and cutoff is not None and cutoff > 0.5 / dt:
            raise ValueError(
                f"cutoff {cutoff:g} Hz lies above the Nyquist frequency {0.5 / dt:g} Hz of dt {dt:g} s; "
                f"expected a cutoff of at most {0.5 / dt:g} Hz (or a dt of at most {0.5 / cutoff:g} s)"
            )
        return self


class WindGeneratorConfig(WindSiteConfig):
    """Generated along-wind loads on the experiment's floors (`physics.motions.wind`), one record per draw: a
    mean speed drawn in `speed` (m/s at the reference height) and a duration in `duration` (s),
    sampled every `dt` s up to `cutoff` Hz."""

    kind: Literal["wind"] = "wind"
    dt: TimeStep = 0.02
    duration: DurationRange = (60.0, 180.0)
    speed: bounded_range(0.0, 100.0, low_open=True) = (10.0, 30.0)  # m/s
    cutoff: Annotated[float, Field(gt=0.0, le=50.0)] = 5.0


GeneratorConfig = Annotated[
    NoiseImpulsesConfig
    | KanaiTajimiConfig
    | NearFaultConfig
    | SiteBasedConfig
    | MixtureConfig
    | WindGeneratorConfig,
    Field(discriminator="kind"),
]


class ExcitationConfig(StrictModel):
    """Training motions come from `generator`; validation motions are `validation_motions` draws
    of `validation_generator` (default: the same generator) with the fixed `validation_seed`."""

    generator: GeneratorConfig = NoiseImpulsesConfig()
    validation_generator: GeneratorConfig | None = None
    validation_motions: Annotated[int, Field(ge=1, le=1000)] = 8
    validation_seed: Seed = 10_000

    @property
    def validation(self) -> GeneratorConfig:
        """The generator of the validation motions."""
        return self.validation_generator or self.generator

    def sources(self) -> list[NoiseImpulsesConfig | KanaiTajimiConfig | NearFaultConfig | SiteBasedConfig]:
        """The generators motions can come from (the components of mixtures), validation included."""
        sources = []
        for generator in (self.generator, self.validation_generator):
            if isinstance(generator, MixtureConfig):
                sources += [component.generator for component in generator.components]
            elif generator is not None:
                sources.append(generator)
        return sources


class WindSuiteConfig(WindSiteConfig):
    """A suite of generated along-wind load records (`physics.motions.wind`): `records_per_speed` records of
    `duration` s at each mean speed (m/s at the reference height), sampled every `dt` s up to
    `cutoff` Hz, from one `seed`. Used as `--records FILE.yaml`."""

    kind: Literal["wind"]
    speeds: Annotated[list[Annotated[float, Field(gt=0.0, le=100.0)]], Field(min_length=1, max_length=20)]
    records_per_speed: Annotated[int, Field(ge=1, le=100)] = 3
    duration: Annotated[float, Field(gt=0.0, le=7200.0)] = 600.0
    dt: Annotated[float, Field(ge=0.005, le=1.0)] = 0.1
    cutoff: Annotated[float, Field(gt=0.0, le=50.0)] = 1.0
    seed: Seed = 2026


def names_wind_suite(records: str | Path | None) -> bool:
    """Whether a `--records` value names a wind suite (a YAML file, kind: wind) rather than ground motions."""
    return records is not None and Path(records).suffix in (".yaml", ".yml")


def load_wind_suite(path: str | Path) -> WindSuiteConfig:
    """A wind suite from a YAML file; one-line errors naming the file and the key."""
    return read_model(path, WindSuiteConfig, "kind: wind")
