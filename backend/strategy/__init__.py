"""Strategy: who goes where (plays, roles, assignment, paths, the classroom formations)."""
