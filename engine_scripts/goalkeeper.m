function target = goalkeeper(ball, vel, goal_x, goal_width, margin, min_speed)
  % Goalkeeper target on the goal line (mm, mm/s), the rule of
  % backend.geometry.goalkeeper_target: if the ball moves towards the goal line faster
  % than min_speed along x, stand where its straight path crosses x = goal_x; otherwise
  % where the bisector of the angle the goal mouth (posts at goal_x, +-goal_width/2) makes
  % at the ball crosses it. Clamp to the goal mouth shrunk by margin on each side.
  %   ball, vel: 1x2 [x y] or Nx2; returns [goal_x y] rows.
  if nargin < 5
    margin = 0;
  end
  if nargin < 6
    min_speed = 100;
  end
  towards = (goal_x - ball(:,1)).*vel(:,1);
  moving = towards > 0 & abs(vel(:,1)) > min_speed;
  h = goal_width/2;
  dx = ball(:,1) - goal_x;
  d1 = sqrt(dx.*dx + (ball(:,2) - h).*(ball(:,2) - h));
  d2 = sqrt(dx.*dx + (ball(:,2) + h).*(ball(:,2) + h));
  s = d1 + d2;
  y = ball(:,2);
  ok = s > 0;
  y(ok) = h*(d2(ok) - d1(ok))./s(ok);
  y(moving) = ball(moving,2) + (goal_x - ball(moving,1)).*vel(moving,2)./vel(moving,1);
  lim = max(goal_width/2 - margin, 0);
  y = min(max(y, -lim), lim);
  target = [repmat(goal_x, size(y)), y];
end
