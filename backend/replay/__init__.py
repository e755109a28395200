"""Replay: recorded sessions (SSL log files) fed through the station's pipeline."""
