//! KHR_materials_variants: named material sets a file offers (a shoe in several colours). The loader keeps
//! each primitive's mappings; [`SceneAsset::select_variant`] switches the materials its triangles use at load,
//! and [`ActiveVariant`] switches what the renderer shows at run time (the asset stays as loaded).

use super::{MeshData, SceneAsset, SceneError};
use bevy_ecs::prelude::Resource;
use std::borrow::Cow;
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

/// The variant the renderer shows (index into [`SceneAsset::variants`]; `None`: the file's own materials). It
/// starts as the asset's [`SceneAsset::active_variant`] (`--variant`); the editor's switch writes it, and the
/// render plugin then rewrites only the triangles' material words.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ActiveVariant(pub Option<usize>);

impl MeshData {
    /// Each triangle's material under `variant` (`None`: the file's materials). A mesh without mappings keeps
    /// its own; an index the file does not have selects the file's materials.
    pub fn triangle_materials_under(&self, variant: Option<usize>) -> Cow<'_, [u32]> {
        if self.primitive_variants.is_empty() {
            return Cow::Borrowed(&self.triangle_materials);
        }
        let mut materials = self.triangle_materials.clone();
        for pv in &self.primitive_variants {
            let end = (pv.triangles.end as usize).min(materials.len());
            let start = (pv.triangles.start as usize).min(end);
            materials[start..end].fill(pv.material_under(variant));
        }
        Cow::Owned(materials)
    }
}

impl PrimitiveVariants {
    /// The primitive's material under `variant`: its mapping for it, else the file's material.
    pub fn material_under(&self, variant: Option<usize>) -> u32 {
        variant
            .and_then(|v| self.mappings.iter().find(|(mv, _)| *mv as usize == v))
            .map_or(self.file_material, |&(_, m)| m)
    }
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
                )?),
            };
        for mesh in &mut self.meshes {
            if mesh.primitive_variants.is_empty() {
                continue;
            }
            mesh.triangle_materials = mesh.triangle_materials_under(variant).into_owned();
            for (p, pv) in mesh.primitive_variants.iter().enumerate() {
                if let Some(range) = mesh.primitives.get_mut(p) {
                    range.material = pv.material_under(variant);
                }
            }
        }
        self.active_variant = variant;
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
