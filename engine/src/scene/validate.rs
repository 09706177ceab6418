//! Checks a glTF document's JSON before the gltf crate reads it. The crate's own validation checks most
//! references, but it, and the readers the loader calls, index, unwrap and assert on what it does not check:
//! an accessor whose byteStride is smaller than its element or whose count is 0, an index or JOINTS accessor
//! of a component type the spec does not allow, a POSITION accessor that does not exist (indexed inside the
//! crate's validation itself), an image with neither uri nor bufferView, an animation channel aimed at a node
//! that does not exist or at an unknown property. Reading those panics or, worse, reads garbage (a VEC2
//! POSITION read as VEC3).
//!
//! [`check`] runs first, on the parsed JSON. What makes the whole file unusable is an error; a primitive,
//! image or animation channel that breaks a rule is listed in [`Findings`] for the loader to skip with a
//! warning; an optional piece that breaks one (a NORMAL of the wrong type, a skin's inverse bind matrices, a
//! morph target attribute) is removed from the document with a warning, so the loader never sees it.

use gltf::json::{
    self,
    accessor::{ComponentType, Type},
    animation::Property,
    mesh::Semantic,
    validation::Checked,
};
use std::collections::HashMap;

/// The glTF versions this loader implements: 2.0, and later 2.x files (the spec keeps minor versions
/// backward compatible unless `asset.minVersion` says otherwise).
const SUPPORTED: (u32, u32) = (2, 0);

/// What the loader must skip, and the warnings of what [`check`] repaired.
#[derive(Debug, Default)]
pub(super) struct Findings {
    pub warnings: Vec<String>,
    /// (mesh, primitive) -> why the primitive cannot be read.
    pub primitives: HashMap<(usize, usize), String>,
    /// image -> why it cannot be read.
    pub images: HashMap<usize, String>,
    /// (animation, channel) -> why the channel cannot be played.
    pub channels: HashMap<(usize, usize), String>,
}

/// Checks `root` and removes optional pieces the readers would misread; an error says why the file cannot
/// be loaded at all.
pub(super) fn check(root: &mut json::Root) -> Result<Findings, String> {
    check_version(&root.asset)?;
    check_position_references(root)?;
    let accessors: Vec<Result<Format, String>> = (0..root.accessors.len())
        .map(|i| accessor(root, i))
        .collect();
    let mut findings = Findings::default();
    check_primitives(root, &accessors, &mut findings);
    check_skins(root, &accessors, &mut findings);
    check_animations(root, &accessors, &mut findings);
    check_images(root, &mut findings);
    check_cameras(root, &mut findings);
    Ok(findings)
}

/// A GLB header the crate would mis-read: it computes `length - 12` unchecked (a length under 12 underflows).
pub(super) fn glb_header_problem(bytes: &[u8]) -> Option<String> {
    let word = |at: usize| -> Option<u32> {
        Some(u32::from_le_bytes(bytes.get(at..at + 4)?.try_into().ok()?))
    };
    if !bytes.starts_with(b"glTF") {
        return None;
    }
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return Some(format!(
            "a GLB of {} bytes has no complete 12-byte header",
            bytes.len()
        ));
    };
    if version != 2 {
        return Some(format!(
            "GLB version {version}: raykin reads GLB version 2 (glTF 2.0)"
        ));
    }
    (length < 12)
        .then(|| format!("the GLB header's length {length} is shorter than the header itself"))
}

/// The version a file states, from its raw JSON: for a message when the crate cannot parse the file at all
/// (a glTF 1.0 file is not even shaped like a 2.0 one).
pub(super) fn version_problem(json: &[u8]) -> Option<String> {
    let value: serde_json::Value = serde_json::from_slice(json).ok()?;
    let asset = value.get("asset")?;
    let asset = json::Asset {
        version: asset.get("version")?.as_str()?.to_string(),
        min_version: asset
            .get("minVersion")
            .and_then(|v| v.as_str())
            .map(str::to_string),
        copyright: None,
        extensions: None,
        extras: Default::default(),
        generator: None,
    };
    check_version(&asset).err()
}

fn parse_version(v: &str) -> Option<(u32, u32)> {
    let (major, minor) = v.split_once('.')?;
    Some((major.parse().ok()?, minor.parse().ok()?))
}

