function varargout = identity(varargin)
  % returns its arguments unchanged (codec round trips)
  varargout = varargin;
end
