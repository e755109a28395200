from __future__ import annotations

import pytest


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "match: starts a whole match (all processes); part of `make test`, "
        "deselect with -m 'not match'")
