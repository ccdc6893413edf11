-- worn_paint.lua: painted steel, worn through along its edges and in patches.
-- One script serves every instance of a mesh: each <MeshInstance> gives its
-- paint colour and how worn it is as <Attribute>s, which getattribute reads
-- (an instance without them takes the mesh's own, then the defaults here).
-- Made for a cube of half-size 0.5 centred on its origin.
params { scale = 2.5 }
local abs, max, min = math.abs, math.max, math.min
local STEEL = vec3(0.56, 0.57, 0.58)

function material(s)
  local tint = getattribute("tint", vec3(0.5))
  local wear = clamp(getattribute("wear", 0), 0, 1)
  -- Near an edge two coordinates are near 0.5: the middle one of the three.
  local x, y, z = abs(s.P.x), abs(s.P.y), abs(s.P.z)
  local mid = x + y + z - max(x, y, z) - min(x, y, z)
  local edge = smoothstep(0.5 - 0.1 * wear, 0.5 - 0.05 * wear, mid)
  -- Patches where the noise rises above a level that wear lowers, each
  -- instance with its own (s.random).
  local n = 0.5 + 0.5 * fbm(s.P * param.scale + vec3(31 * s.random), 5, 2, 0.5, filterwidth(s, param.scale))
  local level = 1 - 0.7 * wear
  local patches = smoothstep(level, level + 0.04, n)
  local bare = max(edge, patches)
  local paint = layer{top = dielectric{ior = 1.5, roughness = 0.25}, base = diffuse{albedo = tint}}
  return mix(paint, conductor{f0 = STEEL, roughness = 0.35}, bare)
end
