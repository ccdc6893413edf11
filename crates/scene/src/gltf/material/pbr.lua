-- gltf_pbr.lua: a glTF 2.0 material (metallic-roughness and the KHR material
-- extensions) as OpenPBR, built into luster (docs/gltf-materials.md).
-- luster fills the parameters from the glTF file: factors already clamped
-- and combined where no texture varies them, and the textures the material
-- has, each in a slot with its image, uv transform and sampler.

local SLOTS = 12
local decl = {
  base_color = rgb(1), alpha = 1,
  alpha_mode = 0,          -- 0 opaque, 1 mask, 2 blend
  alpha_cutoff = 0.5,
  metallic = 1, roughness = 1,
  emission = rgb(0),       -- emissiveFactor
  emission_scale = 0,      -- 255 × KHR_materials_emissive_strength (0: no emission)
  ior = 1.5, specular = 1, specular_color = rgb(1),
  transmission = 0, transmission_tint = rgb(1), thin = 0,
  coat = 0, coat_roughness = 0,
  sheen = 0, sheen_color = rgb(0), sheen_roughness = 0,
  unlit = 0,
  -- The slot each texture is in, 0 for none; the channel is glTF's.
  base_tex = 0, alpha_tex = 0, metallic_tex = 0, roughness_tex = 0, emission_tex = 0,
  transmission_tex = 0, coat_tex = 0, coat_roughness_tex = 0, sheen_color_tex = 0,
  sheen_roughness_tex = 0, specular_tex = 0, specular_color_tex = 0,
}
for k = 1, SLOTS do
  decl["image" .. k] = ""                    -- the image's name in the scene
  decl["u" .. k] = vec3(1, 0, 0)             -- u' = x u + y v + z (KHR_texture_transform)
  decl["v" .. k] = vec3(0, 1, 0)             -- v' = x u + y v + z
  decl["sampler" .. k] = vec3(0, 0, 0)       -- wrap s, wrap t (0 repeat, 1 clamp, 2 mirror), 1 for nearest
  decl["texel" .. k] = vec3(0, 0, 0)         -- half a texel across and down
end
params(decl)

local floor = math.floor
local P = param

-- The slots in use, 1 to n, as arrays the per-call loop reads.
local n = 0
local name, ua, ub, uc, va, vb, vc, ws, wt, filt, hu, hv, su, sv = {}, {}, {}, {}, {}, {}, {}, {}, {}, {},
  {}, {}, {}, {}
for k = 1, SLOTS do
  if P["image" .. k] ~= "" then
    n = k
    local u, v, s, h = P["u" .. k], P["v" .. k], P["sampler" .. k], P["texel" .. k]
    name[k] = P["image" .. k]
    ua[k], ub[k], uc[k] = u.x, u.y, u.z
    va[k], vb[k], vc[k] = v.x, v.y, v.z
    ws[k], wt[k] = s.x, s.y
    filt[k] = s.z == 1 and "nearest" or "bilinear"
    hu[k], hv[k] = h.x, h.y
    -- texture() centres texel i at i / width, glTF at (i + ½) / width: a
    -- bilinear lookup moves by half a texel (a nearest one needs no move).
    if s.z == 1 then su[k], sv[k] = 0, 0 else su[k], sv[k] = h.x, h.y end
  end
end

local BR, BG, BB = P.base_color.x, P.base_color.y, P.base_color.z
local ALPHA, ALPHA_MODE, CUTOFF = P.alpha, P.alpha_mode, P.alpha_cutoff
local METAL, ROUGH = P.metallic, P.roughness
local ER, EG, EB, ESCALE = P.emission.x, P.emission.y, P.emission.z, P.emission_scale
local IOR, SPEC = P.ior, P.specular
local SR, SG, SB = P.specular_color.x, P.specular_color.y, P.specular_color.z
local TRANS, THIN = P.transmission, P.thin == 1
local TR, TG, TB = P.transmission_tint.x, P.transmission_tint.y, P.transmission_tint.z
local COAT, COAT_ROUGH = P.coat, P.coat_roughness
local SHEEN, HR, HG, HB, SHEEN_ROUGH = P.sheen, P.sheen_color.x, P.sheen_color.y, P.sheen_color.z,
  P.sheen_roughness
local UNLIT = P.unlit == 1
local T_BASE, T_ALPHA, T_METAL, T_ROUGH, T_EMIT = P.base_tex, P.alpha_tex, P.metallic_tex, P.roughness_tex,
  P.emission_tex
local T_TRANS, T_COAT, T_COAT_ROUGH = P.transmission_tex, P.coat_tex, P.coat_roughness_tex
local T_SHEEN, T_SHEEN_ROUGH, T_SPEC, T_SPEC_COLOR = P.sheen_color_tex, P.sheen_roughness_tex, P.specular_tex,
  P.specular_color_tex

