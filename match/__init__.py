"""`make match`: a whole 6 v 6 match on the built-in simulator, directed and judged by Touchline.

``match.director`` is the game controller + autoref as a pure state machine, ``match.shell`` its
I/O (truth in, Referee multicast and ball teleports out), ``match.runner`` starts and tears down
the processes, ``match.report`` prints and writes the result."""
