"""The strict base of every configuration model: unknown keys, changes after validation, non-finite numbers
and booleans where a number is expected (YAML reads `no` as false, which a number field would take as 0) are
refused."""

import types
import typing
from typing import Annotated, Union, get_args, get_origin

from pydantic import BaseModel, ConfigDict, model_validator

NUMBERS = (int, float)


def numbers_only(annotation) -> bool:
    """Whether a field's type takes numbers and nothing else (None aside): int, float, their Optional or
    Annotated."""
    origin = get_origin(annotation)
    if origin is Annotated:
        return numbers_only(get_args(annotation)[0])
    if origin in (Union, types.UnionType):
        options = [option for option in get_args(annotation) if option is not type(None)]
        return bool(options) and all(numbers_only(option) for option in options)
    return annotation in NUMBERS


class StrictModel(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    @model_validator(mode="before")
    @classmethod
    def _no_boolean_numbers(cls, raw: typing.Any) -> typing.Any:
        if isinstance(raw, dict):
            for key, value in raw.items():
                field = cls.model_fields.get(key) if isinstance(key, str) else None
                if isinstance(value, bool) and field is not None and numbers_only(field.annotation):
                    raise ValueError(f"{key}: {value} is a boolean, expected a number")
        return raw
