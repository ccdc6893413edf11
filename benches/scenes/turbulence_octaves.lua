-- The course's perlin texture with NumOctaves 4 and absval, as one call of
-- the course_perlin built-in (the code the built-in map runs): the same
-- image as turbulence_builtin.xml, bit for bit. turbulence.lua writes the
-- octave loop in Lua instead.
function color(s)
  local v = course_perlin(s.P, 3, 4, "absval")
  return v, v, v
end
