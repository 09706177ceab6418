//! "File > Save as": the scene file written back with edited materials and lights. The original glTF JSON is kept as the
//! gltf crate parses it (nodes, meshes, animations, cameras, extensions and extras); only material entries
//! change. Buffers and images come along: a `.gltf` output references the original external files from its
//! own folder (and a GLB's binary chunk becomes `NAME.bin` beside it); a `.glb` output packs every buffer and
//! external image into its one binary chunk.

use super::inputs::Access;
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
    access: Access,
    materials: &[Material],
    out: &Path,
) -> Result<(), SaveError> {
    save_edited(
        source_bytes,
        source_dir,
        source_name,
        access,
        materials,
        None,
        out,
    )
}

/// [`save_with_materials`], and with `node_lights` (glTF node index, its light) the file's
/// KHR_lights_punctual lights are replaced: one light per node that has one (`None` keeps the file's).
pub fn save_edited(
    source_bytes: &[u8],
    source_dir: &Path,
    source_name: &str,
    access: Access,
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
    let parsed = super::extensions::parse(source_bytes).map_err(|e| {
        source_err(match e {
            super::extensions::ParseError::Unsupported(ext) => {
                format!("it requires the unsupported extension `{ext}`")
            }
            super::extensions::ParseError::Invalid(reason) => reason,
        })
    })?;
    let blob = parsed.blob;
    let mut root = parsed.root;
    if root.materials.len() != materials.len() {
        return Err(SaveError::MaterialCount {
            source_name: source_name.to_string(),
            file: root.materials.len(),
            edited: materials.len(),
        });
    }
    for (json_material, edited) in root.materials.iter_mut().zip(materials) {
        apply_material(json_material, edited);
        for name in apply_rendered_extensions(json_material, edited) {
            if !root.extensions_used.iter().any(|e| e == name) {
                root.extensions_used.push(name.into());
            }
        }
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
    let external = access.external_files;
    let sources = Sources {
        dir: source_dir,
        blob: blob.as_deref(),
        access,
    };
    let bytes = if glb {
        pack_glb(&mut root, &sources).map_err(source_err)?
    } else {
        relocate_uris(&mut root, &sources, out, out_dir).map_err(source_err)?;
        root.to_vec_pretty()
            .map_err(|e| source_err(e.to_string()))?
    };
    // Never write a file that does not read back as the scene it came from: gltf-json writes values it cannot
    // read (non-finite numbers as null, empty arrays left out), and repacking can break what an extension
    // relies on (the loader fuzzer found both).
    if let Err(reason) = check_reads_back(
        &bytes,
        out,
        out_dir,
        source_bytes,
        source_dir,
        source_name,
        external,
    ) {
        return Err(source_err(format!("{reason}; nothing was written")));
    }
    crate::image_io::write_bytes_atomically(out, &bytes).map_err(|e| write_err(out, e.to_string()))
}

/// `Ok` when `saved` (to be written at `out`) loads with the triangle count of the source.
fn check_reads_back(
    saved: &[u8],
    out: &Path,
    out_dir: &Path,
    source_bytes: &[u8],
    source_dir: &Path,
    source_name: &str,
    external_files: bool,
) -> Result<(), String> {
    let options = super::LoadOptions {
        skip_images: true,
        allow_external_files: external_files,
        ..Default::default()
    };
    let reloaded = super::load_gltf_slice(saved, out_dir, out, &options)
        .map_err(|e| format!("the saved file would not load ({e})"))?;
    let source = super::load_gltf_slice(source_bytes, source_dir, Path::new(source_name), &options);
    match source {
        Ok(source) if source.triangle_count() != reloaded.triangle_count() => Err(format!(
            "the saved file would read back with {} triangles instead of {}",
            reloaded.triangle_count(),
            source.triangle_count()
        )),
        _ => Ok(()),
    }
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

/// Writes the material extensions the renderer shades with (and the inspector edits) over the JSON material:
/// IOR, transmission, volume, specular, clearcoat, sheen and unlit, added, changed or removed as the material has
/// them.
/// Texture references the editor turned off are removed. Returns the names of those in use.
fn apply_rendered_extensions(j: &mut json::Material, m: &Material) -> Vec<&'static str> {
    use json::extensions::material as ext;
    let e = &m.extensions;
    let x = j.extensions.get_or_insert_with(Default::default);
    let mut used = Vec::new();
    x.unlit = e.unlit.then(Default::default);
    if e.unlit {
        used.push("KHR_materials_unlit");
    }
    if e.ior != 1.5 || x.ior.is_some() {
        x.ior.get_or_insert_with(Default::default).ior = ext::IndexOfRefraction(e.ior);
        used.push("KHR_materials_ior");
    }
    x.transmission = e.transmission.as_ref().map(|t| {
        let mut out = x.transmission.take().unwrap_or_default();
        out.transmission_factor = ext::TransmissionFactor(t.factor);
        if t.texture.is_none() {
            out.transmission_texture = None;
        }
        used.push("KHR_materials_transmission");
        out
    });
    x.specular = e.specular.as_ref().map(|s| {
        let mut out = x.specular.take().unwrap_or_default();
        out.specular_factor = ext::SpecularFactor(s.factor);
        out.specular_color_factor = ext::SpecularColorFactor(s.color.to_array());
        if s.texture.is_none() {
            out.specular_texture = None;
        }
        if s.color_texture.is_none() {
            out.specular_color_texture = None;
        }
        used.push("KHR_materials_specular");
        out
    });
    // Written as plain JSON: the typed struct would write an infinite attenuation distance ("none") as null.
    let typed = x.volume.take();
    x.others.remove("KHR_materials_volume");
    if let Some(v) = &e.volume {
        let mut out = typed.unwrap_or_default();
        out.thickness_factor = ext::ThicknessFactor(v.thickness);
        out.attenuation_color = ext::AttenuationColor(v.attenuation_color.to_array());
        out.attenuation_distance = ext::AttenuationDistance(v.attenuation_distance);
        if v.thickness_texture.is_none() {
            out.thickness_texture = None;
        }
        if let Ok(serde_json::Value::Object(mut object)) = serde_json::to_value(&out) {
            if !v.attenuation_distance.is_finite() {
                object.remove("attenuationDistance");
            }
            x.others.insert(
                "KHR_materials_volume".into(),
                serde_json::Value::Object(object),
            );
            used.push("KHR_materials_volume");
        }
    }
    let coat = e.clearcoat.as_ref().map(|c| {
        let factors = [
            ("clearcoatFactor", c.factor),
            ("clearcoatRoughnessFactor", c.roughness),
        ];
        let textures = [
            ("clearcoatTexture", c.texture.is_some()),
            ("clearcoatRoughnessTexture", c.roughness_texture.is_some()),
            ("clearcoatNormalTexture", c.normal_texture.is_some()),
        ];
        let mut object = layer_json(x.others.get("KHR_materials_clearcoat"), &factors, &textures);
        if let Some(normal) = object
            .get_mut("clearcoatNormalTexture")
            .and_then(serde_json::Value::as_object_mut)
        {
            normal.insert("scale".into(), c.normal_scale.into());
        }
        object
    });
    let sheen = e.sheen.as_ref().map(|s| {
        let mut object = layer_json(
            x.others.get("KHR_materials_sheen"),
            &[("sheenRoughnessFactor", s.roughness)],
            &[
                ("sheenColorTexture", s.color_texture.is_some()),
                ("sheenRoughnessTexture", s.roughness_texture.is_some()),
            ],
        );
        object.insert(
            "sheenColorFactor".into(),
            s.color.to_array().to_vec().into(),
        );
        object
    });
    for (name, layer) in [
        ("KHR_materials_clearcoat", coat),
        ("KHR_materials_sheen", sheen),
    ] {
        x.others.remove(name);
        if let Some(object) = layer {
            x.others
                .insert(name.into(), serde_json::Value::Object(object));
            used.push(name);
        }
    }
    let empty =
        serde_json::to_value(&*x).is_ok_and(|v| v.as_object().is_some_and(|o| o.is_empty()));
    if empty {
        j.extensions = None;
    }
    used
}

/// A layer extension's JSON (the gltf crate has no typed form of clearcoat or sheen): the file's object with
/// `factors` set and the texture entries whose slot the editor turned off (`false`) removed.
fn layer_json(
    file: Option<&serde_json::Value>,
    factors: &[(&str, f32)],
    textures: &[(&str, bool)],
) -> serde_json::Map<String, serde_json::Value> {
    let mut object = file
        .and_then(serde_json::Value::as_object)
        .cloned()
        .unwrap_or_default();
    for &(key, value) in factors {
        object.insert(key.into(), value.into());
    }
    for &(key, present) in textures {
        if !present {
            object.remove(key);
        }
    }
    object
}

/// Where the original buffers and images are read from.
struct Sources<'a> {
    dir: &'a Path,
    blob: Option<&'a [u8]>,
    /// What the scene was loaded under: Save as embeds no file the load was not allowed to read (an image
    /// the load refused, `/etc/passwd`, must not end up inside a GLB the user then shares).
    access: Access,
}

