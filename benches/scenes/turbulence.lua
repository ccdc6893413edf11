-- The course's perlin texture with NumOctaves 4 and absval (4-octave
-- turbulence) on the course_noise built-in: the same image as the built-in
-- map of turbulence_builtin.xml.
local abs = math.abs
function color(s)
  local sum, w, total, f = 0, 1, 0, 3
  for _ = 1, 4 do
    sum = sum + w * abs(course_noise(s.P.x * f, s.P.y * f, s.P.z * f))
    total = total + w
    w, f = w * 0.5, f * 2
  end
  local v = sum / total
  return v, v, v
end

function height(s)
  return 0.02 * fbm(s.P.x * 8, s.P.y * 8, s.P.z * 8, 4)
end
