//! KHR_texture_basisu: textures whose image is a KTX2 container of Basis Universal data. raykin does not
//! decode KTX2 yet (docs/GLTF.md has the evaluation: the C++-backed crates leave out what BasisLZ needs or
//! need libclang to build; the pure-Rust `basisu` is young and unchecked here). A texture that also names a
//! PNG/JPEG `source` uses that; one that only has the KTX2 image is dropped with a warning, and its materials
//! use their factors.

pub(super) const EXTENSION: &str = "KHR_texture_basisu";

/// The 12-byte KTX 2.0 file identifier.
const KTX2_MAGIC: [u8; 12] = [
    0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A,
];

/// True for KTX2 bytes.
pub(super) fn is_ktx2(bytes: &[u8]) -> bool {
    bytes.starts_with(&KTX2_MAGIC)
}

/// The image index a texture's KHR_texture_basisu extension names, if any.
pub(super) fn basisu_source(texture: &gltf::Texture) -> Option<usize> {
    texture
        .extension_value(EXTENSION)?
        .get("source")?
        .as_u64()
        .map(|s| s as usize)
}

/// The image index of a texture's core `source`, if it has one (with KHR_texture_basisu it may not: the
/// gltf crate then holds a placeholder index that must not be followed).
pub(super) fn core_source(document: &gltf::Document, texture: usize) -> Option<usize> {
    let json = document.as_json();
    let source = json.textures.get(texture)?.source.value();
    (source < json.images.len()).then_some(source)
}

#[cfg(test)]
mod tests {
    #[test]
    fn ktx2_magic() {
        let mut bytes = super::KTX2_MAGIC.to_vec();
        bytes.extend([0; 8]);
        assert!(super::is_ktx2(&bytes));
        assert!(!super::is_ktx2(b"\x89PNG\r\n\x1a\n"));
    }
}
