"""The HTTP and websocket API (docs/api.md) and the built frontend, on one port: the app
factory. The routes are in ``backend.routes`` (one router per resource, who may call each one
its dependency); this assembles them behind the edge and access guards."""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import AsyncIterator
from pathlib import Path

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import HTMLResponse, JSONResponse
from fastapi.staticfiles import StaticFiles

from . import routes
from .access import AccessGuard, AccessRule
from .config import Settings
from .jsonsafe import SafeJSONResponse
from .params.store import ParamError, PresetNotFound, format_errors
from .routes.deps import PUBLIC, refusal_before_body
from .security import EdgeGuard
from .station import Station
from .wsfanout import ServerSendTap

log = logging.getLogger("touchline.api")


def create_app(settings: Settings, station: Station | None = None,
               access: AccessRule | None = None) -> FastAPI:
    st = station or Station(settings)
    rule = access or AccessRule.from_settings(
        settings.host, settings.state_dir, settings.require_token, settings.view_token,
        settings.estop_for_all)

    @contextlib.asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        if not st.loop.running:  # python -m backend starts it before the web side
            await asyncio.to_thread(st.start_thread)
        st.startup.mark("web serving")  # (uvicorn binds its socket right after this)
        st.startup.log_once()
        try:
            yield
        finally:
            await asyncio.to_thread(st.stop_thread)

    # every answer renders, whatever a value in it is (backend.jsonsafe): never a 500 for it
    app = FastAPI(title="Touchline", version="0.1.0", lifespan=lifespan,
                  default_response_class=SafeJSONResponse)
    app.state.station = st
    app.state.access = rule
    app.state.settings = settings
    st.web.access = rule.health
    # the caller's role from its token (backend.access; each route's dependency decides what
    # the role allows), behind the EdgeGuard (the last added runs first)
    app.add_middleware(AccessGuard, rule=rule)
    # host allowlist, Origin, cross-site requests and body limits, before any route
    app.add_middleware(EdgeGuard, bound_host=settings.host, allow_hosts=settings.allowed_hosts,
                       dev_origins=settings.allowed_origins)
    # outermost: the server's own send of a websocket, for the fan-out (backend.wsfanout)
    app.add_middleware(ServerSendTap)

    @app.exception_handler(RequestValidationError)
    async def validation_handler(req: Request, exc: RequestValidationError) -> JSONResponse:
        refused = refusal_before_body(req)  # who may call it comes first
        if refused is not None:
            return SafeJSONResponse(status_code=refused.status_code,
                                    content={"detail": refused.detail})
        # The default handler echoes the input, and a NaN input makes it fail with a 500.
        return SafeJSONResponse(status_code=422,
                                content={"detail": format_errors(exc.errors())})

    @app.exception_handler(ParamError)
    async def param_error_handler(_req: Request, exc: ParamError) -> JSONResponse:
        return SafeJSONResponse(status_code=422, content={"detail": exc.errors})

    @app.exception_handler(PresetNotFound)
    async def preset_not_found_handler(_req: Request, exc: PresetNotFound) -> JSONResponse:
        return SafeJSONResponse(status_code=404,
                                content={"detail": f"no preset named {exc.args[0]!r}"})

    for router in routes.ROUTERS:
        app.include_router(router)
    _mount_frontend(app, settings.static_dir)
    return app


def _mount_frontend(app: FastAPI, static_dir: Path) -> None:
    if (static_dir / "index.html").exists():
        app.mount("/", StaticFiles(directory=static_dir, html=True), name="frontend")
        return

    @app.get("/", response_class=HTMLResponse, dependencies=[PUBLIC])
    async def not_built() -> str:
        return ("<!doctype html><title>Touchline</title><h1>Touchline backend is running</h1>"
                f"<p>The frontend is not built ({static_dir} has no index.html). "
                "Run <code>make run</code>, which builds it.</p>")
