-- Cobblestones from Voronoi cells: F2 - F1 is the distance to the cell's
-- edge, so stones are rounded domes separated by grout; each stone gets its
-- own colour from its cell id. Parameters: scale (stones per unit, 3).
-- The parameters a scene's <Parameter> may set, with their defaults.
params {
  scale = 3,
}
local sc = param.scale
local rock = ramp({ 0, 0.35, 0.7, 1 }, {
  { 0.42, 0.40, 0.38 }, { 0.55, 0.50, 0.44 }, { 0.50, 0.52, 0.55 }, { 0.62, 0.56, 0.48 },
})

local function cell(s)
  return voronoi(s.P.x * sc, s.P.y * sc, s.P.z * sc)
end

function height(s)
  local f1, f2 = cell(s)
  local edge = f2 - f1
  local dome = smoothstep(0, 0.35, edge)
  return 0.05 * dome / sc + 0.002 * fbm(s.P.x * 25, s.P.y * 25, s.P.z * 25, 3)
end

function color(s)
  local f1, f2, id = cell(s)
  local edge = f2 - f1
  local r, g, b = rock(hash(id))
  local speck = 0.85 + 0.15 * fbm(s.P.x * 30, s.P.y * 30, s.P.z * 30, 3)
  -- Grout, with dirt gathering at the stones' feet.
  local grout = 1 - smoothstep(0.02, 0.08, edge)
  local dirt = 1 - 0.35 * (1 - smoothstep(0.05, 0.3, edge))
  r, g, b = r * speck * dirt, g * speck * dirt, b * speck * dirt
  return mix(r, 0.16, grout), mix(g, 0.14, grout), mix(b, 0.12, grout)
end
