//! glTF materials (metallic-roughness and the KHR material extensions)
//! mapped onto luster's OpenPBR surface.
