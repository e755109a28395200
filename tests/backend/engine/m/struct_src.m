function s = struct_src()
  % a source file exporting its functions as a struct of handles
  s.twice = @twice;
  s.hidden_name = @helper;
end

function y = twice(x)
  y = 2 * x;
end

function y = helper(x)
  y = x - 1;
end
