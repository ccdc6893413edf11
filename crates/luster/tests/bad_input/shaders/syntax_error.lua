-- A missing "then" on line 3.
function color(s)
  if s.P.x > 0 return 1, 1, 1 end
  return 0, 0, 0
end
