function die()
  exit(3);
end
