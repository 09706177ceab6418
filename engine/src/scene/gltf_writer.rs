//! "File > Save as": the scene file written back with edited materials and lights. The original glTF JSON is kept as the
//! gltf crate parses it (nodes, meshes, animations, cameras, extensions and extras); only material entries
//! change. Buffers and images come along: a `.gltf` output references the original external files from its
//! own folder (and a GLB's binary chunk becomes `NAME.bin` beside it); a `.glb` output packs every buffer and
//! external image into its one binary chunk.

use super::gltf_loader::percent_decode;
use super::{AlphaMode, Material, PunctualLight};
use gltf::json;
use std::path::{Component, Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum SaveError {
    #[error("{path}: the output must end in .gltf or .glb")]
    Extension { path: PathBuf },
    #[error("{source_name}: cannot re-read the scene file to save it: {reason}")]
    Source { source_name: String, reason: String },
    #[error(
        "{source_name}: the file has {file} materials but the editor holds {edited}; only scenes loaded from one file can be saved"
    )]
    MaterialCount {
        source_name: String,
        file: usize,
        edited: usize,
    },
    #[error("{path}: cannot write: {reason}")]
    Write { path: PathBuf, reason: String },
}

/// Writes the glTF in `source_bytes` (read from a file in `source_dir`; `source_name` names it in messages) to
/// `out` (.gltf or .glb by extension) with `materials` in place of the file's materials.
pub fn save_with_materials(
    source_bytes: &[u8],
    source_dir: &Path,
    source_name: &str,
    materials: &[Material],
    out: &Path,
) -> Result<(), SaveError> {
    save_edited(source_bytes, source_dir, source_name, materials, None, out)
}

/// [`save_with_materials`], and with `node_lights` (glTF node index, its light) the file's
/// KHR_lights_punctual lights are replaced: one light per node that has one (`None` keeps the file's).
pub fn save_edited(
    source_bytes: &[u8],
    source_dir: &Path,
    source_name: &str,
    materials: &[Material],
    node_lights: Option<&[(usize, PunctualLight)]>,
    out: &Path,
) -> Result<(), SaveError> {
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let glb = match ext.as_deref() {
        Some("glb") => true,
        Some("gltf") => false,
        _ => {
            return Err(SaveError::Extension {
                path: out.to_path_buf(),
            });
        }
    };
    let source_err = |reason: String| SaveError::Source {
        source_name: source_name.to_string(),
        reason,
    };
    let gltf = gltf::Gltf::from_slice(source_bytes).map_err(|e| source_err(e.to_string()))?;
    let blob = gltf.blob;
    let mut root = gltf.document.into_json();
    if root.materials.len() != materials.len() {
        return Err(SaveError::MaterialCount {
            source_name: source_name.to_string(),
            file: root.materials.len(),
            edited: materials.len(),
        });
    }
    for (json_material, edited) in root.materials.iter_mut().zip(materials) {
        apply_material(json_material, edited);
    }
    if materials.iter().any(|m| m.emissive_strength != 1.0)
        && !root
            .extensions_used
            .iter()
            .any(|e| e == "KHR_materials_emissive_strength")
    {
        root.extensions_used
            .push("KHR_materials_emissive_strength".into());
    }
    if let Some(node_lights) = node_lights {
        apply_lights(&mut root, node_lights).map_err(source_err)?;
    }
    let write_err = |path: &Path, reason: String| SaveError::Write {
        path: path.to_path_buf(),
        reason,
    };
    let out_dir = out
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(out_dir).map_err(|e| write_err(out_dir, e.to_string()))?;
    let sources = Sources {
        dir: source_dir,
        blob: blob.as_deref(),
    };
    let bytes = if glb {
        pack_glb(&mut root, &sources).map_err(source_err)?
    } else {
        relocate_uris(&mut root, &sources, out, out_dir).map_err(source_err)?;
        root.to_vec_pretty()
            .map_err(|e| source_err(e.to_string()))?
    };
    crate::image_io::write_bytes_atomically(out, &bytes).map_err(|e| write_err(out, e.to_string()))
}

