"""The one way a tunable number is declared: default, bounds, unit, UI step and description,
all of which travel in the JSON schema to the browser's forms."""

from __future__ import annotations

from typing import Any

from pydantic import Field


def num(default: float | None, ge: float, le: float, unit: str, step: float,
        description: str) -> Any:
    """A tunable number (``default=None`` for an optional override of a global value)."""
    return Field(default=default, ge=ge, le=le, description=description,
                 json_schema_extra={"unit": unit, "step": step})
