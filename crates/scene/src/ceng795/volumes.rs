//! `<Volumes>`: luster's extension of the CENG795 format for participating
//! media and hypertextures (see the README's "Volumes" section).
//!
//! ```xml
//! <Volumes>
//!     <Volume id="cloud">
//!         <Sphere><Center>0 1 0</Center><Radius>1</Radius></Sphere>
//!         <Transformations>s1</Transformations>
//!         <Shader>shaders/cloud.lua</Shader>
//!         <Parameter name="scale">2</Parameter>
//!         <Density>4</Density>
//!         <Absorption>0.2 0.2 0.2</Absorption>
//!         <Scattering>1 1 1</Scattering>
//!     </Volume>
//!     <Volume id="plume">
//!         <VdbFile>volumes/plume.vdb</VdbFile>
//!         <EmissionGrid>temperature</EmissionGrid>
//!         <Emission>3000 1000 200</Emission>
//!     </Volume>
//!     <Hypertexture id="fuzz">
//!         <Box><Min>-1 -1 -1</Min><Max>1 1 1</Max></Box>
//!         <Material>1</Material>
//!         <Shader>shaders/fuzzy.lua</Shader>
//!         <Threshold>0.5</Threshold>
//!     </Hypertexture>
//! </Volumes>
//! ```
//!
//! | element | reads | default |
//! |---|---|---|
//! | bound (one of) | `Sphere` (`Center` x y z, `Radius`), `Box` (`Min`, `Max`), `Ellipsoid` (`Center`, `Radii`, optional `Rotation` = angle ax ay az) — coordinates inline, in the volume's space; with a `VdbFile` it clips the grids | required, except with a `VdbFile`: the box of its grids' active voxels |
//! | `Transformations` | named transforms, as for objects | none |
//! | `Shader`, `Parameter` | a script defining `density(s)` (media may add `emission(s)`), read as for shader maps | none: constant density |
//! | `VdbFile` (media) | an OpenVDB file (path relative to the scene's folder) whose float grid is the density, in the file's world space; not with a `Shader` | none |
//! | `DensityGrid`, `EmissionGrid` (media, with `VdbFile`) | the density grid's name; a grid whose value times `Emission` is the emission per unit length (instead of `Emission` × density) | `density`, none |
//! | `Density` | the constant density, or a factor on the script's or the VDB grid's | 1 |
//! | `StepSize` | ray-marching step, world units | 1/64 of the bound's world diagonal; with a `VdbFile`, a voxel's smallest world edge |
//! | `GridResolution` | bake the script's density (and emission) on N³ points (2 to 512, at most 1 GiB of samples) | none: exact |
//! | `Absorption`, `Scattering` (media) | σa, σs per unit length at density 1 | 1 1 1, 0 0 0 |
//! | `Emission` (media) | emitted radiance per unit length at density 1 | 0 0 0 |
//! | `Anisotropy` (media) | Henyey–Greenstein g, −0.99 to 0.99 | 0 |
//! | `ScatteringOctaves` (media) | terms of the multiple-scattering approximation, 1 to 8 (1: single scattering) | 1 |
//! | `Material`, `Threshold`, `Textures` (hypertextures) | the surface's material, the density of the surface, its texture maps | required, 0.5, none |
//! | `Attribute name` | what the volume's scripts read with `getattribute` (see [`super::attributes`]) | none |

use super::objects::radii_and_rotation;
use super::shader_map;
use super::textures::object_textures;
use super::transforms::compose;
use super::Warnings;
use crate::description::{BoundDesc, VdbDesc, VolumeDesc, VolumeKind};
use crate::element::{Element, Reader};
use crate::error::SceneError;
use luster_core::math::Transform;
use std::collections::HashMap;
use std::path::Path;

/// Largest `GridResolution`: 512³ floats are half a gigabyte.
pub const MAX_GRID: u32 = 512;

/// Most `ScatteringOctaves`: each halves the last one's contribution.
pub const MAX_OCTAVES: u32 = 8;

/// What volume reading needs from the rest of the file.
pub struct Context<'a> {
    /// Typed reading with errors naming the file.
    pub r: Reader<'a>,
    /// Material id to index.
    pub materials: &'a HashMap<&'a str, usize>,
    /// Texture map id to index.
    pub textures: &'a HashMap<&'a str, usize>,
    /// Named transforms.
    pub transforms: &'a HashMap<String, Transform>,
    /// Folder of the scene file.
    pub base_dir: &'a Path,
}

