"""Backend settings: one typed model, defaults in code, flags override (see __main__)."""

from __future__ import annotations

from pathlib import Path

from pydantic import BaseModel, Field

from sslnet import defaults

ROOT = Path(__file__).resolve().parent.parent


class Settings(BaseModel):
    host: str = "127.0.0.1"
    port: int = defaults.BACKEND_PORT
    relay_pub: str = defaults.RELAY_PUB  # the relay's PUB we subscribe to
    relay_sub: str = defaults.RELAY_SUB  # the relay's SUB we publish commands to
    our_team: str = Field(default="blue", pattern="^(blue|yellow)$")
    our_side: int = -1  # -1: our goal at negative x
    demo: bool = True  # drive our robots between formation points until given targets
    control_rate_max_wait_s: float = 0.05  # control runs at least this often
    vision_stale_s: float = 0.3  # no vision for this long: command zero
    ws_max_hz: float = 60.0
    static_dir: Path = ROOT / "frontend" / "dist"
    allowed_origins: list[str] = Field(
        default_factory=lambda: ["http://localhost:5173", "http://127.0.0.1:5173"]
    )
    topic_sizes: dict[str, int] = Field(
        default_factory=lambda: {
            "vision-packets": 64,
            "referee-packets": 30,
            "vision-detections": 64,
            "geometry": 4,
            "referee": 30,
            "world": 30,
            "operator-targets": 30,
            "targets": 10,
            "robot-commands": 20,
            "sim-commands": 20,
            "relay-stats": 10,
            "estop": 10,
        }
    )
