"""Default addresses and ports of the SSL world and of Touchline (see DESIGN.md section 2)."""

from __future__ import annotations

VISION_GROUP = "224.5.23.2"
VISION_PORT_REAL = 10006
VISION_PORT_SIM = 10020
TRACKER_PORT = 10010
REFEREE_GROUP = "224.5.23.1"
REFEREE_PORT = 10003

SIM_CONTROL_PORT = 10300
SIM_BLUE_PORT = 10301
SIM_YELLOW_PORT = 10302
GRSIM_COMMAND_PORT = 20011
GRSIM_STATUS_BLUE_PORT = 30011  # grSim Robots_Status to the sender of the last command
GRSIM_STATUS_YELLOW_PORT = 30012
ROBOT_BOX_PORT = 10000

# Touchline ZeroMQ endpoints (relay binds both).
RELAY_PUB = "tcp://127.0.0.1:5570"
RELAY_SUB = "tcp://127.0.0.1:5571"

# Seed LARCmaCS compatibility endpoints.
COMPAT_VISION_PUB = "tcp://127.0.0.1:4242"
COMPAT_REFEREE_PUB = "tcp://127.0.0.1:4243"
COMPAT_COMMANDS = "tcp://127.0.0.1:5667"

BACKEND_PORT = 8000
