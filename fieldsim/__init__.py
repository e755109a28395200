"""fieldsim: Touchline's built-in SSL simulator (vision + grSim-style robots over UDP)."""

from fieldsim.config import SimConfig

__all__ = ["SimConfig"]
