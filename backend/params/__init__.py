"""Server-owned parameters: typed models with ranges and units, validated, versioned,
persisted atomically, broadcast to every client."""
