function orders = keeper_wall(ours, theirs, ball, game)
  % Keeper and wall (Octave, the paper's style)
  % Our goalkeeper (the referee's, else robot 0 if it is ours, else our lowest id) keeps goal
  % between ball and goal centre; the others stand as a wall in front of our defence area. Several functions in one file: keeper_spot and
  % wall_spots below. Try changing WALL_GAP or the keeper's distance from the line.
  %
  % ours: one row a robot (id x y orientation vx vy omega visible mine ball_contact),
  % ball: [x y z vx vy visible] or [], game: a struct (see docs/team-api.md).
  % orders: one row a robot (id mode x y orientation max_speed_mps kick_mps chip dribble).
  mine = ours(ours(:, 9) == 1, :);
  orders = zeros(0, 9);
  if isempty(mine)
    return;
  end
  ids = sort(mine(:, 1));
  keeper = game.goalkeeper;
  if isnan(keeper)
    keeper = 0;
  end
  if any(ids == keeper)
    ids = [keeper; ids(ids ~= keeper)];  % the keeper first
  end
  if isempty(ball)
    b = [0 0];
  else
    b = ball(1, 1:2);
  end
  f = game.field;
  [kx, ky, kface] = keeper_spot(b, f);
  orders(end + 1, :) = [ids(1) 0 kx ky kface NaN 0 0 0];
  spots = wall_spots(b, f, numel(ids) - 1);
  for k = 2:numel(ids)
    orders(end + 1, :) = [ids(k) 0 spots(k - 1, 1) spots(k - 1, 2) 0 NaN 0 0 0];
  end
end

function [x, y, face] = keeper_spot(b, f)
  % on our goal line, between the ball and the goal centre, inside the goal mouth
  x = -f.length / 2 + f.robot_radius + 30;
  y = max(-f.goal_width / 2 + f.robot_radius, min(f.goal_width / 2 - f.robot_radius, b(2) / 3));
  face = atan2(b(2) - y, b(1) - x);
end

function spots = wall_spots(b, f, n)
  % n robots side by side on the line from our goal centre to the ball, just outside our
  % defence area
  WALL_GAP = 2 * f.robot_radius + 80;
  goal = [-f.length / 2, 0];
  d = b - goal;
  d = d / max(norm(d), 1);
  base = goal + d * (f.penalty_area_depth + f.robot_radius + 250);
  side = [-d(2), d(1)];
  spots = zeros(n, 2);
  for k = 1:n
    offset = (k - (n + 1) / 2) * WALL_GAP;
    spots(k, :) = base + side * offset;
  end
end
