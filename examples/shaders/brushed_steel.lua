-- brushed_steel.lua: brushed metal. An anisotropic conductor (its highlight
-- stretched along the surface's tangent, around the y axis on a sphere) with
-- brushing streaks: fine noise stretched along the tangent dims the
-- reflectance and roughens it a little, scratch by scratch.
params { f0 = rgb(0.9, 0.9, 0.88), roughness = 0.4, anisotropy = 1 }

function material(s)
  local p = s.P
  local a = math.atan2(p.x, p.z)                         -- around y, along the brushing
  local streak = fbm(a * 4, p.y * 300, 0.5, 3, 2, 0.5, filterwidth(s, 300))
  local c = conductor{f0 = param.f0 * (0.92 + 0.08 * streak), roughness = param.roughness + 0.05 * streak,
                      anisotropy = param.anisotropy}
  return c
end
