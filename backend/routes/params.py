"""Parameters and presets. A refused change raises ParamError (422 with field and reason) and
a missing preset PresetNotFound (404), both answered by the app's exception handlers.

The parameters are station state: a change is one call on the station's queue (checked,
applied to every part and recorded on the station thread, the store's one writer), answered
once its file is written (by the store's own writer thread). Presets are files beside it:
saving, reading and deleting one touches no station state and stays on the web thread."""

from __future__ import annotations

import asyncio
import json
import logging
from concurrent.futures import Future
from typing import Any

from fastapi import APIRouter, Request
from fastapi.responses import JSONResponse

from .. import contract
from ..operators import Who
from ..params.store import ParamError, diff
from ..station import Station
from .deps import OPERATOR, VIEWER, OperatorDep, StationDep
from .operators import check_params, version_seen

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


def _state(st: Station) -> contract.ParamsState:
    return {"version": st.params.version, "values": st.params.values()}


#: a change made on the station thread: the state after it, and its file's write (None: none)
Change = tuple[contract.ParamsState, Future[None] | None]


def _changed(st: Station, action: str, who: Who, details: dict[str, Any]) -> Change:
    """After a change on the station thread: recorded, and the state with its file's write."""
    st.operator_action(action, str(who), details)
    return _state(st), st.params.saved


async def _answer(change: Change) -> contract.ParamsState:
    state, saved = change
    if saved is not None:  # on disk before the answer says it is done
        await asyncio.wrap_future(saved)
    return state


def _patch(st: Station, body: Any, seen: int | None, who: Who) -> Change:
    check_params(st, body, seen, who)
    st.params.patch(body)
    strategy = body.get("strategy") if isinstance(body, dict) else None
    play = isinstance(strategy, dict) and "play" in strategy
    log.info("parameters changed to version %d", st.params.version)
    return _changed(st, "play" if play else "params", who, {"changes": body})


def _replace(st: Station, values: Any, action: str, who: Who,
             details: dict[str, Any]) -> Change:
    st.params.replace(values)
    return _changed(st, action, who, details)


@router.get("/params/schema", dependencies=[VIEWER])
async def params_schema(st: StationDep) -> dict[str, Any]:
    return st.params.schema()


@router.get("/params", dependencies=[VIEWER])
async def params_get(st: StationDep) -> contract.ParamsState:
    return await st.read(_state, st)  # the version and the values of one moment


@router.patch("/params")
async def params_patch(request: Request, st: StationDep,
                       caller: OperatorDep) -> contract.ParamsState:
    body = await _json_body(request)
    return await _answer(await st.call(_patch, st, body, version_seen(request),
                                       caller.operator))


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
    values = body["values"] if isinstance(body, dict) and "values" in body else body
    return await _answer(await st.call(_replace, st, values, "params-import",
                                       caller.operator, {}))


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
    values = st.params.read_preset(name)  # the file, read here; the change on the station
    return await _answer(await st.call(_replace, st, values, "preset-load", caller.operator,
                                       {"preset": name}))


@router.delete("/presets/{name}", dependencies=[OPERATOR])
async def preset_delete(name: str, st: StationDep) -> contract.PresetList:
    st.params.delete_preset(name)
    return {"presets": st.params.list_presets()}
