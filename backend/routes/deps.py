"""Typed dependencies of the routes (the full-stack-fastapi-template's ``api/deps.py``): the
station, the access rule, the settings, and **who may call a route**.

Every route states its access with one of ``ViewerDep``/``OperatorDep``/``EstopDep``/
``PublicDep`` (as a parameter when it uses the caller, else in ``dependencies=[...]``):
the rule lives beside the route, a test walks ``app.routes`` and fails on a state-changing
route without one, and docs/api.md's table of who may call what is generated from them.

The AccessGuard middleware (backend.access) stays the first line of defence: it reads the
credential once, counts wrong tokens, answers 429 to a blocked address and refuses a websocket
before it is accepted; it leaves the caller's role (None: no or a wrong token) in
``scope[ROLE_KEY]``. The dependencies decide from that role what this route allows.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Annotated, Any, Literal
from urllib.parse import unquote

from fastapi import Depends, FastAPI, HTTPException, WebSocketException
from fastapi.dependencies.models import Dependant
from fastapi.requests import HTTPConnection
from fastapi.routing import iter_route_contexts

from sslnet.ratelog import RateLimitedLog

from ..access import (
    NEED_OPERATOR,
    NEED_VIEWER,
    ROLE_KEY,
    AccessRule,
    Role,
    client_of,
    is_loopback,
)
from ..config import Settings
from ..operators import Who, clean_name
from ..station import Station

log = logging.getLogger("touchline.access")
_ratelog = RateLimitedLog(log, interval_s=30.0)

Access = Literal["anyone", "viewer", "operator", "estop"]


#: the name given at login (``/login?name=`` or the page's own prompt); not a secret
NAME_COOKIE = "touchline_name"


@dataclass(frozen=True)
class Caller:
    """Who calls: the role the credential gives (None: none or a wrong one; every caller is
    the operator where no token is required), the client's address and the operator's name
    (its cookie; "local" on loopback, else "unnamed")."""

    role: Role | None
    address: str
    name: str = ""

    @property
    def operator(self) -> Who:
        """As the operators' list and the driving lock know it: a name at an address."""
        name = self.name or "unnamed"
        return Who(f"{name}@{self.address}", name, self.role or "operator", self.address)

    @property
    def who(self) -> str:
        """For the session log, the action list and the e-stop's ``by``."""
        return str(self.operator)


def name_of(conn: HTTPConnection) -> str:
    address = client_of(conn.scope)
    return clean_name(unquote(conn.cookies.get(NAME_COOKIE, ""))) or (
        "local" if is_loopback(address) else "unnamed")


def who_of(conn: HTTPConnection) -> Who:
    """The operator behind a request or websocket (the role the AccessGuard found)."""
    role = str(conn.scope.get(ROLE_KEY) or "operator")
    address = client_of(conn.scope)
    name = name_of(conn)
    return Who(f"{name}@{address}", name, role, address)


def get_station(conn: HTTPConnection) -> Station:
    station: Station = conn.app.state.station
    return station


def get_rule(conn: HTTPConnection) -> AccessRule:
    rule: AccessRule = conn.app.state.access
    return rule


def get_settings(conn: HTTPConnection) -> Settings:
    settings: Settings = conn.app.state.settings
    return settings


StationDep = Annotated[Station, Depends(get_station)]
RuleDep = Annotated[AccessRule, Depends(get_rule)]
SettingsDep = Annotated[Settings, Depends(get_settings)]


def _caller(conn: HTTPConnection, rule: AccessRule) -> Caller:
    role: Role | None = "operator" if not rule.required else conn.scope.get(ROLE_KEY)
    return Caller(role, client_of(conn.scope), name_of(conn))


def _refuse(conn: HTTPConnection, rule: AccessRule, status: int, reason: str,
            key: str) -> HTTPException | WebSocketException:
    rule.refused[key] = rule.refused.get(key, 0) + 1
    _ratelog.warning(f"access-{key}", "refused %s %s from %s: %s",
                     conn.scope.get("method", "websocket"), conn.url.path,
                     client_of(conn.scope), reason)
    if conn.scope["type"] == "websocket":  # the guard refused it before; a second line
        return WebSocketException(code=1008, reason=reason[:120])
    return HTTPException(status, reason)


def anyone(conn: HTTPConnection, rule: RuleDep) -> Caller:
    """Open to anyone (the login page checks its token itself)."""
    return _caller(conn, rule)


