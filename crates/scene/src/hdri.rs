//! An HDRI lighting any loaded scene (`--env FILE [--env-rotate DEG]
//! [--env-strength S]`): a latitude-longitude `.hdr` or `.exr` image becomes
//! the scene's environment light and background.
//!
//! | flag | meaning |
//! |---|---|
//! | `--env FILE` | the image (`.hdr` or `.exr`, any aspect; lat-long as Blender and Mitsuba read it) |
//! | `--env-rotate DEG` | turns the map about `+y`, counter-clockwise seen from above (default 0) |
//! | `--env-strength S` | scales it (default 1; finite, at least 0) |
//!
//! Units: a texel of 1.0 is display white (the film's 255), so the light's
//! radiance is `value × 255 × S`. Orientation: `--env-rotate 0` shows the
//! picture Blender's world shows with an Environment Texture node and no
//! mapping (after its OBJ/glTF import turns `+y` up into `+z` up): the
//! image's centre is `+x`, a quarter across is `-z`, three quarters is `+z`.
//! In hw5's orientation (the course's `SphericalDirectionalLight`, whose
//! centre is `-z`) that is a turn of −90°, which
//! [`EnvironmentLightDesc::rotation`] holds.
//!
//! A scene's own `SphericalDirectionalLight` is replaced (with a warning).
//! A model scene's [`Studio`] goes: its key, fill and ambient lights, and its
//! course materials take the normalized Blinn-Phong (a reflectance is an
//! albedo, as in Blender); its camera path-traces with MIS, as Cycles does.
//! The ground plane stays.

use crate::description::{
    BrdfDesc, BrdfKind, Description, EnvMapping, EnvSampling, EnvironmentLightDesc, ImageDesc,
    PathParamsDesc, RendererDesc, Studio,
};
use crate::error::{Loc, SceneError, Warning};
use std::path::{Path, PathBuf};

/// The turn from hw5's orientation (centre `-z`) to Blender's (centre
/// `+x`), counter-clockwise seen from above.
pub const BLENDER_FROM_HW5: f32 = -90.0;

/// The film's display white: a texel of 1.0 lights as much.
pub const WHITE: f32 = 255.0;

/// An HDRI given on the command line.
#[derive(Clone, Debug, PartialEq)]
pub struct Hdri {
    /// The image file.
    pub path: PathBuf,
    /// `--env-rotate`: degrees about `+y`, counter-clockwise seen from above.
    pub rotation: f32,
    /// `--env-strength`: factor on the image's values (1.0 is display white).
    pub strength: f32,
}

impl Hdri {
    /// An HDRI, or a sentence saying what is wrong with the file's name or
    /// the numbers. The image itself is read when the scene is built.
    pub fn new(path: &Path, rotation: f32, strength: f32) -> Result<Hdri, SceneError> {
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        if !matches!(ext.as_deref(), Some("hdr" | "exr")) {
            return Err(SceneError::file(
                path,
                "--env needs a linear high-dynamic-range image, .hdr (Radiance) or .exr (OpenEXR)",
            ));
        }
        if !rotation.is_finite() {
            return Err(SceneError::file(path, "--env-rotate must be a finite number of degrees"));
        }
        // A finite strength above 1.3e36 would still overflow once times 255.
        if !(strength >= 0.0 && (WHITE * strength).is_finite()) {
            return Err(SceneError::file(path, "--env-strength must be a number from 0 to 1e36"));
        }
        Ok(Hdri { path: path.to_path_buf(), rotation, strength })
    }

    /// Makes the HDRI `desc`'s environment light and background, in place of
    /// its `SphericalDirectionalLight` or its studio (see the module).
    pub fn apply(&self, desc: &mut Description) {
        let loc = Loc { line: None, path: "--env".into() };
        if let Some(old) = &desc.environment_light {
            desc.warnings.push(Warning {
                loc: old.loc.clone(),
                message: "--env replaces the scene's SphericalDirectionalLight".into(),
            });
        }
        if let Some(studio) = desc.studio.take() {
            remove_studio(desc, &studio, &loc);
        }
        desc.images.push(ImageDesc::file("--env".into(), self.path.clone(), false, loc.clone()));
        desc.environment_light = Some(EnvironmentLightDesc {
            image: desc.images.len() - 1,
            mapping: EnvMapping::LatLong,
            sampling: EnvSampling::Importance,
            rotation: (self.rotation + BLENDER_FROM_HW5).rem_euclid(360.0),
            strength: WHITE * self.strength,
            loc,
        });
    }
}

