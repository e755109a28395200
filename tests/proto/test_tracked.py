"""Tracked vision (TrackerWrapperPacket) against bytes built by hand from the league's field
numbers (ssl-game-controller's ssl_vision_wrapper_tracked.proto, _detection_tracked.proto)."""

from __future__ import annotations

import struct

from sslpb.ssl_gc_common_pb2 import BLUE, YELLOW
from sslpb.ssl_vision_detection_tracked_pb2 import CAPABILITY_DETECT_KICKED_BALLS
from sslpb.ssl_vision_wrapper_tracked_pb2 import TrackerWrapperPacket
from tests.wire import f32, f64, ld, uv

# TrackerWrapperPacket{uuid="ab", source_name="TL", tracked_frame{frame_number=5,
#   timestamp=2.5, balls[{pos{1, -2, 0.5}, vel{0.25, 0, 0}, visibility=1}],
#   robots[{robot_id{id=3, team=BLUE}, pos{0.5, 1}, orientation=0.25, vel{1, 0},
#     vel_angular=2, visibility=0.5}],
#   kicked_ball{pos{0, 0}, vel{4, 0, 1}, start_timestamp=2, stop_pos{3, 0},
#     robot_id{id=1, team=YELLOW}},
#   capabilities=[CAPABILITY_DETECT_KICKED_BALLS]}}
BALL = (ld(1, f32(1, 1.0) + f32(2, -2.0) + f32(3, 0.5))
        + ld(2, f32(1, 0.25) + f32(2, 0) + f32(3, 0)) + f32(3, 1.0))
ROBOT = (ld(1, uv(1, 3) + uv(2, 2)) + ld(2, f32(1, 0.5) + f32(2, 1.0)) + f32(3, 0.25)
         + ld(4, f32(1, 1.0) + f32(2, 0)) + f32(5, 2.0) + f32(6, 0.5))
KICK = (ld(1, f32(1, 0) + f32(2, 0)) + ld(2, f32(1, 4.0) + f32(2, 0) + f32(3, 1.0))
        + f64(3, 2.0) + ld(5, f32(1, 3.0) + f32(2, 0)) + ld(6, uv(1, 1) + uv(2, 1)))
FRAME = uv(1, 5) + f64(2, 2.5) + ld(3, BALL) + ld(4, ROBOT) + ld(5, KICK) + uv(6, 3)
WRAPPER = ld(1, b"ab") + ld(2, b"TL") + ld(3, FRAME)


def test_tag_bytes_by_hand() -> None:
    # field 1 (uuid), wire type 2: 1 << 3 | 2 = 0x0a; source_name 0x12; tracked_frame 0x1a
    assert WRAPPER[:8] == b"\x0a\x02ab\x12\x02TL" and WRAPPER[8] == 0x1a
    # frame_number: field 1 varint 0x08; timestamp: field 2 double (wire type 1) 0x11
    assert FRAME[:11] == b"\x08\x05\x11" + struct.pack("<d", 2.5)
    # capabilities: field 6 varint (proto2 repeated enum, not packed) 0x30
    assert FRAME[-2:] == b"\x30\x03"


def test_tracker_wrapper_decodes_hand_built_bytes() -> None:
    p = TrackerWrapperPacket()
    p.ParseFromString(WRAPPER)
    assert p.IsInitialized()
    assert (p.uuid, p.source_name) == ("ab", "TL")
    f = p.tracked_frame
    assert (f.frame_number, f.timestamp) == (5, 2.5)
    b = f.balls[0]
    assert (b.pos.x, b.pos.y, b.pos.z, b.vel.x, b.visibility) == (1.0, -2.0, 0.5, 0.25, 1.0)
    r = f.robots[0]
    assert (r.robot_id.id, r.robot_id.team) == (3, BLUE)
    assert (r.pos.x, r.pos.y, r.orientation, r.vel.x, r.vel_angular, r.visibility) == (
        0.5, 1.0, 0.25, 1.0, 2.0, 0.5)
    k = f.kicked_ball
    assert (k.vel.x, k.vel.z, k.start_timestamp, k.stop_pos.x) == (4.0, 1.0, 2.0, 3.0)
    assert not k.HasField("stop_timestamp")
    assert (k.robot_id.id, k.robot_id.team) == (1, YELLOW)
    assert list(f.capabilities) == [CAPABILITY_DETECT_KICKED_BALLS]
    assert p.SerializeToString() == WRAPPER  # and encodes to the same bytes


def test_uuid_is_required() -> None:
    p = TrackerWrapperPacket()
    p.tracked_frame.frame_number = 1
    p.tracked_frame.timestamp = 0.0
    assert not p.IsInitialized()
    p.uuid = "x"
    assert p.IsInitialized()
