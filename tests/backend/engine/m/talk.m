function y = talk(x)
  disp("hello from octave")
  printf("no newline")
  y = x + 1
end
