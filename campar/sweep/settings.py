"""The base of every job section: frozen pydantic settings that refuse unknown keys and a
YAML true/false where a number belongs (campar.sweep.job, campar.sweep.laws)."""

import typing

from pydantic import BaseModel, ConfigDict, field_validator


class Settings(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, populate_by_name=True)

    @field_validator("*", mode="before")
    @classmethod
    def booleans_are_not_numbers(cls, value, info):
        """YAML's true/false where a number belongs is a mistake (pydantic reads true as 1)."""
        annotation = cls.model_fields[info.field_name].annotation
        values = value.values() if isinstance(value, dict) else [value]
        if any(isinstance(v, bool) for v in values) and wants_number(annotation):
            raise ValueError("must be a number, not true or false")
        return value


def wants_number(annotation) -> bool:
    """A field typed int or float (inside Annotated, Optional or a dict's values)."""
    if annotation in (int, float):
        return True
    args = typing.get_args(annotation)
    if typing.get_origin(annotation) is dict:
        return wants_number(args[1])
    return any(wants_number(a) for a in args if a is not bool)
