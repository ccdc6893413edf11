-- The contact sheet of docs/patterns.png (examples/scenes/patterns.xml):
-- every pattern of require "patterns" and four warps, each on a tile through
-- one grey color_map, filtered over the pixel's footprint, with its name
-- written under it. The plane is z = 0 seen from +z; a tile is a unit
-- square, (u, v) from -1 to 1 across it.
local P = require "patterns"
local W = P.warp

local grey = P.color_map { { 0, 0.05 }, { 0.5, 0.5 }, { 1, 0.95 } }
local COLUMNS, ROWS = 6, 5
local CELL_W, CELL_H = 1.1, 1.3
local LABEL = 0.2 -- the strip under a tile

-- A slice of pattern space: the point at (u, v) scaled by `scale`, and the
-- footprint's widths on the slice's two axes.
local function xy(u, v, w, scale, z)
  return vec3(u * scale, v * scale, z or 0.5), vec3(w * scale, w * scale, 0)
end
local function xz(u, v, w, scale, y)
  return vec3(u * scale, y or 0.25, v * scale), vec3(w * scale, 0, w * scale)
end

local TILES = {
  { "agate", function(u, v, w) return P.agate(xz(u, v, w, 2)) end },
  { "bozo", function(u, v, w) return P.bozo(xy(u, v, w, 3)) end },
  { "crackle", function(u, v, w) local p, fw = xy(u, v, w, 3) return P.crackle(p, fw) end },
  { "crackle f1", function(u, v, w)
    local p, fw = xy(u, v, w, 3)
    return P.crackle(p, fw, { form = vec3(1.2, 0, 0) })
  end },
  { "dents", function(u, v, w) return P.dents(xy(u, v, w, 3)) end },
  { "granite", function(u, v, w) return P.granite(xy(u, v, w, 1)) end },
  { "leopard", function(u, v, w) return P.leopard(xy(u, v, w, 12, 1.3)) end },
  { "marble", function(u, v, w)
    local p, fw = xy(u, v, w, 2)
    return P.marble(p, fw, { turbulence = 1 })
  end },
  { "onion", function(u, v, w) return P.onion(xy(u, v, w, 3, 0)) end },
  { "ripples", function(u, v, w)
    local p, fw = xy(u, v, w, 1.5, 0)
    return P.ripples(p, fw, { frequency = 4 })
  end },
  { "spiral1", function(u, v, w)
    local p, fw = xy(u, v, w, 3, 0)
    return P.spiral1(p, fw, { arms = 3 })
  end },
  { "spiral2", function(u, v, w)
    local p, fw = xy(u, v, w, 3, 0)
    return P.spiral2(p, fw, { arms = 3 })
  end },
  { "waves", function(u, v, w)
    local p, fw = xy(u, v, w, 1.5, 0)
    return P.waves(p, fw, { frequency = 2 })
  end },
  { "wood", function(u, v, w)
    local p, fw = xy(u, v, w, 3, 0)
    return P.wood(p + vec3(1, 0.5, 0), fw, { turbulence = 0.04 })
  end },
  { "wrinkles", function(u, v, w) return P.wrinkles(xy(u, v, w, 2)) end },
  { "gradient", function(u, v, w)
    local p, fw = xy(u, v, w, 2)
    return P.gradient(p, fw, { direction = vec3(1, 0.5, 0) })
  end },
  { "radial", function(u, v, w)
    local p, fw = xz(u, v, w, 1)
    return P.radial(p, fw, { frequency = 6 })
  end },
  { "hexagon", function(u, v, w)
    local p, fw = xz(u, v, w, 3)
    return P.hexagon(p, fw) / 2
  end },
  { "brick", function(u, v, w)
    local p, fw = xy(u, v, w, 12)
    return P.brick(p, fw)
  end },
  { "boxed", function(u, v, w) return P.boxed(xy(u, v, w, 1.2, 0.3)) end },
  { "spherical", function(u, v, w) return P.spherical(xy(u, v, w, 1.2, 0)) end },
  { "cylindrical", function(u, v, w) return P.cylindrical(xz(u, v, w, 1.2)) end },
  { "planar", function(u, v, w) return P.planar(xy(u, v, w, 1.2, 0)) end },
  { "cells", function(u, v, w) return P.cells(xy(u, v, w, 4)) end },
  { "checker", function(u, v, w) return P.checker(xy(u, v, w, 4)) end },
  { "spotted", function(u, v, w) return P.spotted(xy(u, v, w, 6)) end },
  -- Warps, each on a checker (or a gradient) so the bending shows.
  { "turbulence", function(u, v, w)
    local q, fw = W.turbulence(xy(u, v, w, 3))
    return P.checker(q, fw)
  end },
  { "black_hole", function(u, v, w)
    local p, fw = xy(u, v, w, 4)
    local q, qw = W.black_hole(p, fw, { center = vec3(0.3, -0.2, 0.5), radius = 3, strength = 1.5, falloff = 1.5 })
    return P.checker(q, qw)
  end },
  { "repeat", function(u, v, w)
    local p, fw = xy(u, v, w, 3, 0)
    local q, qw = W["repeat"](p, fw, { direction = vec3(1.5, 0, 0), flip = vec3(1, 0, 0), offset = vec3(0, 0.5, 0) })
    return P.gradient(q, qw, { direction = vec3(1, 1, 0) })
  end },
  { "cyl. map", function(u, v, w)
    local p, fw = xz(u, v, w, 1)
    local q, qw = W.cylindrical(p, fw)
    return P.checker(q * vec3(12, 1, 6), qw * vec3(12, 1, 6))
  end },
}

