-- A brick wall in the x-y plane: running bond, each brick its own shade,
-- mottled, with recessed mortar joints in the height.
-- Parameters: width and height of a brick (0.5, 0.22), mortar (0.025).
-- The parameters a scene's <Parameter> may set, with their defaults.
params {
  width = 0.5,
  height = 0.22,
  mortar = 0.025,
}
local bw, bh, mw = param.width, param.height, param.mortar
-- Colours are picked on a display; srgb() makes them linear (docs/shaders.md).
local mortar_c = srgb(0.62, 0.60, 0.56)
local tones = ramp({ 0, 0.5, 1 }, { srgb(0.45, 0.16, 0.10), srgb(0.60, 0.25, 0.15), srgb(0.70, 0.38, 0.24) })

function height(s)
  local x, y = s.P.x, s.P.y
  local m, id, u, v = brick(x, y, bw, bh, mw)
  -- Soften the joint's edge a little so the bump shows a bevel, not a step.
  local ex = math.min(u, 1 - u) * bw
  local ey = math.min(v, 1 - v) * bh
  local edge = smoothstep(0, 0.012, math.min(ex, ey))
  local rough = 0.002 * fbm(x * 30, y * 30, s.P.z * 30, 3)
  return -0.012 * (1 - edge) * (1 - m) - 0.012 * m + rough
end

function color(s)
  local x, y = s.P.x, s.P.y
  local m, id = brick(x, y, bw, bh, mw)
  if m > 0 then
    local g = 0.9 + 0.1 * fbm(x * 40, y * 40, 0, 2)
    return (mortar_c * g):unpack()
  end
  local r, g, b = tones(hash(id))
  local mottle = 0.85 + 0.2 * fbm(x * 12, y * 12, hash(id, 3) * 10, 4)
  local soot = 1 - 0.25 * smoothstep(0.2, 0.8, fbm(x * 1.5, y * 1.5, 5, 3) + 0.3)
  return r * mottle * soot, g * mottle * soot, b * mottle * soot
end
