"""The matrices an Octave/MATLAB play gets and returns (API version 1), the paper's way.

A play is a function file ``team/<name>.m`` whose main function is called every tick as::

    orders = name(ours, theirs, ball, game)

with local functions after it in the same file (the paper's several functions in one file).
Matrices have one row a robot; the columns are listed below (1-based in Octave). Units as in
the Python interface: our frame (our goal at negative x), mm, mm/s, rad, m/s for speeds.
``persistent`` variables keep state between ticks; a save of the file starts afresh.
"""

from __future__ import annotations

#: ``ours``: one row per robot of ours on the field (``mine`` = 1 for the robots this play
#: drives; ``ball_contact``: 1 yes, 0 no, NaN the robot does not say)
OURS_COLUMNS: tuple[str, ...] = ("id", "x", "y", "orientation", "vx", "vy", "omega",
                                 "visible", "mine", "ball_contact")
#: ``theirs``: one row per robot of the other team
THEIRS_COLUMNS: tuple[str, ...] = ("id", "x", "y", "orientation", "vx", "vy", "omega",
                                   "visible")
#: ``ball``: one row, or an empty matrix while no ball is known
BALL_COLUMNS: tuple[str, ...] = ("x", "y", "z", "vx", "vy", "visible")
#: ``orders`` (returned): one row per robot to drive. ``mode`` 0: drive to (x, y) with
#: heading ``orientation`` (NaN: keep the heading); ``mode`` 1: velocity in the robot's frame,
#: ``x`` = forward m/s, ``y`` = left m/s, ``orientation`` = turn rad/s. ``max_speed_mps`` NaN
#: or 0: the controller's own limit. ``kick_mps`` 0: no kick. ``chip``, ``dribble``: 0 or 1.
#: A robot of ``mine`` without a row is stopped.
ORDER_COLUMNS: tuple[str, ...] = ("id", "mode", "x", "y", "orientation", "max_speed_mps",
                                  "kick_mps", "chip", "dribble")
#: ``game``: a struct with these fields: t (s), our_team ('blue'/'yellow'), our_side,
#: command (the referee command, '' none), situation (see touchline.game.SituationName),
#: ours (1 our set piece, 0 theirs, NaN neither), designated ([x y] or []), goalkeeper (id or
#: NaN), field (a struct: length, width, goal_width, goal_depth, boundary_width,
#: penalty_area_depth, penalty_area_width, center_circle_radius, robot_radius, ball_radius),
#: topics (a struct of structs: the team processors' outputs), replay (0/1), version
GAME_FIELDS: tuple[str, ...] = ("version", "t", "our_team", "our_side", "command",
                                "situation", "ours", "designated", "goalkeeper", "field",
                                "topics", "replay")
