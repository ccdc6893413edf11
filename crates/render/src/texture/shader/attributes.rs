//! The [`Attributes`] shaders read with `getattribute`, gathered from a
//! scene description: each object's own attributes under its index (the
//! shading point's `s.instance_id`), each geometry's under its index (the
//! `s.object_id` of every object drawing it), and each object's id as its
//! `object:name`. Volumes number their own scripts' points by volume
//! ([`for_volumes`]).

use luster_scene::description::Description;
use luster_scene::SceneError;
use luster_shading::shader::attributes::{Attributes, Level};

/// The attributes of `desc`'s objects; an error (the scene's attributes
/// over their cap) names the object that passed it.
pub fn for_objects(desc: &Description) -> Result<Attributes, SceneError> {
    let mut a = Attributes::new();
    for (i, o) in desc.objects.iter().enumerate() {
        let id = u32::try_from(i).map_err(|_| SceneError::at(&desc.file, &o.loc, "too many objects"))?;
        for (level, list) in [(Level::Instance, &o.attributes), (Level::Object, &o.geometry_attributes)] {
            a.insert(level, id, list).map_err(|why| SceneError::at(&desc.file, &o.loc, why))?;
        }
    }
    a.set_names(desc.objects.iter().map(|o| o.id.clone()).collect());
    Ok(a)
}

/// The attributes of `desc`'s volumes, by volume index (a volume script's
/// `s.object_id` and `s.instance_id`), and their ids as `object:name`.
pub fn for_volumes(desc: &Description) -> Result<Attributes, SceneError> {
    let mut a = Attributes::new();
    for (i, v) in desc.volumes.iter().enumerate() {
        let id = u32::try_from(i).map_err(|_| SceneError::at(&desc.file, &v.loc, "too many volumes"))?;
        a.insert(Level::Object, id, &v.attributes).map_err(|why| SceneError::at(&desc.file, &v.loc, why))?;
    }
    a.set_names(desc.volumes.iter().map(|v| v.id.clone()).collect());
    Ok(a)
}