const COMMON: [&str; 10] = [
    "Sphere",
    "Box",
    "Ellipsoid",
    "Transformations",
    "Shader",
    "Parameter",
    "Density",
    "StepSize",
    "GridResolution",
    super::attributes::CHILD,
];

/// Reads every `Volume` and `Hypertexture` of a `Volumes` element.
pub fn read_all(ctx: &Context, el: &Element, w: &mut Warnings) -> Result<Vec<VolumeDesc>, SceneError> {
    w.unknown_children(el, &["Volume", "Hypertexture"]);
    let r = &ctx.r;
    let mut out = Vec::new();
    for v in &el.children {
        let kind = match v.name.as_str() {
            "Volume" => {
                let extra = [
                    "Absorption",
                    "Scattering",
                    "Emission",
                    "Anisotropy",
                    "ScatteringOctaves",
                    "VdbFile",
                    "DensityGrid",
                    "EmissionGrid",
                ];
                w.unknown_children(v, &[&COMMON[..], &extra[..]].concat());
                let c = super::media::coefficients(r, v)?;
                let octaves = match v.child("ScatteringOctaves") {
                    Some(o) => {
                        let n = r.uint(o)?;
                        if !(1..=MAX_OCTAVES).contains(&n) {
                            return Err(r.err(
                                o,
                                format!("<ScatteringOctaves> must be 1 to {MAX_OCTAVES}, found {n}"),
                            ));
                        }
                        n
                    }
                    None => 1,
                };
                VolumeKind::Medium {
                    octaves,
                    absorption: c.absorption,
                    scattering: c.scattering,
                    emission: c.emission,
                    anisotropy: c.anisotropy,
                }
            }
            "Hypertexture" => {
                if let Some(f) = v.child("VdbFile") {
                    return Err(r.err(
                        f,
                        "<VdbFile> is for media (<Volume>); a <Hypertexture> takes its density from a <Shader>",
                    ));
                }
                let extra = ["Material", "Threshold", "Textures"];
                w.unknown_children(v, &[&COMMON[..], &extra[..]].concat());
                let m = r.required(v, "Material")?;
                let id = m.text.trim();
                let material = *ctx
                    .materials
                    .get(id)
                    .ok_or_else(|| r.err(m, format!("material \"{id}\" is not defined in <Materials>")))?;
                let threshold = r.float_or(v, "Threshold", 0.5)?;
                if !threshold.is_finite() {
                    return Err(r.err(v, "<Threshold> must be finite"));
                }
                let textures = match v.child("Textures") {
                    Some(t) => object_textures(r, t, ctx.textures)?,
                    None => Vec::new(),
                };
                VolumeKind::Surface { material, threshold, textures }
            }
            _ => continue,
        };
        out.push(volume(ctx, v, kind)?);
    }
    Ok(out)
}

/// The parts every volume has.
fn volume(ctx: &Context, v: &Element, kind: VolumeKind) -> Result<VolumeDesc, SceneError> {
    let r = &ctx.r;
    let density = r.float_or(v, "Density", 1.0)?;
    if density < 0.0 || !density.is_finite() {
        return Err(r.err(
            v.child("Density").unwrap_or(v),
            format!("<Density> must be finite and ≥ 0, found {density}"),
        ));
    }
    let step = match v.child("StepSize") {
        Some(s) => {
            let x = r.float(s)?;
            if !(x > 0.0 && x.is_finite()) {
                return Err(r.err(s, format!("<StepSize> must be positive, found {x}")));
            }
            Some(x)
        }
        None => None,
    };
    let vdb = vdb_file(r, v, ctx.base_dir)?;
    if let (Some(f), Some(_)) = (&vdb, v.child("Shader")) {
        return Err(SceneError::at(
            r.file,
            &f.loc,
            "a <Volume> takes its density from a <Shader> or a <VdbFile>, not both",
        ));
    }
    let script = match v.child("Shader") {
        Some(_) => Some(shader_map::script(r, v, ctx.base_dir)?),
        None => None,
    };
    let grid = match v.child("GridResolution") {
        Some(g) => {
            if vdb.is_some() {
                return Err(
                    r.err(g, "<GridResolution> bakes a <Shader>; a <VdbFile>'s voxels are already a grid")
                );
            }
            let n = r.uint(g)?;
            if !(2..=MAX_GRID).contains(&n) {
                return Err(r.err(g, format!("<GridResolution> must be 2 to {MAX_GRID}, found {n}")));
            }
            if script.is_none() {
                return Err(r.err(g, "<GridResolution> needs a <Shader>: a constant density needs no grid"));
            }
            Some(n)
        }
        None => None,
    };
    if script.is_none() && matches!(kind, VolumeKind::Surface { .. }) {
        return Err(r.err(v, "a <Hypertexture> needs a <Shader> whose density(s) gives its shape"));
    }
    let transform = match v.child("Transformations") {
        Some(t) => compose(r, t, ctx.transforms)?,
        None => Transform::IDENTITY,
    };
    Ok(VolumeDesc {
        id: v.attr("id").unwrap_or("").trim().to_string(),
        bound: bound(r, v, vdb.is_some())?,
        transform,
        density,
        script,
        vdb,
        step,
        grid,
        kind,
        loc: v.loc.clone(),
        attributes: super::attributes::read(r, v)?,
    })
}