/// Replaces the file's KHR_lights_punctual lights by one per entry of `node_lights`, referenced from its node.
fn apply_lights(
    root: &mut json::Root,
    node_lights: &[(usize, PunctualLight)],
) -> Result<(), String> {
    use json::extensions::scene::khr_lights_punctual::KhrLightsPunctual;
    for node in &mut root.nodes {
        if let Some(ext) = &mut node.extensions {
            ext.khr_lights_punctual = None;
        }
    }
    for (i, (node, _)) in node_lights.iter().enumerate() {
        let count = root.nodes.len();
        let n = root
            .nodes
            .get_mut(*node)
            .ok_or_else(|| format!("a light is on node {node}, but the file has {count} nodes"))?;
        n.extensions
            .get_or_insert_with(Default::default)
            .khr_lights_punctual = Some(KhrLightsPunctual {
            light: json::Index::new(i as u32),
        });
    }
    let name = "KHR_lights_punctual";
    if node_lights.is_empty() {
        if let Some(ext) = &mut root.extensions {
            ext.khr_lights_punctual = None;
        }
        root.extensions_used.retain(|e| e != name);
        root.extensions_required.retain(|e| e != name);
    } else {
        root.extensions
            .get_or_insert_with(Default::default)
            .khr_lights_punctual = Some(json::extensions::root::KhrLightsPunctual {
            lights: node_lights.iter().map(|(_, l)| l.to_json()).collect(),
        });
        if !root.extensions_used.iter().any(|e| e == name) {
            root.extensions_used.push(name.into());
        }
    }
    Ok(())
}

/// Writes the editable parameters of `m` over the JSON material; texture references the editor turned off are
/// removed, the others are left as the file has them.
fn apply_material(j: &mut json::Material, m: &Material) {
    let pbr = &mut j.pbr_metallic_roughness;
    pbr.base_color_factor = json::material::PbrBaseColorFactor(m.base_color.to_array());
    pbr.metallic_factor = json::material::StrengthFactor(m.metallic);
    pbr.roughness_factor = json::material::StrengthFactor(m.roughness);
    if m.base_color_texture.is_none() {
        pbr.base_color_texture = None;
    }
    if m.metallic_roughness_texture.is_none() {
        pbr.metallic_roughness_texture = None;
    }
    if m.normal_texture.is_none() {
        j.normal_texture = None;
    }
    if let Some(normal) = &mut j.normal_texture {
        normal.scale = m.normal_scale;
    }
    if m.emissive_texture.is_none() {
        j.emissive_texture = None;
    }
    j.emissive_factor = json::material::EmissiveFactor(m.emissive.to_array());
    let has_strength = j
        .extensions
        .as_ref()
        .is_some_and(|e| e.emissive_strength.is_some());
    if m.emissive_strength != 1.0 || has_strength {
        j.extensions
            .get_or_insert_with(Default::default)
            .emissive_strength = Some(json::extensions::material::EmissiveStrength {
            emissive_strength: json::extensions::material::EmissiveStrengthFactor(
                m.emissive_strength,
            ),
        });
    }
    let (mode, cutoff) = match m.alpha_mode {
        AlphaMode::Opaque => (json::material::AlphaMode::Opaque, None),
        AlphaMode::Mask(c) => (
            json::material::AlphaMode::Mask,
            Some(json::material::AlphaCutoff(c)),
        ),
        AlphaMode::Blend => (json::material::AlphaMode::Blend, None),
    };
    j.alpha_mode = json::validation::Checked::Valid(mode);
    j.alpha_cutoff = cutoff;
    j.double_sided = m.double_sided;
}

/// Where the original buffers and images are read from.
struct Sources<'a> {
    dir: &'a Path,
    blob: Option<&'a [u8]>,
}

impl Sources<'_> {
    fn read_uri(&self, uri: &str) -> Result<Vec<u8>, String> {
        super::gltf_loader::read_uri(self.dir, uri)
    }

    fn buffer(&self, buffer: &json::Buffer) -> Result<Vec<u8>, String> {
        let mut bytes = match &buffer.uri {
            Some(uri) => self.read_uri(uri)?,
            None => self.blob.ok_or("the GLB has no binary chunk")?.to_vec(),
        };
        bytes.truncate(buffer.byte_length.0 as usize);
        Ok(bytes)
    }
}

/// .gltf output: a GLB binary chunk becomes `STEM.bin` beside `out`; relative file URIs are rewritten to point
/// from `out_dir` at the original files; data URIs stay.
fn relocate_uris(
    root: &mut json::Root,
    sources: &Sources,
    out: &Path,
    out_dir: &Path,
) -> Result<(), String> {
    let stem = out
        .file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy().to_string());
    for buffer in &mut root.buffers {
        match &buffer.uri {
            None => {
                let bytes = sources.buffer(buffer)?;
                let name = format!("{stem}.bin");
                let path = out_dir.join(&name);
                crate::image_io::write_bytes_atomically(&path, &bytes)
                    .map_err(|e| format!("{}: cannot write: {e}", path.display()))?;
                buffer.uri = Some(percent_encode(&name));
            }
            Some(uri) => buffer.uri = Some(relocated(uri, sources.dir, out_dir)?),
        }
    }
    for image in &mut root.images {
        if let Some(uri) = &image.uri {
            image.uri = Some(relocated(uri, sources.dir, out_dir)?);
        }
    }
    Ok(())
}

