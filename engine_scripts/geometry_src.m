function ref_array = geometry_src()
  % Several functions in one file, in the URoboRus 2022 paper's style (section 3.1):
  % the source file returns a cell array of handles to its functions. Touchline's
  % OctaveEngine calls them as geometry_src.get_angle, geometry_src.rotate_2d, ...
  % Points are 1x2 rows [x y] or Nx2 matrices (mm); angles in rad.
  ref_array = {...
    @get_angle, ...
    @rotate_2d, ...
    @select_closest_point, ...
    @to_cartesian, ...
    @distance, ...
    @wrap_angle, ...
    @point_segment_distance, ...
    @segment_circle_hit ...
  };
end

function a = get_angle(v1, v2)
  % signed angle turning v1 onto v2, in [-pi, pi)
  a = atan2(v1(:,1).*v2(:,2) - v1(:,2).*v2(:,1), v1(:,1).*v2(:,1) + v1(:,2).*v2(:,2));
  a = wrap_angle(a);
end

function p = rotate_2d(p, angle)
  % rotate rows of p counter-clockwise by angle about the origin
  c = cos(angle); s = sin(angle);
  p = [c.*p(:,1) - s.*p(:,2), s.*p(:,1) + c.*p(:,2)];
end

function [p, idx] = select_closest_point(points, target)
  % the row of points closest to target, and its (1-based) index
  d = hypot(points(:,1) - target(1), points(:,2) - target(2));
  [~, idx] = min(d);
  p = points(idx, :);
end

function p = to_cartesian(r, theta)
  p = [r.*cos(theta), r.*sin(theta)];
end

function d = distance(a, b)
  d = hypot(b(:,1) - a(:,1), b(:,2) - a(:,2));
end

function a = wrap_angle(a)
  % into [-pi, pi), pi becomes -pi: Touchline's convention (domain/angles.py)
  out = ~(a >= -pi & a < pi);
  a(out) = mod(a(out) + pi, 2*pi) - pi;
  a(a >= pi) = -pi;
end

function d = point_segment_distance(p, a, b)
  ab = b - a;
  l2 = sum(ab.^2, 2);
  t = zeros(size(p, 1), 1);
  nz = l2 > 0;
  t(nz) = sum((p(nz,:) - a(nz,:)).*ab(nz,:), 2) ./ l2(nz);
  t = min(max(t, 0), 1);
  q = a + t.*ab;
  d = hypot(p(:,1) - q(:,1), p(:,2) - q(:,2));
end

function [hit, first] = segment_circle_hit(a, b, centers, radii)
  % does segment a-b pass strictly through any circle; first: 1-based index of the first
  % circle entered along a->b, 0 if none
  d = b - a;
  f = a - centers;
  qa = sum(d.^2);
  qb = f*d';
  qc = sum(f.^2, 2) - radii(:).^2;
  disc = qb.^2 - qa.*qc;
  sq = sqrt(max(disc, 0));
  t0 = (-qb - sq)./qa;
  t1 = (-qb + sq)./qa;
  hits = disc > 0 & t0 < 1 & t1 > 0;
  entry = inf(size(t0));
  entry(hits) = max(t0(hits), 0);
  [tmin, first] = min(entry);
  hit = isfinite(tmin);
  if ~hit
    first = 0;
  end
end
