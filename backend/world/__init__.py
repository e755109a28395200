"""World model: merges camera frames into one state per object (pure code, no I/O)."""
