-- velvet.lua: crushed velvet. A sheen lobe (bright at grazing angles) over a
-- dark diffuse; an fbm pattern weights the sheen, like pile pressed flat.
params { color = rgb(0.06, 0.005, 0.03), sheen_color = rgb(0.95, 0.35, 0.6), crush = 4 }

function material(s)
  local pile = clamp(0.8 + 0.6 * fbm(s.P * param.crush, 4), 0, 1)   -- crushed patches shine less
  local fuzz = sheen{color = param.sheen_color, roughness = 0.5}
  local c = layer{top = pile * fuzz, base = diffuse{albedo = param.color, roughness = 0.8}}
  return c
end
