"""What the web side reads: the station's views, built on the station thread (from
backend/views.py) at most at the rate someone reads them and replaced whole, never changed,
so a web thread never sees a half-made one."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

from . import contract
from .jsonsafe import dumps
from .params.model import StationParams
from .processor import Every, Processor

if TYPE_CHECKING:
    from .station import Station


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

    def __init__(self, station: Station) -> None:
        self.station = station
        self.views = Views()
        self._listeners: set[Callable[[], None]] = set()

    @property
    def listening(self) -> bool:
        return bool(self._listeners)

    def world_version(self) -> tuple[object, ...]:
        """Changes whenever the world message would: a new world, a referee message, the
        e-stop, why the robots are stopped (that changes while no world is written: vision
        lost), or the internal referee (its panel follows the world message)."""
        st = self.station
        ir, rs = st.internal_referee, st.referee_state
        return (st.world_topic.seq, st.referee_topic.seq, st.estop, st.player.serial,
                st.armed, st.arming_required,
                st.control.halt_reason, rs.command_counter,
                ir.enabled, ir.foreign_active(), rs.max_allowed_bots("blue"),
                rs.max_allowed_bots("yellow"), rs.blue.score, rs.yellow.score)

    def publish(self, force: bool = False) -> None:
        """Builds what changed of the views (on the station thread) and tells the clients."""
        if not force and not self._listeners:
            return
        st, v = self.station, self.views
        changes: dict[str, Any] = {}
        key = self.world_version()
        if force or key != v.world_key:
            world = st.world_dict()
            changes.update(world_key=key, world=world,
                           world_json=dumps({"type": "world", "world": world}, "world"))
        now = time.monotonic()
        if force or now - v.health_mono >= self.health_period_s:
            health = st.health()
            changes.update(health=health, health_mono=now,
                           health_json=dumps({"type": "health", "health": health}, "health"))
        if force or st.geometry_topic.seq != v.geometry_seq:
            changes.update(geometry=st.geometry(), geometry_seq=st.geometry_topic.seq)
        if force or st.player.serial != v.player_serial:
            changes.update(player=st.player.view(), player_serial=st.player.serial,
                           player_json=st.player.json())
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
