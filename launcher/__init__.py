"""Starts and supervises Touchline's three processes: fieldsim, larcmacs_relay, backend."""
