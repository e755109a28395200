"""larcmacs_relay: the only Touchline process that speaks SSL UDP (see README.md)."""

from larcmacs_relay.config import RelayConfig
from larcmacs_relay.relay import Relay, run_relay

__all__ = ["Relay", "RelayConfig", "run_relay"]
