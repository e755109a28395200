"""Every route says who may call it by its dependency (backend/routes/deps.py): a route that
changes something without an operator (or e-stop) dependency fails here, whichever router
it is in, and the dependency refuses by itself, without the AccessGuard in front."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi import APIRouter, FastAPI
from fastapi.testclient import TestClient

from backend.access import NEED_OPERATOR, NEED_VIEWER, AccessRule, TokenStore
from backend.api import create_app
from backend.config import Settings
from backend.routes import robots, views
from backend.routes.deps import OPERATOR, VIEWER, route_access
from backend.security import STATE_CHANGING
from backend.station import Station
from launcher.supervisor import free_tcp_port


def _settings(tmp_path: Path, **kw: Any) -> Settings:
    return Settings(relay_pub=f"tcp://127.0.0.1:{free_tcp_port()}",
                    relay_sub=f"tcp://127.0.0.1:{free_tcp_port()}", static_dir=tmp_path,
                    state_dir=tmp_path / "state", allowed_hosts=["testserver"], **kw)


def unguarded(app: FastAPI) -> list[str]:
    """The routes whose access is missing or too weak for what they do."""
    fastapi_docs = {app.openapi_url, app.docs_url, app.redoc_url,
                    app.swagger_ui_oauth2_redirect_url}
    bad = []
    for method, path, access in route_access(app):
        if access is None and not (method == "GET" and path in fastapi_docs):
            bad.append(f"{method} {path}: no access dependency")
        elif method in STATE_CHANGING and access not in ("operator", "estop"):
            bad.append(f"{method} {path}: changes something, open to {access}")
        elif access == "estop" and path != "/api/estop":
            bad.append(f"{method} {path}: the e-stop rule is the e-stop's only")
    return bad


@pytest.fixture
def app(tmp_path: Path) -> Iterator[FastAPI]:
    cfg = _settings(tmp_path)
    yield create_app(cfg, Station(cfg))


def test_every_route_of_the_app_states_its_access(app: FastAPI) -> None:
    table = route_access(app)
    assert ("POST", "/api/robots/{team}/{rid}/target", "operator") in table
    assert ("POST", "/api/estop", "estop") in table
    assert ("GET", "/api/world", "viewer") in table
    assert ("WEBSOCKET", "/api/ws", "viewer") in table
    assert ("GET", "/login", "anyone") in table
    assert len([r for r in table if r[0] in STATE_CHANGING]) > 15
    assert unguarded(app) == []


def test_a_changing_route_without_an_access_dependency_is_found(app: FastAPI) -> None:
    extra = APIRouter(prefix="/api/extra")

    @extra.post("/forgotten")
    async def forgotten() -> None: ...

    @extra.delete("/weak", dependencies=[VIEWER])
    async def weak() -> None: ...

    @extra.put("/right", dependencies=[OPERATOR])
    async def right() -> None: ...

    app.include_router(extra)
    assert unguarded(app) == ["POST /api/extra/forgotten: no access dependency",
                              "DELETE /api/extra/weak: changes something, open to viewer"]


def test_the_dependency_refuses_without_the_guard(tmp_path: Path) -> None:
    """A bare app with the routers and no AccessGuard: the rule still holds, because it is
    the route's dependency (no role in the scope: no token was read)."""
    cfg = _settings(tmp_path)
    bare = FastAPI()
    bare.state.station = Station(cfg)
    bare.state.access = AccessRule(operator=TokenStore(None),
                                   viewer=TokenStore(None, env="NO_SUCH_VARIABLE"),
                                   required=True)
    bare.include_router(robots.router)
    bare.include_router(views.router)
    with TestClient(bare) as c:
        r = c.post("/api/robots/blue/1/target", json={"x": 0, "y": 0})
        assert r.status_code == 401 and r.json()["detail"] == NEED_OPERATOR
        r = c.get("/api/world")
        assert r.status_code == 401 and r.json()["detail"] == NEED_VIEWER
    assert bare.state.access.refused == {"no operator token": 1, "no viewer token": 1}


def test_a_body_that_does_not_parse_is_refused_for_the_token_first(tmp_path: Path) -> None:
    """FastAPI answers an unparsable body before any dependency runs: the access rule is
    applied all the same, so a caller without the token learns nothing about the body."""
    cfg = _settings(tmp_path, require_token=True)
    with TestClient(create_app(cfg, Station(cfg)), headers={"X-Touchline": "1"}) as c:
        json_type = {"content-type": "application/json"}
        r = c.post("/api/robots/blue/1/target", content=b"{not json", headers=json_type)
        assert r.status_code == 401 and r.json()["detail"] == NEED_OPERATOR
        r = c.post("/api/estop", content=b"{not json", headers=json_type)
        assert r.status_code == 422  # the e-stop's rule needs the body: a viewer may press
        token = c.app.state.access.operator.token  # type: ignore[attr-defined]
        r = c.post("/api/robots/blue/1/target", content=b"{not json",
                   headers={**json_type, "authorization": f"Bearer {token}"})
        assert r.status_code == 422 and r.json()["detail"][0]["type"] == "json_invalid"
