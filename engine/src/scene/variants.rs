//! KHR_materials_variants: named material sets a file offers (a shoe in several colours). The loader keeps
//! each primitive's mappings; [`SceneAsset::select_variant`] switches the materials its triangles use.

use super::{SceneAsset, SceneError};
use std::ops::Range;

pub(super) const EXTENSION: &str = "KHR_materials_variants";

/// One primitive's variant mappings.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PrimitiveVariants {
    /// The primitive's triangles inside its mesh.
    pub triangles: Range<u32>,
    /// The material the file gives the primitive (used when no mapping names the selected variant).
    pub file_material: u32,
    /// `(variant, material)` pairs: under that variant the primitive uses that material.
    pub mappings: Vec<(u32, u32)>,
}

impl SceneAsset {
    /// Selects a variant by name (`None`: the file's own materials). An unknown name is an error listing the
    /// variants the file has.
    pub fn select_variant(&mut self, name: Option<&str>) -> Result<(), SceneError> {
        let variant =
            match name {
                None => None,
                Some(name) => Some(self.variants.iter().position(|v| v == name).ok_or_else(
                    || SceneError::UnknownVariant {
                        path: self.source.clone().into(),
                        name: name.to_string(),
                        known: if self.variants.is_empty() {
                            "the file has no KHR_materials_variants".into()
                        } else {
                            format!(
                                "its variants are {}",
                                self.variants
                                    .iter()
                                    .map(|v| format!("`{v}`"))
                                    .collect::<Vec<_>>()
                                    .join(", ")
                            )
                        },
                    },
                )? as u32),
            };
        for mesh in &mut self.meshes {
            for (p, pv) in mesh.primitive_variants.iter().enumerate() {
                let material = variant
                    .and_then(|v| pv.mappings.iter().find(|(mv, _)| *mv == v))
                    .map_or(pv.file_material, |&(_, m)| m);
                if let Some(range) = mesh.primitives.get_mut(p) {
                    range.material = material;
                }
                let end = (pv.triangles.end as usize).min(mesh.triangle_materials.len());
                let start = (pv.triangles.start as usize).min(end);
                mesh.triangle_materials[start..end].fill(material);
            }
        }
        self.active_variant = variant.map(|v| v as usize);
        Ok(())
    }
}

/// Reads a primitive's mappings; variant or material indices out of range are dropped with a note.
pub(super) fn read_mappings(
    primitive: &gltf::Primitive,
    variant_count: usize,
    material_count: usize,
    notes: &mut Vec<String>,
) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    for mapping in primitive.mappings() {
        let Some(material) = mapping.material().index().filter(|&m| m < material_count) else {
            notes.push("a KHR_materials_variants mapping names a material that does not exist; mapping ignored".into());
            continue;
        };
        for &v in mapping.variants() {
            if (v as usize) < variant_count {
                out.push((v, material as u32));
            } else {
                notes.push(format!(
                    "a KHR_materials_variants mapping names variant {v} of {variant_count}; ignored"
                ));
            }
        }
    }
    out
}