fn check_version(asset: &json::Asset) -> Result<(), String> {
    let version = parse_version(&asset.version).ok_or_else(|| {
        format!(
            "asset.version `{}` is not a MAJOR.MINOR version",
            asset.version
        )
    })?;
    if version.0 != SUPPORTED.0 {
        return Err(format!(
            "asset.version is {}: this is not a glTF 2.x file (raykin reads glTF 2.0{})",
            asset.version,
            if version.0 < 2 {
                "; convert it, e.g. with the Khronos glTF 1.0 to 2.0 converter"
            } else {
                ""
            }
        ));
    }
    if let Some(min) = &asset.min_version {
        let min_version = parse_version(min)
            .ok_or_else(|| format!("asset.minVersion `{min}` is not a MAJOR.MINOR version"))?;
        if min_version > version {
            return Err(format!(
                "asset.minVersion {min} is greater than asset.version {}",
                asset.version
            ));
        }
        if min_version > SUPPORTED {
            return Err(format!(
                "asset.minVersion is {min}: the file needs a glTF {min} reader, raykin implements glTF {}.{}",
                SUPPORTED.0, SUPPORTED.1
            ));
        }
    }
    Ok(())
}

/// The crate's validation indexes the POSITION accessor unchecked: a missing one must be an error first.
fn check_position_references(root: &json::Root) -> Result<(), String> {
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let named = primitive
                .attributes
                .iter()
                .map(|(semantic, index)| (semantic.to_string(), index.value()))
                .chain(
                    primitive
                        .indices
                        .map(|i| ("indices".to_string(), i.value())),
                );
            for (what, index) in named {
                if index >= root.accessors.len() {
                    return Err(format!(
                        "mesh {m} primitive {p}: {what} names accessor {index}, but the file has {} accessors",
                        root.accessors.len()
                    ));
                }
            }
        }
    }
    Ok(())
}

/// An accessor's element format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Format {
    component: ComponentType,
    ty: Type,
}

impl std::fmt::Display for Format {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} {}",
            type_name(self.ty),
            component_name(self.component)
        )
    }
}

fn type_name(ty: Type) -> &'static str {
    match ty {
        Type::Scalar => "SCALAR",
        Type::Vec2 => "VEC2",
        Type::Vec3 => "VEC3",
        Type::Vec4 => "VEC4",
        Type::Mat2 => "MAT2",
        Type::Mat3 => "MAT3",
        Type::Mat4 => "MAT4",
    }
}

fn component_name(c: ComponentType) -> &'static str {
    match c {
        ComponentType::I8 => "BYTE",
        ComponentType::U8 => "UNSIGNED_BYTE",
        ComponentType::I16 => "SHORT",
        ComponentType::U16 => "UNSIGNED_SHORT",
        ComponentType::U32 => "UNSIGNED_INT",
        ComponentType::F32 => "FLOAT",
    }
}

/// Whether accessor `i` can be read at all, and its format: every range is checked in u64 with overflow
/// checks, as the readers compute `offset + stride * (count - 1) + size` unchecked.
/// Most elements an accessor without a bufferView may have (zeros, or a Draco primitive's decoded values):
/// 2^25, 384 MiB of float positions.
const MAX_VIEWLESS_ELEMENTS: u64 = 1 << 25;

