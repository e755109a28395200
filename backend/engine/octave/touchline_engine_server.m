function touchline_engine_server(req_path, resp_path)
  % Touchline OctaveEngine worker loop (see backend/engine/octave_engine.py).
  % For each 8-byte token on stdin: read the request file, call the function, write the response
  % file, print the done marker. Values use the binary format of backend/engine/mcodec.py.
  more off;
  page_screen_output(false);
  crash_dumps_octave_core(false);
  exports = struct();
  mark = char(30);
  printf("%sTOUCHLINE_READY\n", mark);
  fflush(stdout);
  while true
    % a request token is exactly 8 bytes ("%07d\n"): fread of a fixed count returns at
    % once, while fgetl on a pipe waits for the next line's first byte
    [token, count] = fread(stdin, 8, "uint8=>char");
    if count < 8
      break;  % stdin closed: the engine is gone
    end
    line = strtrim(token');
    try
      fid = fopen(req_path, "r", "ieee-le");
      req = tl_read(fid);
      fclose(fid);
      name = req{1};
      nout = req{2};
      args = req{3};
      [fn, exports] = tl_resolve(name, exports);
      out = cell(1, nout);
      if nout == 0
        fn(args{:});
      else
        [out{1:nout}] = fn(args{:});
      end
      tl_respond(resp_path, out);
    catch err
      tl_respond_error(resp_path, err);
    end
    printf("\n%sTOUCHLINE_DONE %s\n", mark, line);
    fflush(stdout);
  end
end

function [fn, exports] = tl_resolve(name, exports)
  dot = find(name == ".", 1);
  if isempty(dot)
    fn = str2func(name);
    return;
  end
  file = name(1:dot-1);
  fname = name(dot+1:end);
  if ~isfield(exports, file)
    % the paper's source-file convention: FILE() returns a cell array (or a struct) of
    % handles to the functions defined in FILE.m
    if ~any(exist(file) == [2 3 5])
      error("touchline:engine", "no function file %s.m on the path", file);
    end
    try
      refs = feval(file);
    catch err
      error("touchline:engine", "%s.%s: calling %s() for the functions it exports failed: %s", file, fname, file, err.message);
    end
    table = struct();
    if iscell(refs)
      for k = 1:numel(refs)
        if ~is_function_handle(refs{k})
          error("touchline:engine", "%s() returned a cell whose element %d is not a function handle", file, k);
        end
        key = func2str(refs{k});
        if key(1) == "@"
          key = key(2:end);
        end
        table.(key) = refs{k};
      end
    elseif isstruct(refs)
      names = fieldnames(refs);
      for k = 1:numel(names)
        table.(names{k}) = refs.(names{k});
      end
    else
      error("touchline:engine", "%s() must return a cell array or struct of function handles to export functions", file);
    end
    exports.(file) = table;
  end
  table = exports.(file);
  if ~isfield(table, fname)
    error("touchline:engine", "%s exports no function %s (it exports: %s)", file, fname, strjoin(fieldnames(table)', ", "));
  end
  fn = table.(fname);
end

function tl_respond(path, out)
  fid = fopen(path, "w", "ieee-le");
  try
    fwrite(fid, 0, "uint8");
    tl_write(fid, out);
    fclose(fid);
  catch err
    fclose(fid);
    tl_respond_error(path, err);
  end
end

function tl_respond_error(path, err)
  fid = fopen(path, "w", "ieee-le");
  fwrite(fid, 1, "uint8");
  tb = sprintf("error: %s", err.message);
  for k = 1:numel(err.stack)
    s = err.stack(k);
    if ~isempty(strfind(s.name, "touchline_engine_server"))
      continue;
    end
    tb = [tb, sprintf("\n    at %s (%s, line %d)", s.name, s.file, s.line)];
  end
  tl_write(fid, err.message);
  tl_write(fid, tb);
  fclose(fid);
end

function v = tl_read(fid)
  tag = char(fread(fid, 1, "uint8"));
  switch tag
    case "n"
      v = [];
    case "d"
      dims = tl_dims(fid);
      v = reshape(fread(fid, prod(dims), "float64=>double"), dims);
    case "l"
      dims = tl_dims(fid);
      v = reshape(logical(fread(fid, prod(dims), "uint8=>uint8")), dims);
    case "s"
      n = fread(fid, 1, "uint32");
      v = char(fread(fid, [1 n], "uint8=>uint8"));
      if n == 0
        v = "";
      end
    case "c"
      dims = tl_dims(fid);
      v = cell(dims);
      for k = 1:numel(v)
        v{k} = tl_read(fid);
      end
    case "r"
      n = fread(fid, 1, "uint32");
      v = struct();
      for k = 1:n
        key = tl_read(fid);
        v.(key) = tl_read(fid);
      end
    otherwise
      error("touchline:engine", "bad value tag %d in request", double(tag));
  end
end

function dims = tl_dims(fid)
  nd = fread(fid, 1, "uint32");
  dims = fread(fid, [1 nd], "uint32=>double");
end

function tl_write_dims(fid, v)
  d = size(v);
  fwrite(fid, numel(d), "uint32");
  fwrite(fid, d, "uint32");
end

function tl_write(fid, v)
  if ischar(v)
    if rows(v) <= 1
      fwrite(fid, "s", "uint8");
      fwrite(fid, numel(v), "uint32");
      fwrite(fid, double(v), "uint8");
    else
      tl_write(fid, cellstr(v));
    end
  elseif islogical(v)
    fwrite(fid, "l", "uint8");
    tl_write_dims(fid, v);
    fwrite(fid, double(full(v(:))), "uint8");
  elseif isnumeric(v)
    if ~isreal(v)
      error("touchline:engine", "complex results are not supported");
    end
    fwrite(fid, "d", "uint8");
    tl_write_dims(fid, v);
    fwrite(fid, double(full(v(:))), "float64");
  elseif iscell(v)
    fwrite(fid, "c", "uint8");
    tl_write_dims(fid, v);
    for k = 1:numel(v)
      tl_write(fid, v{k});
    end
  elseif isstruct(v) && isscalar(v)
    names = fieldnames(v);
    fwrite(fid, "r", "uint8");
    fwrite(fid, numel(names), "uint32");
    for k = 1:numel(names)
      tl_write(fid, names{k});
      tl_write(fid, v.(names{k}));
    end
  else
    error("touchline:engine", "cannot return a value of class %s (size %s)", class(v), mat2str(size(v)));
  end
end
