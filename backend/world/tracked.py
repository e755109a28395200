"""The station's world estimate as tracked vision (the league's TrackerWrapperPacket).

So that Touchline's own filtered world can be recorded next to the league's type-5 tracker
records and read by any tool that reads tracked vision (the league's log player, autorefs).
The world is in mm, mm/s, rad, rad/s; tracked vision is in m, m/s, rad, rad/s.

Visibility (0..1): 1 for an object seen now, 0.5 while its position is extrapolated
(``predicted``: not seen for a few frames), 0 once it is lost (frozen, not visible). Lost
objects are still sent, as the league's trackers do, until the world model drops them.
"""

from __future__ import annotations

from sslpb.ssl_gc_common_pb2 import BLUE, YELLOW
from sslpb.ssl_gc_common_pb2 import Team as PbTeam
from sslpb.ssl_vision_wrapper_tracked_pb2 import TrackerWrapperPacket

from .state import Team, WorldState

MM = 0.001  # m per mm
_TEAM: dict[Team, PbTeam.ValueType] = {"yellow": YELLOW, "blue": BLUE}


def _visibility(visible: bool, predicted: bool, lost: bool) -> float:
    if lost or not visible:
        return 0.0
    return 0.5 if predicted else 1.0


def team_enum(team: Team) -> PbTeam.ValueType:
    """The league's Team enum number (YELLOW = 1, BLUE = 2)."""
    return _TEAM[team]


def tracked_packet(world: WorldState, uuid: str, frame_number: int,
                   source_name: str = "Touchline") -> bytes:
    """One TrackerWrapperPacket, serialized. ``uuid`` identifies this station (kept constant
    while it runs); ``frame_number`` increases with each packet. No capabilities yet (one ball
    on the ground, no kick detection)."""
    p = TrackerWrapperPacket(uuid=uuid, source_name=source_name)
    f = p.tracked_frame
    f.frame_number = frame_number
    f.timestamp = world.t_capture
    b = world.ball
    if b is not None:
        tb = f.balls.add(visibility=_visibility(b.visible, b.predicted, b.lost))
        tb.pos.x, tb.pos.y, tb.pos.z = b.x * MM, b.y * MM, 0.0
        tb.vel.x, tb.vel.y, tb.vel.z = b.vx * MM, b.vy * MM, 0.0
    for r in world.robots:
        tr = f.robots.add(orientation=r.orientation, vel_angular=r.omega,
                          visibility=_visibility(r.visible, r.predicted, r.lost))
        tr.robot_id.id = r.id
        tr.robot_id.team = team_enum(r.team)
        tr.pos.x, tr.pos.y = r.x * MM, r.y * MM
        tr.vel.x, tr.vel.y = r.vx * MM, r.vy * MM
    return p.SerializeToString()
