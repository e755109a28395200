"""Parameters and presets. A refused change raises ParamError (422 with field and reason) and
a missing preset PresetNotFound (404), both answered by the app's exception handlers."""

from __future__ import annotations

import json
import logging
from typing import Any

from fastapi import APIRouter, Request
from fastapi.responses import JSONResponse

from .. import contract
from ..params.store import ParamError, diff
from ..station import Station
from .deps import OPERATOR, VIEWER, OperatorDep, StationDep
from .operators import check_params

log = logging.getLogger("touchline.api")

router = APIRouter(prefix="/api", tags=["params"])


async def _json_body(request: Request) -> Any:
    # read by hand: a partial nested object of any shape, validated by the store as a whole
    try:
        return json.loads(await request.body())
    except RecursionError:  # the EdgeGuard refuses deep JSON first; a last line of defence
        raise ParamError([{"loc": ["body"], "msg": "JSON nested too deeply",
                           "type": "json_invalid"}]) from None
    except ValueError as exc:
        raise ParamError([{"loc": ["body"], "msg": f"invalid JSON: {exc}",
                           "type": "json_invalid"}]) from None


async def _applied(st: Station) -> contract.ParamsState:
    await st.call(lambda: None)  # the station loop has applied it before we answer
    return {"version": st.params.version, "values": st.params.values()}


@router.get("/params/schema", dependencies=[VIEWER])
async def params_schema(st: StationDep) -> dict[str, Any]:
    return st.params.schema()


@router.get("/params", dependencies=[VIEWER])
async def params_get(st: StationDep) -> contract.ParamsState:
    return {"version": st.params.version, "values": st.params.values()}


@router.patch("/params")
async def params_patch(request: Request, st: StationDep,
                       caller: OperatorDep) -> contract.ParamsState:
    body = await _json_body(request)
    await check_params(request, st, body)
    st.params.patch(body)
    strategy = body.get("strategy") if isinstance(body, dict) else None
    play = isinstance(strategy, dict) and "play" in strategy
    await st.call(st.operator_action, "play" if play else "params", caller.who,
                  {"changes": body})
    log.info("parameters changed to version %d", st.params.version)
    return await _applied(st)


@router.get("/params/diff", dependencies=[VIEWER])
async def params_diff(st: StationDep) -> contract.ParamsDiff:
    return {"version": st.params.version, "changes": st.params.diff_from_defaults()}


@router.get("/params/export", dependencies=[VIEWER])
async def params_export(st: StationDep) -> JSONResponse:
    return JSONResponse({"touchline_params": 1, "values": st.params.values()}, headers={
        "content-disposition": 'attachment; filename="touchline-params.json"'})


@router.post("/params/import")
async def params_import(request: Request, st: StationDep,
                        caller: OperatorDep) -> contract.ParamsState:
    body = await _json_body(request)
    st.params.replace(body["values"] if isinstance(body, dict) and "values" in body else body)
    await st.call(st.operator_action, "params-import", caller.who, {})
    return await _applied(st)


@router.get("/presets", dependencies=[VIEWER])
async def presets_list(st: StationDep) -> contract.PresetList:
    return {"presets": st.params.list_presets()}


@router.put("/presets/{name}", dependencies=[OPERATOR])
async def preset_save(name: str, st: StationDep) -> contract.PresetList:
    st.params.save_preset(name)
    return {"presets": st.params.list_presets()}


@router.get("/presets/{name}", dependencies=[VIEWER])
async def preset_get(name: str, st: StationDep) -> contract.PresetDetail:
    store = st.params
    values = store.read_preset(name)
    return {"name": name, "values": values,
            "diff_from_defaults": diff(store.defaults.model_dump(mode="json"), values),
            "diff_from_current": diff(store.values(), values)}


@router.post("/presets/{name}/load")
async def preset_load(name: str, st: StationDep, caller: OperatorDep) -> contract.ParamsState:
    st.params.load_preset(name)
    await st.call(st.operator_action, "preset-load", caller.who, {"preset": name})
    return await _applied(st)


@router.delete("/presets/{name}", dependencies=[OPERATOR])
async def preset_delete(name: str, st: StationDep) -> contract.PresetList:
    st.params.delete_preset(name)
    return {"presets": st.params.list_presets()}