/// A medium's `VdbFile` with its grid names, or `None` when it has none
/// (then naming a grid is an error).
fn vdb_file(r: &Reader, v: &Element, base_dir: &Path) -> Result<Option<VdbDesc>, SceneError> {
    let Some(f) = v.child("VdbFile") else {
        return match ["DensityGrid", "EmissionGrid"].iter().find_map(|n| v.child(n)) {
            Some(g) => {
                Err(r.err(g, format!("<{}> names a grid of a <VdbFile>, and this volume has none", g.name)))
            }
            None => Ok(None),
        };
    };
    let rel = f.text.trim();
    if rel.is_empty() {
        return Err(r.err(f, "<VdbFile> names no file"));
    }
    let grid = |name: &str| match v.child(name) {
        Some(g) if g.text.trim().is_empty() => Err(r.err(g, format!("<{name}> names no grid"))),
        Some(g) => Ok(Some(g.text.trim().to_string())),
        None => Ok(None),
    };
    Ok(Some(VdbDesc {
        path: base_dir.join(rel),
        density_grid: grid("DensityGrid")?.unwrap_or_else(|| "density".to_string()),
        emission_grid: grid("EmissionGrid")?,
        loc: f.loc.clone(),
    }))
}

/// The one bound child of a volume; `None` when it has none and `optional`
/// (a VDB file's grids then bound it).
fn bound(r: &Reader, v: &Element, optional: bool) -> Result<Option<BoundDesc>, SceneError> {
    let found: Vec<&Element> =
        v.children.iter().filter(|c| matches!(c.name.as_str(), "Sphere" | "Box" | "Ellipsoid")).collect();
    let b = match found[..] {
        [b] => b,
        [] if optional => return Ok(None),
        [] => return Err(r.err(v, format!("<{}> needs a bound: <Sphere>, <Box> or <Ellipsoid>", v.name))),
        _ => return Err(r.err(found[1], format!("<{}> has more than one bound", v.name))),
    };
    Ok(Some(match b.name.as_str() {
        "Sphere" => {
            let re = r.required(b, "Radius")?;
            let radius = r.float(re)?;
            if !(radius > 0.0 && radius.is_finite()) {
                return Err(r.err(re, format!("<Radius> must be positive, found {radius}")));
            }
            BoundDesc::Sphere { center: r.vec3(r.required(b, "Center")?)?, radius }
        }
        "Box" => {
            let (lo, hi) = (r.required(b, "Min")?, r.required(b, "Max")?);
            let (min, max) = (r.vec3(lo)?, r.vec3(hi)?);
            if !(min.cmplt(max).all() && min.is_finite() && max.is_finite()) {
                return Err(r.err(b, "<Min> must be below <Max> on every axis"));
            }
            BoundDesc::Box { min, max }
        }
        _ => {
            let (radii, rotation) = radii_and_rotation(r, b)?;
            BoundDesc::Ellipsoid { center: r.vec3(r.required(b, "Center")?)?, radii, rotation }
        }
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The volumes of `<Volumes>{inner}</Volumes>`, read beside `/scenes/s.xml`.
    fn read(inner: &str) -> Result<Vec<VolumeDesc>, SceneError> {
        let file = Path::new("/scenes/s.xml");
        let el = crate::xml::parse(file, &format!("<Volumes>{inner}</Volumes>"))?;
        let materials = HashMap::from([("m", 0)]);
        let (textures, transforms) = (HashMap::new(), HashMap::new());
        let ctx = Context {
            r: Reader { file },
            materials: &materials,
            textures: &textures,
            transforms: &transforms,
            base_dir: Path::new("/scenes"),
        };
        read_all(&ctx, &el, &mut Warnings::default())
    }

    fn refused(inner: &str, words: &[&str]) {
        let e = read(inner).expect_err("the volume should be refused").to_string();
        for w in words {
            assert!(e.contains(w), "{e:?} lacks {w:?}");
        }
    }

    const BALL: &str = "<Sphere><Center>0 0 0</Center><Radius>1</Radius></Sphere>";

    #[test]
    fn a_vdb_file_needs_no_bound_and_names_its_grids() {
        let v = read("<Volume id=\"p\"><VdbFile> vdb/plume.vdb </VdbFile></Volume>").unwrap();
        let f = v[0].vdb.as_ref().unwrap();
        assert_eq!(f.path, Path::new("/scenes/vdb/plume.vdb"));
        assert_eq!((f.density_grid.as_str(), f.emission_grid.as_deref()), ("density", None));
        assert!(f.loc.path.ends_with("Volume[id=p]/VdbFile"), "{}", f.loc.path);
        assert_eq!(v[0].bound, None);
        assert!(v[0].script.is_none());

        let v = read(&format!(
            "<Volume id=\"p\">{BALL}<VdbFile>a.vdb</VdbFile><DensityGrid>smoke</DensityGrid>\
             <EmissionGrid>flame</EmissionGrid></Volume>"
        ))
        .unwrap();
        let f = v[0].vdb.as_ref().unwrap();
        assert_eq!((f.density_grid.as_str(), f.emission_grid.as_deref()), ("smoke", Some("flame")));
        assert!(matches!(v[0].bound, Some(BoundDesc::Sphere { .. })));
    }

    #[test]
    fn vdb_mistakes_are_refused() {
        refused(
            &format!("<Volume id=\"p\">{BALL}<VdbFile>a.vdb</VdbFile><Shader>d.lua</Shader></Volume>"),
            &["Volume[id=p]/VdbFile", "<Shader> or a <VdbFile>, not both"],
        );
        refused("<Volume id=\"p\"><VdbFile> </VdbFile></Volume>", &["<VdbFile> names no file"]);
        refused(
            "<Volume id=\"p\"><VdbFile>a.vdb</VdbFile><EmissionGrid></EmissionGrid></Volume>",
            &["<EmissionGrid> names no grid"],
        );
        refused(
            &format!("<Volume id=\"p\">{BALL}<DensityGrid>smoke</DensityGrid></Volume>"),
            &["Volume[id=p]/DensityGrid", "has none"],
        );
        refused(
            "<Volume id=\"p\"><VdbFile>a.vdb</VdbFile><GridResolution>64</GridResolution></Volume>",
            &["<GridResolution>", "already a grid"],
        );
        refused(
            &format!(
                "<Hypertexture id=\"h\">{BALL}<Material>m</Material><VdbFile>a.vdb</VdbFile></Hypertexture>"
            ),
            &["Hypertexture[id=h]/VdbFile", "for media"],
        );
        refused("<Volume id=\"p\"><Density>2</Density></Volume>", &["Volume[id=p]", "needs a bound"]);
    }

    #[test]
    fn negative_coefficients_and_anisotropy_outside_the_open_interval_are_refused() {
        for name in ["Absorption", "Scattering", "Emission"] {
            refused(
                &format!("<Volume id=\"v\">{BALL}<{name}>0.5 -0.1 0</{name}></Volume>"),
                &[&format!("Volume[id=v]/{name}"), "finite and ≥ 0"],
            );
        }
        for g in ["1", "-1", "1.5", "-7", "NaN"] {
            refused(
                &format!("<Volume id=\"v\">{BALL}<Anisotropy>{g}</Anisotropy></Volume>"),
                &["Volume[id=v]/Anisotropy"],
            );
        }
        let v = read(&format!("<Volume id=\"v\">{BALL}<Anisotropy>-0.99</Anisotropy></Volume>")).unwrap();
        assert!(matches!(v[0].kind, VolumeKind::Medium { anisotropy, .. } if anisotropy == -0.99));
    }
}
