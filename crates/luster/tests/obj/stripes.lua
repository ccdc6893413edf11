-- A test shader for tests/obj.rs: stripes of the object-space position,
-- tinted by the texture coordinates (so a uv mismatch shows), and a wavy
-- height for bump_shader. Parameter: scale (stripes per unit, 2).
local sin, max = math.sin, math.max
local sc = (param.scale or 2) * 6.2832

function color(s)
  local a = max(sin(s.P.x * sc) * sin(s.P.y * sc + s.P.z * 3), 0)
  return 0.25 + 0.6 * a, 0.3 + 0.4 * s.uv.u, 0.75 - 0.5 * a * s.uv.v
end

function height(s)
  return 0.03 * sin(s.P.x * sc) * sin(s.P.z * sc + s.P.y * 2)
end
