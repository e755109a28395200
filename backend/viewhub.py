"""Where the web side and the station meet: the station's views, built on the station thread
(by backend/views.py, through the ``ViewSource`` it is given) at most at the rate someone
reads them and replaced whole, never changed, so a web thread never sees a half-made one; and
what the web side counts for the station's health (``WebStats``)."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any, Protocol

from . import contract
from .jsonsafe import dumps
from .params.model import StationParams
from .processor import Every, Processor
from .replay.player import LogPlayer


def _no_access_rule() -> contract.AccessHealth:
    return {"token_required": False, "view_token": False, "estop_for_all": False,
            "refused": {}, "blocked_clients": 0}


@dataclass
class WebStats:
    """What the web side counts for the station's health: its websocket clients, those it
    dropped for taking nothing (stalled), and who may do what with the refusals so far (the
    app sets ``access`` from its AccessRule). Plain counters the web loop writes."""

    clients: int = 0
    dropped: int = 0
    access: Callable[[], contract.AccessHealth] = field(default=_no_access_rule)


class ViewSource(Protocol):
    """What the hub publishes, built when called (backend/views.py's ``BrowserData``)."""

    def world_version(self) -> tuple[object, ...]: ...

    def world(self) -> contract.World: ...

    def health(self) -> contract.Health: ...

    def geometry(self) -> contract.Geometry | None: ...

    def geometry_seq(self) -> int: ...


@dataclass(frozen=True)
class Views:
    """One publication: the world, health, geometry and player as dicts and as JSON."""

    world_key: tuple[object, ...] = ()
    world: contract.World | None = None
    world_json: str = ""
    health: contract.Health | None = None
    health_json: str = ""
    health_mono: float = -1e9
    geometry: contract.Geometry | None = None
    geometry_seq: int = -1
    player: contract.Player | None = None
    player_json: str = ""
    player_serial: int = -1
    #: counts every publication that changed something (websocket clients wait on it)
    serial: int = 0


class ViewHub:
    """Publishes the views for the websocket clients: what changed only, and nothing while no
    client listens (HTTP answers are built when asked); health at most every 0.25 s."""

    health_period_s = 0.25

    def __init__(self, source: ViewSource, player: LogPlayer) -> None:
        self.source = source
        self.player = player
        self.views = Views()
        self._listeners: set[Callable[[], None]] = set()

    @property
    def listening(self) -> bool:
        return bool(self._listeners)

    def publish(self, force: bool = False) -> None:
        """Builds what changed of the views (on the station thread) and tells the clients."""
        if not force and not self._listeners:
            return
        src, player, v = self.source, self.player, self.views
        changes: dict[str, Any] = {}
        key = src.world_version()
        if force or key != v.world_key:
            world = src.world()
            changes.update(world_key=key, world=world,
                           world_json=dumps({"type": "world", "world": world}, "world"))
        now = time.monotonic()
        if force or now - v.health_mono >= self.health_period_s:
            health = src.health()
            changes.update(health=health, health_mono=now,
                           health_json=dumps({"type": "health", "health": health}, "health"))
        seq = src.geometry_seq()
        if force or seq != v.geometry_seq:
            changes.update(geometry=src.geometry(), geometry_seq=seq)
        if force or player.serial != v.player_serial:
            changes.update(player=player.view(), player_serial=player.serial,
                           player_json=player.json())
        if changes:
            self.views = replace(v, serial=v.serial + 1, **changes)
            self.notify()

    def subscribe(self, listener: Callable[[], None]) -> Callable[[], None]:
        """``listener()`` is called (on the station thread: it must only hand over, e.g. with
        ``loop.call_soon_threadsafe``) after every publication; returns the unsubscribe."""
        self._listeners.add(listener)
        return lambda: self._listeners.discard(listener)

    def notify(self) -> None:
        for listener in list(self._listeners):
            try:
                listener()
            except RuntimeError:  # its web loop has closed
                self._listeners.discard(listener)


class ViewPublisher(Processor):
    """Publishes the station's views at ``stream.ws_max_hz``. Eight cameras merge hundreds of
    frames a second; a page needs no more than it can show."""

    name = "views"

    def __init__(self, hub: ViewHub) -> None:
        super().__init__(Every(60.0))
        self.hub = hub

    def configure(self, params: StationParams) -> None:
        self.set_rate(params.stream.ws_max_hz)

    async def tick(self) -> None:
        self.hub.publish()
