"""The strict base of every configuration model: unknown keys, changes after validation and
non-finite numbers are refused."""

from pydantic import BaseModel, ConfigDict


class StrictModel(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)
