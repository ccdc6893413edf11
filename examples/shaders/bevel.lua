-- bevel.lua: rounded edges without modelling them. bevel() averages the
-- normals of the surface within `radius` of the point, as Cycles' Bevel node
-- does; as a replace_normal map listed before the others, every map after it
-- shades with the rounded normal. Indirect rays take fewer samples.
params { radius = 0.06 }

function normal(s)
  return bevel(s, param.radius, s.depth == 0 and 8 or 2)
end
