-- A planet: one fBm height makes continents (above sea level) and ocean
-- depths; colour by elevation and latitude, polar ice, and a cloud layer.
-- The bump uses the same height, flat over the sea. Parameters: sea (sea
-- level, 0.05), seed (moves the continents, 0).
local abs, max = math.abs, math.max
-- The parameters a scene's <Parameter> may set, with their defaults.
params {
  sea = 0.05,
  seed = 0,
}
local sea = param.sea
local seed = param.seed
local land = ramp({ 0, 0.08, 0.3, 0.55, 0.8 }, {
  { 0.76, 0.70, 0.50 }, { 0.22, 0.45, 0.16 }, { 0.36, 0.42, 0.20 }, { 0.45, 0.36, 0.28 }, { 0.92, 0.92, 0.95 },
})
local ocean = ramp({ 0, 0.3, 1 }, { { 0.10, 0.32, 0.55 }, { 0.04, 0.16, 0.40 }, { 0.02, 0.06, 0.22 } })

local function elevation(s)
  local p = normalize(s.P)
  return fbm(p.x * 1.6 + seed, p.y * 1.6, p.z * 1.6, 7, 2.1, 0.5)
end

function height(s)
  return 0.03 * max(elevation(s) - sea, 0)
end

function color(s)
  local e = elevation(s) - sea
  local p = normalize(s.P)
  local r, g, b
  if e > 0 then
    r, g, b = land(e * 1.6)
  else
    r, g, b = ocean(-e * 2.5)
  end
  -- Ice: above a latitude that wavers with noise, and on high ground.
  local lat = abs(p.y) + 0.08 * fbm(p.x * 5, p.y * 5, p.z * 5, 3)
  local ice = smoothstep(0.78, 0.84, lat + max(e, 0) * 0.3)
  r, g, b = mix(r, 0.93, ice), mix(g, 0.95, ice), mix(b, 0.98, ice)
  -- Clouds: swirled fBm, thinned so there are gaps.
  local q = p * 2.2
  local swirl = fbm(q.x, q.y * 2, q.z, 3)
  local cl = smoothstep(0.15, 0.6, fbm(q.x + swirl, q.y * 2.5, q.z - swirl, 6))
  return mix(r, 1, cl * 0.85), mix(g, 1, cl * 0.85), mix(b, 1, cl * 0.85)
end
