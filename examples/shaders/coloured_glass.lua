-- coloured_glass.lua: smooth glass whose transmission tint runs from amber
-- at the bottom to ruby at the top, as in a cased art-glass ball. The tint
-- colours light each time it crosses the surface; reflections stay white.
params { low = rgb(1.0, 0.7, 0.15), high = rgb(0.9, 0.1, 0.25) }

function material(s)
  local t = smoothstep(-0.6, 0.6, s.P.y / 0.5)
  local c = dielectric{ior = 1.5, tint = mix(param.low, param.high, t)}
  return c
end