fn accessor(root: &json::Root, i: usize) -> Result<Format, String> {
    let a = &root.accessors[i];
    let (Checked::Valid(component), Checked::Valid(ty)) = (a.component_type, a.type_) else {
        return Err(format!("accessor {i} has an invalid componentType or type"));
    };
    let format = Format {
        component: component.0,
        ty,
    };
    let count = a.count.0;
    if count == 0 {
        return Err(format!("accessor {i} has count 0"));
    }
    let element = (component.0.size() * ty.multiplicity()) as u64;
    if let Some(view) = a.buffer_view {
        let offset = a.byte_offset.map_or(0, |o| o.0);
        let stride = view_range(root, view.value(), element, &format!("accessor {i}"))?;
        span(offset, count, stride, element)
            .filter(|&end| end <= root.buffer_views[view.value()].byte_length.0)
            .ok_or_else(|| {
                format!(
                    "accessor {i} ({count} x {format} from byte {offset}) lies outside bufferView {}",
                    view.value()
                )
            })?;
    } else if count > MAX_VIEWLESS_ELEMENTS {
        // Without a bufferView the reader makes `count` zeros (or Draco decodes them): bound what a few bytes
        // of JSON can make it allocate.
        return Err(format!(
            "accessor {i}: {count} elements without a bufferView (over the {MAX_VIEWLESS_ELEMENTS} raykin \
             fills with zeros or decodes)"
        ));
    }
    if let Some(sparse) = &a.sparse {
        let n = sparse.count.0;
        if n == 0 || n > count {
            return Err(format!(
                "accessor {i}: sparse count {n} is not between 1 and the accessor's count {count}"
            ));
        }
        let Checked::Valid(index_type) = sparse.indices.component_type else {
            return Err(format!(
                "accessor {i}: sparse indices have an invalid componentType"
            ));
        };
        let index_size = index_type.0.size() as u64;
        for (what, view, offset, size) in [
            (
                "sparse indices",
                sparse.indices.buffer_view.value(),
                sparse.indices.byte_offset.0,
                index_size,
            ),
            (
                "sparse values",
                sparse.values.buffer_view.value(),
                sparse.values.byte_offset.0,
                element,
            ),
        ] {
            let stride = view_range(root, view, size, &format!("accessor {i} {what}"))?;
            span(offset, n, stride, size)
                .filter(|&end| end <= root.buffer_views[view].byte_length.0)
                .ok_or_else(|| format!("accessor {i}: {what} lie outside bufferView {view}"))?;
        }
    }
    Ok(format)
}

/// `offset + stride * (count - 1) + element`, None on overflow.
fn span(offset: u64, count: u64, stride: u64, element: u64) -> Option<u64> {
    stride
        .checked_mul(count - 1)?
        .checked_add(element)?
        .checked_add(offset)
}

/// Checks buffer view `v` lies inside its buffer and can hold elements of `element` bytes; returns its
/// stride.
fn view_range(root: &json::Root, v: usize, element: u64, user: &str) -> Result<u64, String> {
    let view = root
        .buffer_views
        .get(v)
        .ok_or_else(|| format!("{user} names bufferView {v}, which does not exist"))?;
    let stride = view.byte_stride.map_or(element, |s| s.0 as u64);
    if stride < element {
        return Err(format!(
            "{user}: bufferView {v} has byteStride {stride}, smaller than one element ({element} bytes)"
        ));
    }
    view_in_buffer(root, v)?;
    Ok(stride)
}

fn view_in_buffer(root: &json::Root, v: usize) -> Result<(), String> {
    let view = &root.buffer_views[v];
    let buffer = view.buffer.value();
    let length = root
        .buffers
        .get(buffer)
        .ok_or_else(|| format!("bufferView {v} names buffer {buffer}, which does not exist"))?
        .byte_length
        .0;
    let offset = view.byte_offset.map_or(0, |o| o.0);
    match offset.checked_add(view.byte_length.0) {
        Some(end) if end <= length => Ok(()),
        _ => Err(format!(
            "bufferView {v} (bytes {offset}..+{}) lies outside buffer {buffer} ({length} bytes)",
            view.byte_length.0
        )),
    }
}

use ComponentType::{F32, I8, I16, U8, U16, U32};

/// Formats a vertex attribute the loader reads may have: glTF 2.0's (3.7.2.1), widened by
/// KHR_mesh_quantization when the file uses it (`quantized`; `accessor.rs` checks the normalized flags);
/// `None` for attributes it never reads.
fn attribute_formats(
    semantic: &Semantic,
    quantized: bool,
) -> Option<(&'static [ComponentType], &'static [Type])> {
    Some(match semantic {
        Semantic::Positions if quantized => (&[F32, I8, U8, I16, U16], &[Type::Vec3]),
        Semantic::Normals if quantized => (&[F32, I8, I16], &[Type::Vec3]),
        Semantic::Tangents if quantized => (&[F32, I8, I16], &[Type::Vec4]),
        Semantic::TexCoords(0 | 1) if quantized => (&[F32, I8, U8, I16, U16], &[Type::Vec2]),
        Semantic::Positions | Semantic::Normals => (&[F32], &[Type::Vec3]),
        Semantic::Tangents => (&[F32], &[Type::Vec4]),
        Semantic::TexCoords(0 | 1) => (&[F32, U8, U16], &[Type::Vec2]),
        Semantic::Colors(0) => (&[F32, U8, U16], &[Type::Vec3, Type::Vec4]),
        Semantic::Joints(_) => (&[U8, U16], &[Type::Vec4]),
        Semantic::Weights(_) => (&[F32, U8, U16], &[Type::Vec4]),
        _ => return None,
    })
}

