//! Numbering a model's (OBJ or glTF) materials, images and texture maps into a
//! description that already has some: a CENG795 scene with `objFile` meshes
//! appends them after its own, the model scene starts from nothing.

use super::{Part, PartMap};
use crate::description::{ImageDesc, MaterialDesc, TextureMapDesc, TextureSource};

/// Materials, images and texture maps that OBJ parts add to a description,
/// numbered after those it already has.
#[derive(Debug, Default)]
pub struct Additions {
    base: [usize; 3],
    /// New materials.
    pub materials: Vec<MaterialDesc>,
    /// New images (one per file).
    pub images: Vec<ImageDesc>,
    /// New texture maps.
    pub texture_maps: Vec<TextureMapDesc>,
}

impl Additions {
    /// Additions to a description that has this many materials, images and maps.
    pub fn new(materials: usize, images: usize, texture_maps: usize) -> Additions {
        Additions { base: [materials, images, texture_maps], ..Default::default() }
    }

    /// Adds a material; returns its index in the description.
    pub fn add_material(&mut self, m: MaterialDesc) -> usize {
        self.materials.push(m);
        self.base[0] + self.materials.len() - 1
    }

    /// Adds a part's material and maps; returns the material's index and the
    /// maps' indices in the description. An image file used twice is read once.
    pub fn add_part(&mut self, part: &Part) -> (usize, Vec<usize>) {
        self.add_with_maps(&part.material, &part.maps)
    }

    /// Adds a material and its maps (an OBJ part's, a glTF material's);
    /// returns the material's index and the maps' indices in the description.
    pub fn add_with_maps(&mut self, material: &MaterialDesc, part_maps: &[PartMap]) -> (usize, Vec<usize>) {
        let material = self.add_material(material.clone());
        let mut maps = Vec::new();
        for pm in part_maps {
            let mut map = pm.map.clone();
            if let (TextureSource::Image { image, .. }, Some(img)) = (&mut map.source, &pm.image) {
                let local = match self.images.iter().position(|i| i.same_texels(img)) {
                    Some(k) => k,
                    None => {
                        self.images.push(img.clone());
                        self.images.len() - 1
                    }
                };
                *image = self.base[1] + local;
            }
            self.texture_maps.push(map);
            maps.push(self.base[2] + self.texture_maps.len() - 1);
        }
        (material, maps)
    }
}
