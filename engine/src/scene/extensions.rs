//! Which glTF extensions raykin reads, parsing a document that requires them, and one warning for each
//! extension a file uses that raykin ignores. docs/GLTF.md lists what each extension does in raykin.

/// Extensions raykin reads. A file may require any of these; the material ones (and texture transforms)
/// are parsed but not rendered yet, which the loader reports per file.
pub(super) const SUPPORTED: &[&str] = &[
    "KHR_materials_emissive_strength",
    "KHR_mesh_quantization",
    super::draco::EXTENSION,
    "EXT_meshopt_compression",
    "KHR_meshopt_compression",
    super::instancing::EXTENSION,
    "KHR_texture_transform",
    super::variants::EXTENSION,
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_materials_specular",
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
    "KHR_materials_unlit",
    "KHR_materials_iridescence",
    "KHR_materials_anisotropy",
    "KHR_materials_dispersion",
    "KHR_materials_diffuse_transmission",
    super::texture_basisu::EXTENSION,
];

/// Why a document could not be parsed.
pub(super) enum ParseError {
    /// It requires an extension raykin does not read.
    Unsupported(String),
    /// Anything else, described.
    Invalid(String),
}

/// Parses glTF or GLB bytes and validates the document, accepting what the supported extensions permit:
/// required extensions from [`SUPPORTED`], accessors without a bufferView (zeros, or Draco-decoded), and
/// textures whose image comes from an extension (KHR_texture_basisu) instead of `source`.
pub(super) fn parse(bytes: &[u8]) -> Result<gltf::Gltf, ParseError> {
    let gltf = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| ParseError::Invalid(e.to_string()))?;
    if let Some(ext) = gltf
        .document
        .extensions_required()
        .find(|e| !SUPPORTED.contains(e))
    {
        return Err(ParseError::Unsupported(ext.to_string()));
    }
    use gltf::json::validation::Validate;
    let root = gltf.document.as_json();
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, error| {
        let path = path().to_string();
        if !permitted(root, &path, &error) {
            errors.push(format!("{path}: {error}"));
        }
    });
    if !errors.is_empty() {
        let shown: Vec<String> = errors.iter().take(5).cloned().collect();
        return Err(ParseError::Invalid(format!(
            "validation failed: {}",
            shown.join("; ")
        )));
    }
    Ok(gltf)
}

/// Validation errors that the supported extensions make valid.
fn permitted(root: &gltf::json::Root, path: &str, error: &gltf::json::validation::Error) -> bool {
    use gltf::json::validation::Error;
    // Required extensions were checked against SUPPORTED above.
    if path.starts_with("extensionsRequired") {
        return true;
    }
    // glTF 2.0 allows an accessor without a bufferView (it reads as zeros); Draco primitives use them.
    if path.starts_with("accessors[") && path.ends_with("].bufferView") && *error == Error::Missing
    {
        return true;
    }
    // A texture whose image comes from KHR_texture_basisu may omit `source`.
    if let Some(index) = path
        .strip_prefix("textures[")
        .and_then(|rest| rest.strip_suffix("].source"))
        .and_then(|i| i.parse::<usize>().ok())
    {
        return root.textures.get(index).is_some_and(|t| {
            t.extensions
                .as_ref()
                .is_some_and(|e| e.others.contains_key(super::texture_basisu::EXTENSION))
        });
    }
    false
}

/// One warning per extension in `extensionsUsed` that raykin neither reads nor needs.
pub(super) fn ignored_warnings(document: &gltf::Document) -> Vec<String> {
    document
        .extensions_used()
        .filter(|e| !SUPPORTED.contains(e))
        .map(|e| format!("extension `{e}` is not supported; what it adds is ignored"))
        .collect()
}
