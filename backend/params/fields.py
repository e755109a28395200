"""The one way a tunable number is declared: default, bounds, unit, UI step and description,
all of which travel in the JSON schema to the browser's forms; a group of them inside another;
the check of a per-robot override map's keys."""

from __future__ import annotations

import re
from collections.abc import Iterable
from typing import Any

from pydantic import BaseModel, Field


def num(default: float | None, ge: float, le: float, unit: str, step: float,
        description: str) -> Any:
    """A tunable number (``default=None`` for an optional override of a global value)."""
    return Field(default=default, ge=ge, le=le, description=description,
                 json_schema_extra={"unit": unit, "step": step})


def plain(**field: Any) -> Any:
    """A field that is not a number (a choice, a map): no unit and no UI step."""
    return Field(**field, json_schema_extra={"unit": "", "step": None})


def group(model: type[BaseModel], description: str) -> Any:
    """A group of parameters inside another, its default the group's own defaults (an
    instance: the model is frozen, so one default is shared safely)."""
    return plain(default=model(), description=description)


#: a per-robot override's key: "blue/3", "yellow/15"
_ROBOT_KEY = re.compile(r"^(blue|yellow)/(1[0-5]|[0-9])$")


def check_robot_keys(keys: Iterable[str]) -> None:
    """ValueError (a 422 naming the field) for a key that is not "blue/<0..15>" or
    "yellow/<0..15>"."""
    for key in keys:
        if not _ROBOT_KEY.match(key):
            raise ValueError(f'robot key {key!r} is not "blue/<0..15>" or "yellow/<0..15>"')
