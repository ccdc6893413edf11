-- studio_floor.lua: the matte grey floor of closures.xml.
params { albedo = 0.12 }

function material(s)
  local c = diffuse{albedo = param.albedo, roughness = 0.5}
  return c
end
