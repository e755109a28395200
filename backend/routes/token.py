"""The operator token's rotation (docs/security.md)."""

from __future__ import annotations

import logging

from fastapi import APIRouter
from fastapi.responses import JSONResponse

from ..access import base_url, print_login
from .deps import OperatorDep, RuleDep, SettingsDep
from .login import set_cookie

log = logging.getLogger("touchline.api")

router = APIRouter(prefix="/api/token", tags=["token"])


@router.post("/rotate")
async def token_rotate(rule: RuleDep, settings: SettingsDep,
                       caller: OperatorDep) -> JSONResponse:
    """A new operator token (the operator's only: the current one was checked), written and
    printed; every cookie and script holding the old one is refused."""
    try:
        token = rule.operator.rotate()
    except ValueError as exc:
        return JSONResponse(status_code=409, content={"detail": str(exc)})
    base = base_url(settings.host, settings.port, settings.allowed_hosts)
    print_login(rule, base)
    log.warning("operator token rotated by %s", caller.who)
    answer = JSONResponse({"rotated": True, "login_url": f"{base}/login?token={token}"})
    set_cookie(answer, token)
    return answer
