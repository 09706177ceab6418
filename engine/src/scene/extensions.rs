//! Which glTF extensions raykin reads, parsing a document that requires them, and one warning for each
//! extension a file uses that raykin ignores. docs/GLTF.md lists what each extension does in raykin.

/// Extensions raykin reads. A file may require any of these; the material ones (and texture transforms)
/// are parsed but not rendered yet, which the loader reports per file.
pub(super) const SUPPORTED: &[&str] = &[
    "KHR_materials_emissive_strength",
    "KHR_lights_punctual",
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

/// A parsed document: its JSON after [`super::validate::check`]'s repairs, the GLB's binary chunk, and what
/// the checks found (warnings and pieces to skip).
pub(super) struct Parsed {
    pub root: gltf::json::Root,
    pub blob: Option<Vec<u8>>,
    pub findings: super::validate::Findings,
}

/// Parses glTF or GLB bytes: raykin's own checks first (the crate's validation and readers panic on some of
/// what they catch), then the crate's validation widened by what the supported extensions permit. The loader
/// and Save as both read a file through here, so Save as writes what the loader read.
pub(super) fn parse(bytes: &[u8]) -> Result<Parsed, ParseError> {
    use super::validate;
    if let Some(problem) = validate::glb_header_problem(bytes) {
        return Err(ParseError::Invalid(problem));
    }
    let gltf = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| {
        // A glTF 1.0 file is not even shaped like a 2.0 one: name its version, not the parse error.
        ParseError::Invalid(validate::version_problem(bytes).unwrap_or_else(|| describe(&e)))
    })?;
    let mut root = gltf.document.into_json();
    if let Some(extension) = unsupported_required(&root) {
        return Err(ParseError::Unsupported(extension.to_string()));
    }
    let findings = validate::check(&mut root).map_err(ParseError::Invalid)?;
    validate_widened(&root).map_err(ParseError::Invalid)?;
    Ok(Parsed {
        root,
        blob: gltf.blob,
        findings,
    })
}

fn describe(e: &gltf::Error) -> String {
    match e {
        gltf::Error::Validation(errors) => {
            let list: Vec<String> = errors
                .iter()
                .take(5)
                .map(|(path, err)| format!("{path}: {err}"))
                .collect();
            format!("validation failed: {}", list.join("; "))
        }
        other => other.to_string(),
    }
}

/// The first extension the file requires that raykin does not read.
fn unsupported_required(root: &gltf::json::Root) -> Option<&str> {
    root.extensions_required
        .iter()
        .map(String::as_str)
        .find(|e| !SUPPORTED.contains(e))
}

/// The crate's validation of a document, accepting what the supported extensions permit: required
/// extensions from [`SUPPORTED`], accessors without a bufferView (zeros, or Draco-decoded), and textures whose
/// image comes from an extension (KHR_texture_basisu) instead of `source`.
fn validate_widened(root: &gltf::json::Root) -> Result<(), String> {
    use gltf::json::validation::Validate;
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, error| {
        let path = path().to_string();
        if !permitted(root, &path, &error) {
            errors.push(format!("{path}: {error}"));
        }
    });
    if errors.is_empty() {
        return Ok(());
    }
    let shown: Vec<String> = errors.iter().take(5).cloned().collect();
    Err(format!("validation failed: {}", shown.join("; ")))
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
