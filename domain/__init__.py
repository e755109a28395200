"""The SSL domain, in one place for the backend, fieldsim and the match director: the field
(division A/B, or the geometry packet), teams, angles, and the rules that bind a team (what
each referee command allows, the distances and speeds). Pure code: no I/O, no numpy."""
