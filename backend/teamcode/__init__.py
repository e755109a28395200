"""The team's own code in the station (issue 27): the team folder's plays, processors and
libraries, found without running them (``discovery``), watched for saves (``watcher``), run in
worker processes of their own (``worker``, ``host``, ``octave``), their orders checked by the
safety envelope (``envelope``). The interface teams write to is the ``touchline`` package;
docs/team-code.md and docs/team-api.md describe it."""
