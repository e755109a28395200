"""Touchline backend: the paper's strategy-bridge (Data Bus + Processors) hosted by FastAPI."""
