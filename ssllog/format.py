"""Constants of the SSL log format: 16-byte header, big-endian record headers."""

from __future__ import annotations

import struct
from typing import Final

HEADER_MAGIC: Final = b"SSL_LOG_FILE"
VERSION: Final = 1
FILE_HEADER: Final = struct.Struct(">12si")
HEADER_SIZE: Final = FILE_HEADER.size  # 16
RECORD_HEADER: Final = struct.Struct(">qii")  # receive time ns, type, payload size
RECORD_HEADER_SIZE: Final = RECORD_HEADER.size  # 16

TYPE_BLANK: Final = 0
TYPE_UNKNOWN: Final = 1
TYPE_VISION_2010: Final = 2
TYPE_REFEREE_2013: Final = 3
TYPE_VISION_2014: Final = 4
TYPE_TRACKER_2020: Final = 5
TYPE_INDEX_2021: Final = 6
KNOWN_TYPES: Final = frozenset(range(7))

# Touchline's own record types (docs/logformat.md). The league's tools (ssl-go-tools) skip
# types they do not know, so a Touchline log still plays in the league's log player.
TYPE_TL_COMMANDS: Final = 1001  # touchline.RobotCommandSet protobuf: the commands sent
TYPE_TL_PARAMS: Final = 1002  # UTF-8 JSON {"version", "changes", "by"}
TYPE_TL_ACTION: Final = 1003  # UTF-8 JSON {"action", "by", ...details}: an operator action
TYPE_TL_HEALTH: Final = 1004  # UTF-8 JSON: the station's health, once a second
TYPE_TL_SESSION: Final = 1005  # UTF-8 JSON, first in each file: {"touchline": 1, ...}
TYPE_TL_TEAM: Final = 1006  # UTF-8 JSON {"name", "values"}: a team processor's outputs
TOUCHLINE_TYPES: Final = frozenset(range(1001, 1007))
INDEX_TRAILER: Final = b"INDEXED"
# a payload larger than this is taken as corruption, not data
MAX_PAYLOAD: Final = 64 * 1024 * 1024


def file_header() -> bytes:
    return FILE_HEADER.pack(HEADER_MAGIC, VERSION)