/// `Ok` when accessor `index` is readable and of one of the allowed formats; else why not.
fn require(
    accessors: &[Result<Format, String>],
    index: usize,
    components: &[ComponentType],
    types: &[Type],
) -> Result<(), String> {
    let format = accessors
        .get(index)
        .ok_or_else(|| format!("accessor {index} does not exist"))?
        .clone()?;
    if components.contains(&format.component) && types.contains(&format.ty) {
        return Ok(());
    }
    let allowed: Vec<String> = types
        .iter()
        .flat_map(|&ty| {
            components
                .iter()
                .map(move |&component| Format { component, ty }.to_string())
        })
        .collect();
    Err(format!(
        "accessor {index} is {format}; the spec allows {}",
        allowed.join(" or ")
    ))
}

fn check_primitives(
    root: &mut json::Root,
    accessors: &[Result<Format, String>],
    findings: &mut Findings,
) {
    let quantized = root
        .extensions_used
        .iter()
        .any(|e| e == "KHR_mesh_quantization");
    for (m, mesh) in root.meshes.iter_mut().enumerate() {
        let name = mesh.name.clone().unwrap_or_default();
        for (p, primitive) in mesh.primitives.iter_mut().enumerate() {
            let label = format!("mesh {m} `{name}` primitive {p}");
            let position = primitive
                .attributes
                .get(&Checked::Valid(Semantic::Positions))
                .map(|i| i.value());
            let required = position
                .map(|i| {
                    let (components, types) = attribute_formats(&Semantic::Positions, quantized)
                        .expect("POSITION is read");
                    require(accessors, i, components, types)
                })
                .transpose()
                .map_err(|e| format!("POSITION: {e}"))
                .and_then(|_| {
                    primitive
                        .indices
                        .map(|i| require(accessors, i.value(), &[U8, U16, U32], &[Type::Scalar]))
                        .transpose()
                        .map_err(|e| format!("indices: {e}"))
                });
            if let Err(reason) = required {
                findings.primitives.insert((m, p), reason);
                continue;
            }
            let mut dropped = Vec::new();
            primitive.attributes.retain(|semantic, index| {
                let Checked::Valid(semantic) = semantic else {
                    return true;
                };
                let Some((components, types)) = attribute_formats(semantic, quantized) else {
                    return true;
                };
                match require(accessors, index.value(), components, types) {
                    Ok(()) => true,
                    Err(reason) => {
                        dropped.push(format!("{}: {reason}", semantic.to_string()));
                        false
                    }
                }
            });
            // A JOINTS_n without its WEIGHTS_n (or the reverse) is no influence set.
            let sets: Vec<u32> = primitive
                .attributes
                .keys()
                .filter_map(|k| match k {
                    Checked::Valid(Semantic::Joints(n) | Semantic::Weights(n)) => Some(*n),
                    _ => None,
                })
                .collect();
            for n in sets {
                let joints = Checked::Valid(Semantic::Joints(n));
                let weights = Checked::Valid(Semantic::Weights(n));
                if primitive.attributes.contains_key(&joints)
                    != primitive.attributes.contains_key(&weights)
                {
                    primitive.attributes.remove(&joints);
                    primitive.attributes.remove(&weights);
                }
            }
            // KHR_mesh_quantization: morph targets may be normalized or unnormalized bytes and shorts.
            let morph_formats: &[ComponentType] = if quantized { &[F32, I8, I16] } else { &[F32] };
            for (t, target) in primitive.targets.iter_mut().flatten().enumerate() {
                for (what, slot) in [
                    ("POSITION", &mut target.positions),
                    ("NORMAL", &mut target.normals),
                    ("TANGENT", &mut target.tangents),
                ] {
                    if let Some(index) = *slot
                        && let Err(reason) =
                            require(accessors, index.value(), morph_formats, &[Type::Vec3])
                    {
                        dropped.push(format!("morph target {t} {what}: {reason}"));
                        *slot = None;
                    }
                }
            }
            for d in dropped {
                findings
                    .warnings
                    .push(format!("{label}: {d}; that attribute is ignored"));
            }
        }
    }
}

