function spin()
  while true
  end
end