-- A 3x5 font for the labels: a glyph's five rows, top first.
local FONT = {}
for k, rows in pairs({
  a = ".#./#.#/###/#.#/#.#", b = "##./#.#/##./#.#/##.", c = ".##/#../#../#../.##", d = "##./#.#/#.#/#.#/##.",
  e = "###/#../##./#../###", f = "###/#../##./#../#..", g = ".##/#../#.#/#.#/.##", h = "#.#/#.#/###/#.#/#.#",
  i = "###/.#./.#./.#./###", j = "..#/..#/..#/#.#/.#.", k = "#.#/#.#/##./#.#/#.#", l = "#../#../#../#../###",
  m = "#.#/###/###/#.#/#.#", n = "##./#.#/#.#/#.#/#.#", o = ".#./#.#/#.#/#.#/.#.", p = "##./#.#/##./#../#..",
  q = ".#./#.#/#.#/##./.##", r = "##./#.#/##./#.#/#.#", s = ".##/#../.#./..#/##.", t = "###/.#./.#./.#./.#.",
  u = "#.#/#.#/#.#/#.#/###", v = "#.#/#.#/#.#/#.#/.#.", w = "#.#/#.#/###/###/#.#", x = "#.#/#.#/.#./#.#/#.#",
  y = "#.#/#.#/.#./.#./.#.", z = "###/..#/.#./#../###", ["1"] = ".#./##./.#./.#./###",
  ["2"] = "##./..#/.#./#../###", ["_"] = ".../.../.../.../###", ["."] = ".../.../.../.../.#.",
  [" "] = ".../.../.../.../...",
}) do
  FONT[k] = rows:gsub("/", "")
end

local function lit(text, x, y)
  -- x, y: from the label's centre, in units of one font pixel.
  local n = #text
  local col = math.floor(x + (4 * n - 1) / 2)
  local row = math.floor(2.5 - y)
  if row < 0 or row > 4 or col < 0 or col >= 4 * n then return false end
  local c = col % 4
  if c == 3 then return false end
  local g = FONT[text:sub(math.floor(col / 4) + 1, math.floor(col / 4) + 1)] or FONT[" "]
  local i = row * 3 + c + 1
  return g:sub(i, i) == "#"
end

local BACKGROUND, INK = 0.12, 0.9
local FONT_PIXEL = 0.022

function color(s)
  local x = s.P.x + COLUMNS * CELL_W / 2
  local y = ROWS * CELL_H / 2 - s.P.y
  local col, row = math.floor(x / CELL_W), math.floor(y / CELL_H)
  local g = BACKGROUND
  local tile = TILES[row * COLUMNS + col + 1]
  if tile and col >= 0 and col < COLUMNS then
    -- Within the cell: the tile's top left at (0.05, 0.05).
    local cx, cy = x - col * CELL_W - 0.05, y - row * CELL_H - 0.05
    if cx >= 0 and cx < 1 and cy >= 0 and cy < 1 then
      g = grey(tile[2](cx * 2 - 1, 1 - cy * 2, s.filterwidth * 2)).x
    elseif cx >= 0 and cx < 1 and cy >= 1 and cy < 1 + LABEL then
      local lx, ly = (cx - 0.5) / FONT_PIXEL, (1 + LABEL / 2 - cy) / FONT_PIXEL
      if lit(tile[1], lx, ly) then g = INK end
    end
  end
  return 255 * g, 255 * g, 255 * g
end