fn check_skins(
    root: &mut json::Root,
    accessors: &[Result<Format, String>],
    findings: &mut Findings,
) {
    for (s, skin) in root.skins.iter_mut().enumerate() {
        if let Some(index) = skin.inverse_bind_matrices
            && let Err(reason) = require(accessors, index.value(), &[F32], &[Type::Mat4])
        {
            findings.warnings.push(format!(
                "skin {s}: inverseBindMatrices ignored ({reason}); identity used"
            ));
            skin.inverse_bind_matrices = None;
        }
    }
}

fn check_animations(
    root: &json::Root,
    accessors: &[Result<Format, String>],
    findings: &mut Findings,
) {
    for (a, animation) in root.animations.iter().enumerate() {
        for (c, channel) in animation.channels.iter().enumerate() {
            let reason = (|| {
                let sampler = animation
                    .samplers
                    .get(channel.sampler.value())
                    .ok_or_else(|| format!("sampler {} does not exist", channel.sampler.value()))?;
                let node = channel.target.node.value();
                if node >= root.nodes.len() {
                    return Err(format!(
                        "it targets node {node}, but the file has {} nodes",
                        root.nodes.len()
                    ));
                }
                let Checked::Valid(path) = channel.target.path else {
                    return Err("it targets a property raykin does not know".to_string());
                };
                require(accessors, sampler.input.value(), &[F32], &[Type::Scalar])
                    .map_err(|e| format!("keyframe times: {e}"))?;
                let (components, types): (&[ComponentType], &[Type]) = match path {
                    Property::Translation | Property::Scale => (&[F32], &[Type::Vec3]),
                    Property::Rotation => (&[F32, I8, U8, I16, U16], &[Type::Vec4]),
                    Property::MorphTargetWeights => (&[F32, I8, U8, I16, U16], &[Type::Scalar]),
                };
                require(accessors, sampler.output.value(), components, types)
                    .map_err(|e| format!("keyframe values: {e}"))
            })();
            if let Err(reason) = reason {
                findings.channels.insert((a, c), reason);
            }
        }
    }
}

fn check_images(root: &mut json::Root, findings: &mut Findings) {
    for i in 0..root.images.len() {
        let image = &root.images[i];
        let problem = match (&image.uri, image.buffer_view) {
            (None, None) => Some("it has neither a uri nor a bufferView".to_string()),
            (Some(_), Some(_)) => {
                Some("it has both a uri and a bufferView (the spec allows one)".to_string())
            }
            (None, Some(view)) if view.value() >= root.buffer_views.len() => Some(format!(
                "it names bufferView {}, which does not exist",
                view.value()
            )),
            (None, Some(view)) => view_in_buffer(root, view.value()).err(),
            (Some(_), None) => None,
        };
        if let Some(reason) = problem {
            findings.images.insert(i, reason);
            continue;
        }
        let image = &mut root.images[i];
        if image.buffer_view.is_some() && image.mime_type.is_none() {
            // The decoder recognises PNG and JPEG by their bytes; the crate unwraps the mime type.
            image.mime_type = Some(json::image::MimeType("application/octet-stream".into()));
            findings.warnings.push(format!(
                "image {i}: a bufferView image without the mimeType the spec requires; decoded by its content"
            ));
        }
    }
}

fn check_cameras(root: &mut json::Root, findings: &mut Findings) {
    use json::camera::Type as Projection;
    for (c, camera) in root.cameras.iter_mut().enumerate() {
        let declared = camera.type_;
        let fixed = match (declared, &camera.perspective, &camera.orthographic) {
            (Checked::Valid(Projection::Perspective), None, Some(_)) => Projection::Orthographic,
            (Checked::Valid(Projection::Orthographic), Some(_), None) => Projection::Perspective,
            _ => continue,
        };
        findings.warnings.push(format!(
            "camera {c}: its type does not match the projection it defines; the {} projection is used",
            if fixed == Projection::Perspective {
                "perspective"
            } else {
                "orthographic"
            }
        ));
        camera.type_ = Checked::Valid(fixed);
    }
}
