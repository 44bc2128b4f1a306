"""The base of every world-file model and the value types the schema's sections share."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field

__all__ = ["NonNegFloat", "PositiveFloat", "Strict", "Vec2", "Vec3"]

PositiveFloat = Annotated[float, Field(gt=0)]
NonNegFloat = Annotated[float, Field(ge=0)]
Vec2 = tuple[float, float]
Vec3 = tuple[float, float, float]


class Strict(BaseModel):
    """Base for every section: unknown keys are errors; numbers are finite; values are checked on assignment too."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True, frozen=False, allow_inf_nan=False)
