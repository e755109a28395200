function c = class_of(x)
  c = [class(x), " ", mat2str(size(x))];
end