def viewer(conn: HTTPConnection, rule: RuleDep) -> Caller:
    """Reading: anyone, or with ``--view-token`` the viewer or operator token."""
    caller = _caller(conn, rule)
    if caller.role is None and rule.viewer is not None:
        raise _refuse(conn, rule, 401, NEED_VIEWER, "no viewer token")
    return Caller(caller.role or "viewer", caller.address, caller.name)


def operator(conn: HTTPConnection, rule: RuleDep) -> Caller:
    """Changing something: the operator token (every caller where none is required)."""
    caller = _caller(conn, rule)
    if caller.role != "operator":
        raise _refuse(conn, rule, 401, NEED_OPERATOR, "no operator token")
    return caller


def estop(conn: HTTPConnection, rule: RuleDep) -> Caller:
    """The emergency stop: a viewer reaches the route, which applies the e-stop rule to what
    the body asks (``backend.access.estop_refusal``: press or release)."""
    return viewer(conn, rule)


#: why a caller off this machine may not save team code (docs/security.md)
CODE_EDIT_REFUSED = ("saving team code from another machine needs a station started with "
                     "--allow-code-edit: the code runs on the station's machine "
                     "(docs/security.md)")


def code_edit_refusal(caller: Caller, settings: Settings) -> str | None:
    """Why ``caller`` may not save team code, or None: an operator (as for parameters) on
    loopback; from another machine an operator of a station started with
    ``--allow-code-edit`` only."""
    if caller.role != "operator":
        return NEED_OPERATOR
    if not is_loopback(caller.address) and not settings.allow_code_edit:
        return CODE_EDIT_REFUSED
    return None


def code_editor(conn: HTTPConnection, caller: Annotated[Caller, Depends(operator)],
                settings: SettingsDep) -> Caller:
    """Saving team code: the operator (``operator``, 401 without the token), and off
    loopback only with ``--allow-code-edit`` (403 with the reason)."""
    why = code_edit_refusal(caller, settings)
    if why is not None:
        rule = get_rule(conn)
        raise _refuse(conn, rule, 403, why, "code edit")
    return caller


PublicDep = Annotated[Caller, Depends(anyone)]
ViewerDep = Annotated[Caller, Depends(viewer)]
OperatorDep = Annotated[Caller, Depends(operator)]
EstopDep = Annotated[Caller, Depends(estop)]
CodeEditorDep = Annotated[Caller, Depends(code_editor)]
#: for ``dependencies=[...]`` where the route does not use the caller
PUBLIC, VIEWER, OPERATOR = Depends(anyone), Depends(viewer), Depends(operator)

ACCESS: dict[Callable[..., Any], Access] = {
    anyone: "anyone", viewer: "viewer", operator: "operator", estop: "estop"}


def access_of(route: Any) -> Access | None:
    """The access a route's dependencies give it (the strictest if several; the router's
    own count), or None: no access dependency, or no dependencies at all (FastAPI's
    ``/openapi.json`` and ``/docs``, which are plain Starlette routes)."""
    dependant: Dependant | None = getattr(route, "dependant", None)
    if dependant is None:
        return None
    order: list[Access] = ["anyone", "viewer", "estop", "operator"]
    found = -1
    stack = list(dependant.dependencies)
    while stack:
        dep = stack.pop()
        if dep.call in ACCESS:
            found = max(found, order.index(ACCESS[dep.call]))
        stack += dep.dependencies
    return order[found] if found >= 0 else None


def route_access(app: FastAPI) -> list[tuple[str, str, Access | None]]:
    """(method, path, access) of every route of the app, as it serves them (routers included
    with their prefixes and dependencies); ``WEBSOCKET`` for a websocket, no ``HEAD``."""
    out: list[tuple[str, str, Access | None]] = []
    for ctx in iter_route_contexts(app.routes):
        path = ctx.path
        if path is None:  # a mount (the page's files)
            continue
        methods = ctx.methods
        access = access_of(ctx)
        for m in sorted(methods - {"HEAD"}) if methods is not None else ["WEBSOCKET"]:
            out.append((m, path, access))
    return out


def refusal_before_body(conn: HTTPConnection) -> HTTPException | None:
    """The route's access refusal for a request whose body FastAPI could not parse (it
    answers 422 before any dependency runs): a caller without the right token is told 401,
    as for a well-formed body, not what was wrong with a body it may not send anyway."""
    check = {"viewer": viewer, "operator": operator, "estop": estop}.get(
        access_of(conn.scope.get("route")) or "")
    if check is None:
        return None
    try:
        check(conn, get_rule(conn))
    except HTTPException as exc:
        return exc
    return None