/// Takes away a model scene's studio lights, reads its materials as albedos
/// and path-traces its cameras with MIS.
fn remove_studio(desc: &mut Description, studio: &Studio, loc: &Loc) {
    let mut index = 0;
    desc.point_lights.retain(|_| {
        let keep = !studio.point_lights.contains(&index);
        index += 1;
        keep
    });
    if studio.ambient {
        desc.ambient_light = luster_core::math::Vec3::ZERO;
    }
    // The ground is the last object, so no other object's index moves.
    if studio.ground.is_some_and(|g| g + 1 == desc.objects.len()) {
        desc.objects.pop();
    }
    for &m in &studio.materials {
        if let Some(m) = desc.materials.get_mut(m) {
            if m.brdf.is_none() {
                m.brdf = Some(BrdfDesc {
                    id: "--env".into(),
                    kind: BrdfKind::ModifiedBlinnPhong,
                    exponent: None,
                    normalized: true,
                    kd_fresnel: false,
                    loc: loc.clone(),
                });
            }
        }
    }
    let mis = PathParamsDesc { mis: true, ..Default::default() };
    for c in &mut desc.cameras {
        c.renderer = RendererDesc::PathTracing(mis);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::description::MaterialKind;

    fn write(dir: &tempfile::TempDir, name: &str, text: &str) -> PathBuf {
        let p = dir.path().join(name);
        std::fs::write(&p, text).expect("write");
        p
    }

    #[test]
    fn bad_names_and_numbers_are_refused() {
        let ok = Path::new("sky.EXR");
        assert!(Hdri::new(ok, 30.0, 2.0).is_ok());
        assert!(Hdri::new(Path::new("sky.hdr"), -720.0, 0.0).is_ok());
        for (path, rot, s, word) in [
            ("sky.png", 0.0, 1.0, ".hdr"),
            ("sky", 0.0, 1.0, ".hdr"),
            ("sky.exr", f32::NAN, 1.0, "--env-rotate"),
            ("sky.exr", f32::INFINITY, 1.0, "--env-rotate"),
            ("sky.exr", 0.0, -0.5, "--env-strength"),
            ("sky.exr", 0.0, f32::NAN, "--env-strength"),
            ("sky.exr", 0.0, 1e37, "--env-strength"),
        ] {
            let e = Hdri::new(Path::new(path), rot, s).expect_err(path).to_string();
            assert!(e.starts_with(path) && e.contains(word), "{e}");
        }
    }

    #[test]
    fn a_course_scene_gets_the_hdri_in_place_of_its_environment() {
        let dir = tempfile::tempdir().expect("tempdir");
        let scene = write(
            &dir,
            "s.xml",
            r#"<Scene><Cameras><Camera id="1"><Position>0 0 0</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
            <NearPlane>-1 1 -1 1</NearPlane><NearDistance>1</NearDistance><ImageResolution>4 4</ImageResolution>
            <ImageName>a.png</ImageName></Camera></Cameras>
            <Lights><PointLight id="1"><Position>0 5 0</Position><Intensity>9 9 9</Intensity></PointLight>
            <SphericalDirectionalLight id="1" type="probe"><ImageId>1</ImageId><Sampler>uniform</Sampler></SphericalDirectionalLight></Lights>
            <Textures><Images><Image id="1">old.exr</Image></Images></Textures>
            <Materials><Material id="1"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material></Materials>
            <VertexData>0 0 -2</VertexData>
            <Objects><Sphere id="1"><Material>1</Material><Center>1</Center><Radius>1</Radius></Sphere></Objects></Scene>"#,
        );
        let mut desc = crate::load(&scene).expect("loads");
        let before = desc.warnings.len();
        Hdri::new(Path::new("/maps/sky.hdr"), 30.0, 2.0).expect("valid").apply(&mut desc);
        let env = desc.environment_light.as_ref().expect("an environment");
        assert_eq!(desc.images[env.image].path, Path::new("/maps/sky.hdr"));
        assert_eq!((env.mapping, env.sampling), (EnvMapping::LatLong, EnvSampling::Importance));
        assert_eq!((env.rotation, env.strength), (300.0, 510.0));
        assert_eq!(desc.warnings.len(), before + 1);
        assert!(desc.warnings[before].message.contains("replaces the scene's SphericalDirectionalLight"));
        // A course scene keeps its own lights, materials and renderer.
        assert_eq!(desc.point_lights.len(), 1);
        assert!(desc.materials[0].brdf.is_none());
        assert_eq!(desc.cameras[0].renderer, RendererDesc::Whitted);
    }

    #[test]
    fn a_model_scene_loses_its_studio_and_keeps_its_ground() {
        let dir = tempfile::tempdir().expect("tempdir");
        let model = write(&dir, "m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        let mut desc = crate::load(&model).expect("loads");
        assert!(desc.studio.is_some() && !desc.point_lights.is_empty());
        let objects = desc.objects.len();
        Hdri::new(Path::new("sky.exr"), 0.0, 1.0).expect("valid").apply(&mut desc);
        assert!(desc.studio.is_none());
        assert!(desc.point_lights.is_empty());
        assert_eq!(desc.ambient_light, luster_core::math::Vec3::ZERO);
        assert_eq!(desc.objects.len(), objects, "the model and its ground stay");
        for m in &desc.materials {
            assert_eq!(m.kind, MaterialKind::Plain);
            let b = m.brdf.as_ref().expect("normalized Blinn-Phong");
            assert!(b.normalized && b.kind == BrdfKind::ModifiedBlinnPhong);
        }
        assert!(matches!(desc.cameras[0].renderer, RendererDesc::PathTracing(p) if p.mis));
        let env = desc.environment_light.as_ref().expect("an environment");
        assert_eq!((env.rotation, env.strength), (270.0, 255.0));
        assert!(desc.warnings.iter().all(|w| !w.message.contains("--env")), "no warning for a model");
    }
}