-- A wrapped coordinate: repeat is texture()'s own; clamp stops at the edge
-- texels' centres; mirror reflects every other repeat.
local function wrap(x, mode, half)
  if mode == 1 then
    if x < half then return half end
    if x > 1 - half then return 1 - half end
  elseif mode == 2 then
    x = x - 2 * floor(x * 0.5)
    if x > 1 then return 2 - x end
  end
  return x
end

-- This call's texels, per slot.
local R, G, B = {}, {}, {}
local function fetch(u, v)
  for k = 1, n do
    local x = wrap(ua[k] * u + ub[k] * v + uc[k], ws[k], hu[k]) - su[k]
    local y = wrap(va[k] * u + vb[k] * v + vc[k], wt[k], hv[k]) - sv[k]
    R[k], G[k], B[k] = texture(name[k], x, y, filt[k])
  end
end

-- openpbr{}'s arguments: one table per thread, reused on every call, with
-- only the parameters this material sets (openpbr{} checks each key it is
-- given) and colours as {r, g, b} tables updated in place, so a call
-- allocates nothing.
local args = {}
local BASE, SPEC_C, TINT, EMIT, FUZZ = { BR, BG, BB }, { SR, SG, SB }, { BR * TR, BG * TG, BB * TB },
  { ER, EG, EB }, { HR, HG, HB }
if UNLIT then
  args.base_weight, args.specular_weight = 0, 0
  args.emission_luminance, args.emission_color = 255, BASE
else
  args.base_color, args.base_metalness, args.specular_roughness = BASE, METAL, ROUGH
  if IOR ~= 1.5 then args.specular_ior = IOR end
  if SPEC ~= 1 or T_SPEC > 0 then args.specular_weight = SPEC end
  if SR ~= 1 or SG ~= 1 or SB ~= 1 or T_SPEC_COLOR > 0 then args.specular_color = SPEC_C end
  if TRANS > 0 then
    args.transmission_weight, args.transmission_color = TRANS, TINT
    if THIN then args.geometry_thin_walled = true end
  end
  if COAT > 0 then args.coat_weight, args.coat_roughness, args.coat_ior = COAT, COAT_ROUGH, 1.5 end
  if SHEEN > 0 then args.fuzz_weight, args.fuzz_color, args.fuzz_roughness = SHEEN, FUZZ, SHEEN_ROUGH end
  if ESCALE > 0 then args.emission_luminance, args.emission_color = ESCALE, EMIT end
end
if ALPHA_MODE > 0 then args.geometry_opacity = 1 end

function material(s)
  if n > 0 then
    local uv = s.uv
    fetch(uv.u, uv.v)
    if T_BASE > 0 then
      local br, bg, bb = BR * R[T_BASE], BG * G[T_BASE], BB * B[T_BASE]
      BASE[1], BASE[2], BASE[3] = br, bg, bb
      if TRANS > 0 then TINT[1], TINT[2], TINT[3] = br * TR, bg * TG, bb * TB end
    end
    if not UNLIT then
      if T_METAL > 0 then args.base_metalness = METAL * B[T_METAL] end
      if T_ROUGH > 0 then args.specular_roughness = ROUGH * G[T_ROUGH] end
      if ESCALE > 0 and T_EMIT > 0 then EMIT[1], EMIT[2], EMIT[3] = ER * R[T_EMIT], EG * G[T_EMIT], EB * B[T_EMIT] end
      if T_SPEC > 0 then args.specular_weight = SPEC * R[T_SPEC] end
      if T_SPEC_COLOR > 0 then
        SPEC_C[1], SPEC_C[2], SPEC_C[3] = SR * R[T_SPEC_COLOR], SG * G[T_SPEC_COLOR], SB * B[T_SPEC_COLOR]
      end
      if TRANS > 0 and T_TRANS > 0 then args.transmission_weight = TRANS * R[T_TRANS] end
      if COAT > 0 then
        if T_COAT > 0 then args.coat_weight = COAT * R[T_COAT] end
        if T_COAT_ROUGH > 0 then args.coat_roughness = COAT_ROUGH * G[T_COAT_ROUGH] end
      end
      if SHEEN > 0 then
        if T_SHEEN > 0 then FUZZ[1], FUZZ[2], FUZZ[3] = HR * R[T_SHEEN], HG * G[T_SHEEN], HB * B[T_SHEEN] end
        if T_SHEEN_ROUGH > 0 then args.fuzz_roughness = SHEEN_ROUGH * R[T_SHEEN_ROUGH] end
      end
    end
  end
  if ALPHA_MODE > 0 then
    local a = ALPHA
    if T_ALPHA > 0 then a = a * R[T_ALPHA] end
    if ALPHA_MODE == 1 then
      args.geometry_opacity = a >= CUTOFF and 1 or 0
    else
      args.geometry_opacity = a
    end
  end
  local c = openpbr(args)
  return c
end