impl Sources<'_> {
    fn read_uri(&self, uri: &str) -> Result<Vec<u8>, String> {
        let whole = super::inputs::ReadLimit::AtMost(u64::MAX);
        super::inputs::read_uri(self.dir, uri, self.access, whole, &mut |_| {})
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

/// .gltf output: file URIs inside the output's folder are rewritten relative to it; files outside it (and a
/// GLB binary chunk, as `STEM.bin`) are copied beside it, so the saved scene reads only files in its own
/// folder and loads without `--allow-external-files`. A copy never replaces an existing file: a name in use
/// by other bytes gets a `-1`, `-2` ... suffix. Data URIs stay.
fn relocate_uris(
    root: &mut json::Root,
    sources: &Sources,
    out: &Path,
    out_dir: &Path,
) -> Result<(), String> {
    let stem = out
        .file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy().to_string());
    let out_dir = out_dir
        .canonicalize()
        .map_err(|e| format!("{}: {e}", out_dir.display()))?;
    let mut copier = Copier {
        out_dir: &out_dir,
        reserved: vec![
            out.file_name()
                .map(|n| n.to_os_string())
                .unwrap_or_default(),
        ],
    };
    for buffer in &mut root.buffers {
        let name = match &buffer.uri {
            None => copier.place(&format!("{stem}.bin"), &sources.buffer(buffer)?)?,
            Some(uri) => relocated(uri, sources, &mut copier)?,
        };
        buffer.uri = Some(name);
    }
    for image in &mut root.images {
        if let Some(uri) = &image.uri {
            image.uri = Some(relocated(uri, sources, &mut copier)?);
        }
    }
    Ok(())
}

