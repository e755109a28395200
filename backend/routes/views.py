"""The station's views on request: health, world, geometry (the websocket pushes them), and
the station's folders (set at start, read-only)."""

from __future__ import annotations

from fastapi import APIRouter, HTTPException
from fastapi.responses import JSONResponse

from .. import contract
from ..jsonsafe import SafeJSONResponse
from .deps import VIEWER, StationDep

router = APIRouter(prefix="/api", tags=["views"], dependencies=[VIEWER])


@router.get("/health")
async def health(st: StationDep) -> JSONResponse:
    # current, computed on the station thread (the websocket gets the published one)
    return SafeJSONResponse(await st.read(st.browser.health), what="health")


@router.get("/world")
async def world(st: StationDep) -> JSONResponse:
    # current, built on the station thread (the websocket gets the published one)
    return SafeJSONResponse(await st.read(st.browser.world), what="world")


@router.get("/geometry")
async def geometry(st: StationDep) -> JSONResponse:
    geo = await st.read(st.browser.geometry)
    if geo is None:
        raise HTTPException(404, "no geometry packet received yet")
    return SafeJSONResponse(geo, what="geometry")


@router.get("/folders")
async def folders(st: StationDep) -> contract.StationFolders:
    # set when the station started: no route or parameter changes them (docs/security.md)
    return st.settings.station_folders()