fn relocated(uri: &str, source_dir: &Path, out_dir: &Path) -> Result<String, String> {
    if uri.starts_with("data:") {
        return Ok(uri.to_string());
    }
    let file = source_dir.join(percent_decode(uri));
    let file = file
        .canonicalize()
        .map_err(|e| format!("{}: {e}", file.display()))?;
    let out_dir = out_dir
        .canonicalize()
        .map_err(|e| format!("{}: {e}", out_dir.display()))?;
    let relative = relative_path(&out_dir, &file);
    let text: Vec<String> = relative
        .components()
        .map(|c| c.as_os_str().to_string_lossy().to_string())
        .collect();
    Ok(percent_encode(&text.join("/")))
}

/// The path from folder `from` to `to` (both absolute and canonical).
fn relative_path(from: &Path, to: &Path) -> PathBuf {
    let from: Vec<Component> = from.components().collect();
    let to_parts: Vec<Component> = to.components().collect();
    let common = from
        .iter()
        .zip(&to_parts)
        .take_while(|(a, b)| a == b)
        .count();
    let mut out = PathBuf::new();
    for _ in common..from.len() {
        out.push("..");
    }
    for c in &to_parts[common..] {
        out.push(c.as_os_str());
    }
    out
}

/// .glb output: all buffers concatenated into the binary chunk (4-byte aligned), buffer views re-pointed, and
/// external or data-URI images moved into buffer views.
fn pack_glb(root: &mut json::Root, sources: &Sources) -> Result<Vec<u8>, String> {
    let mut bin: Vec<u8> = Vec::new();
    let mut offsets = Vec::with_capacity(root.buffers.len());
    for buffer in &root.buffers {
        align4(&mut bin);
        offsets.push(bin.len() as u64);
        bin.extend_from_slice(&sources.buffer(buffer)?);
    }
    for view in &mut root.buffer_views {
        let base = offsets[view.buffer.value()];
        view.byte_offset = Some(json::validation::USize64(
            base + view.byte_offset.map_or(0, |o| o.0),
        ));
        view.buffer = json::Index::new(0);
    }
    for i in 0..root.images.len() {
        let Some(uri) = root.images[i].uri.clone() else {
            continue;
        };
        let bytes = sources.read_uri(&uri)?;
        align4(&mut bin);
        let view = json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: json::validation::USize64(bytes.len() as u64),
            byte_offset: Some(json::validation::USize64(bin.len() as u64)),
            byte_stride: None,
            name: None,
            target: None,
            extensions: None,
            extras: Default::default(),
        };
        bin.extend_from_slice(&bytes);
        let index = json::Index::push(&mut root.buffer_views, view);
        let image = &mut root.images[i];
        image.mime_type = Some(json::image::MimeType(mime_type(&uri, &bytes).into()));
        image.buffer_view = Some(index);
        image.uri = None;
    }
    align4(&mut bin);
    root.buffers = if bin.is_empty() {
        Vec::new()
    } else {
        vec![json::Buffer {
            byte_length: json::validation::USize64(bin.len() as u64),
            name: None,
            uri: None,
            extensions: None,
            extras: Default::default(),
        }]
    };
    let json_bytes = root.to_vec().map_err(|e| e.to_string())?;
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header {
            magic: *b"glTF",
            version: 2,
            length: 0, // computed by the writer
        },
        json: json_bytes.into(),
        bin: (!bin.is_empty()).then(|| bin.into()),
    };
    glb.to_vec().map_err(|e| e.to_string())
}

fn align4(bin: &mut Vec<u8>) {
    bin.resize(bin.len().div_ceil(4) * 4, 0);
}

/// glTF allows image/png and image/jpeg; the data tells which.
fn mime_type(uri: &str, bytes: &[u8]) -> &'static str {
    if bytes.starts_with(&[0x89, b'P', b'N', b'G']) {
        "image/png"
    } else if bytes.starts_with(&[0xff, 0xd8]) {
        "image/jpeg"
    } else if uri.to_ascii_lowercase().ends_with(".png") {
        "image/png"
    } else {
        "image/jpeg"
    }
}

/// Escapes what a URI path may not hold verbatim (RFC 3986 unreserved characters and '/' pass).
fn percent_encode(path: &str) -> String {
    let mut out = String::with_capacity(path.len());
    for b in path.bytes() {
        if b.is_ascii_alphanumeric() || b"-._~/".contains(&b) {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_paths_walk_up_then_down() {
        assert_eq!(
            relative_path(Path::new("/a/b/out"), Path::new("/a/b/src/x.bin")),
            PathBuf::from("../src/x.bin")
        );
        assert_eq!(
            relative_path(Path::new("/a"), Path::new("/a/x.bin")),
            PathBuf::from("x.bin")
        );
    }

    #[test]
    fn uris_round_trip_through_percent_encoding() {
        let name = "../my scene/tex #1.png";
        assert_eq!(percent_decode(&percent_encode(name)), name);
        assert_eq!(percent_encode("a b"), "a%20b");
    }
}