/// The URI the saved file uses for `uri` of the source.
fn relocated(uri: &str, sources: &Sources, copier: &mut Copier) -> Result<String, String> {
    if uri.starts_with("data:") {
        return Ok(uri.to_string());
    }
    let file = super::inputs::resolve(sources.dir, uri, sources.access)?;
    if file.starts_with(copier.out_dir) {
        let relative = relative_path(copier.out_dir, &file);
        let text: Vec<String> = relative
            .components()
            .map(|c| c.as_os_str().to_string_lossy().to_string())
            .collect();
        return Ok(percent_encode(&text.join("/")));
    }
    let name = file
        .file_name()
        .map_or("resource".into(), |n| n.to_string_lossy().to_string());
    copier.place(&name, &sources.read_uri(uri)?)
}

/// Writes resources into the output folder under names no other file uses.
struct Copier<'a> {
    out_dir: &'a Path,
    /// Names taken by this save (the output itself, earlier copies).
    reserved: Vec<std::ffi::OsString>,
}

impl Copier<'_> {
    /// Writes `bytes` as `name` (or `name-N`) in the output folder; returns its URI.
    fn place(&mut self, name: &str, bytes: &[u8]) -> Result<String, String> {
        let path = Path::new(name);
        let stem = path
            .file_stem()
            .map_or(name.to_string(), |s| s.to_string_lossy().to_string());
        let ext = path
            .extension()
            .map_or(String::new(), |e| format!(".{}", e.to_string_lossy()));
        for n in 0.. {
            let candidate = if n == 0 {
                name.to_string()
            } else {
                format!("{stem}-{n}{ext}")
            };
            if self.reserved.iter().any(|r| *r == *candidate) {
                continue;
            }
            let target = self.out_dir.join(&candidate);
            match std::fs::read(&target) {
                Ok(existing) if existing != bytes => continue,
                Ok(_) => {}
                Err(_) => crate::image_io::write_bytes_atomically(&target, bytes)
                    .map_err(|e| format!("{}: cannot write: {e}", target.display()))?,
            }
            self.reserved.push(candidate.clone().into());
            return Ok(percent_encode(&candidate));
        }
        unreachable!("some suffix is free")
    }
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
    use crate::scene::inputs::percent_decode;

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
