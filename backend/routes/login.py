"""The login URL: sets the cookie that carries the token."""

from __future__ import annotations

from fastapi import APIRouter
from fastapi.requests import HTTPConnection
from fastapi.responses import JSONResponse, RedirectResponse

from ..access import COOKIE, client_of
from .deps import PUBLIC, RuleDep
from .operators import set_name_cookie

router = APIRouter(tags=["login"])


def set_cookie(answer: JSONResponse | RedirectResponse, token: str) -> None:
    # HttpOnly: no script reads it; SameSite=Strict: no other site's request carries it
    answer.set_cookie(COOKIE, token, max_age=30 * 24 * 3600, path="/", httponly=True,
                      samesite="strict")


@router.get("/login", response_model=None, dependencies=[PUBLIC])
async def login(conn: HTTPConnection, rule: RuleDep,
                token: str = "", name: str = "") -> JSONResponse | RedirectResponse:
    """Opened once per laptop with the URL printed at start: sets the cookie that goes
    with every request and the websocket, and opens the page. Anyone may open it: the
    token it carries is checked here (and counted when wrong). ``name``: the operator's
    name the others see (else the page asks for one)."""
    client = client_of(conn.scope)
    left = rule.limiter.blocked(client)
    if left > 0:
        return JSONResponse(status_code=429, content={
            "detail": f"too many wrong tokens from {client}: try again in {left:.0f} s"})
    if not token or rule.role_of(token) is None:
        if token:
            rule.failed(client, token, "/login")
        return JSONResponse(status_code=401, content={"detail": (
            "wrong or missing token: open the URL printed when the station started "
            "(http://HOST:PORT/login?token=...)")})
    answer = RedirectResponse("/", status_code=303)
    set_cookie(answer, token)
    set_name_cookie(answer, name)
    return answer
