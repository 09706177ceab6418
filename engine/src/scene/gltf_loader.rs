//! glTF 2.0 (.gltf with external or data-URI buffers, and .glb) into a [`SceneAsset`].
//!
//! Problems confined to one primitive, texture or animation channel become warnings and that piece is
//! skipped; problems that make the file unusable are a [`SceneError`] naming the file.

use super::accessor::{self, Floats};
use super::material_extensions::{SlotResolver, SlotSource};
use super::*;
use super::{inputs, validate};
use gltf::accessor::DataType;
use gltf::mesh::Mode;
use std::collections::{HashMap, HashSet};
use std::path::Path;

/// The largest meshopt fallback buffer raykin allocates for decoded data (4 GiB).
const MAX_FALLBACK_BUFFER: usize = 1 << 32;

#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// Skip decoding images (BVH or geometry-only tools).
    pub skip_images: bool,
    /// The glTF scene to display (`--scene N`); `None`: the file's default scene, else its first.
    pub scene: Option<usize>,
    /// Let URIs name files outside the scene's folder (`--allow-external-files`, for trusted files).
    pub allow_external_files: bool,
    /// The KHR_materials_variants variant to show (`--variant NAME`); `None`: the file's own materials. An
    /// unknown name is [`SceneError::UnknownVariant`], which lists the file's variants.
    pub variant: Option<String>,
}

impl LoadOptions {
    /// The files these options let a scene read.
    pub fn access(&self) -> inputs::Access {
        inputs::Access {
            external_files: self.allow_external_files,
        }
    }
}

/// Loads a .gltf or .glb file.
pub fn load_gltf(path: impl AsRef<Path>, options: &LoadOptions) -> Result<SceneAsset, SceneError> {
    let path = path.as_ref();
    let io = |source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    };
    // Only a regular file: a FIFO or a device would be read without end.
    if !std::fs::metadata(path).map_err(io)?.is_file() {
        return Err(io(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "not a regular file",
        )));
    }
    let bytes = std::fs::read(path).map_err(io)?;
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut scene = load_gltf_slice(&bytes, &base, path, options)?;
    if let Ok(file) = path.canonicalize() {
        scene.files.insert(0, file);
    }
    Ok(scene)
}

/// Loads glTF bytes; external URIs resolve against `base_dir`, `name` names the source in messages.
pub fn load_gltf_slice(
    bytes: &[u8],
    base_dir: &Path,
    name: &Path,
    options: &LoadOptions,
) -> Result<SceneAsset, SceneError> {
    // The gltf crate and image decoders are not ours: a panic inside them must still become an error.
    let mut scene = crate::panic_guard::catch(|| {
        Loader::new(bytes, base_dir, name, options).and_then(Loader::load)
    })
    .unwrap_or_else(|message| {
        Err(SceneError::Internal {
            path: name.to_path_buf(),
            message,
        })
    })?;
    if let Some(variant) = &options.variant {
        scene.select_variant(Some(variant))?;
    }
    Ok(scene)
}

struct Loader<'a> {
    path: PathBuf,
    base_dir: &'a Path,
    options: &'a LoadOptions,
    document: gltf::Document,
    buffers: Vec<Vec<u8>>,
    /// Compressed (meshopt) bufferViews that failed to decode, with the reason.
    failed_views: HashMap<usize, String>,
    warnings: std::cell::RefCell<Vec<String>>,
    /// Canonical paths of the files URIs named, as read.
    files: std::cell::RefCell<Vec<PathBuf>>,
    /// Primitives, images and channels [`validate::check`] found unreadable.
    skip: validate::Findings,
}

impl<'a> Loader<'a> {
    fn new(
        bytes: &[u8],
        base_dir: &'a Path,
        name: &Path,
        options: &'a LoadOptions,
    ) -> Result<Self, SceneError> {
        let path = name.to_path_buf();
        let parsed = super::extensions::parse(bytes).map_err(|e| match e {
            super::extensions::ParseError::Unsupported(extension) => {
                SceneError::UnsupportedExtension {
                    path: path.clone(),
                    extension,
                }
            }
            super::extensions::ParseError::Invalid(reason) => SceneError::Invalid {
                path: path.clone(),
                reason,
            },
        })?;
        let mut findings = parsed.findings;
        let document = gltf::Document::from_json_without_validation(parsed.root);
        let mut loader = Self {
            path,
            base_dir,
            options,
            document,
            buffers: Vec::new(),
            failed_views: HashMap::new(),
            warnings: Default::default(),
            files: Default::default(),
            skip: Default::default(),
        };
        for w in std::mem::take(&mut findings.warnings) {
            loader.warn(w);
        }
        loader.skip = findings;
        loader.buffers = loader.load_buffers(parsed.blob)?;
        for (view, reason) in super::meshopt::decode_views(&loader.document, &mut loader.buffers) {
            loader.warn(format!(
                "bufferView {view}: meshopt-compressed data cannot be decoded ({reason}); what reads it is skipped"
            ));
            loader.failed_views.insert(view, reason);
        }
        for w in super::extensions::ignored_warnings(&loader.document) {
            loader.warn(w);
        }
        Ok(loader)
    }

    fn invalid(&self, reason: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            path: self.path.clone(),
            reason: reason.into(),
        }
    }

    /// Collects a warning for [`SceneAsset::warnings`]; the caller shows them (the CLI prints each once).
    fn warn(&self, message: String) {
        self.warnings.borrow_mut().push(message);
    }

    fn load_buffers(&self, mut blob: Option<Vec<u8>>) -> Result<Vec<Vec<u8>>, SceneError> {
        let mut buffers = Vec::new();
        for buffer in self.document.buffers() {
            let index = buffer.index();
            let fail = |uri: &str, reason: String| SceneError::Buffer {
                path: self.path.clone(),
                index,
                // A data URI can be megabytes of base64: name its kind, not its content.
                uri: if uri.starts_with("data:") {
                    "data URI".to_string()
                } else {
                    uri.to_string()
                },
                reason,
            };
            // A meshopt fallback buffer may have no data: its views are decoded into it later.
            let fallback_without_data = super::meshopt::is_fallback_buffer(&buffer)
                && matches!(buffer.source(), gltf::buffer::Source::Bin)
                && (index > 0 || blob.is_none());
            let data = match buffer.source() {
                _ if fallback_without_data => {
                    if buffer.length() > MAX_FALLBACK_BUFFER {
                        return Err(fail(
                            "meshopt fallback buffer",
                            format!(
                                "byteLength {} is over the {MAX_FALLBACK_BUFFER}-byte limit",
                                buffer.length()
                            ),
                        ));
                    }
                    vec![0; buffer.length()]
                }
                gltf::buffer::Source::Bin => blob
                    .take()
                    .ok_or_else(|| fail("GLB BIN chunk", "the .glb has no binary chunk".into()))?,
                gltf::buffer::Source::Uri(uri) => self
                    .read_uri(uri, inputs::ReadLimit::Exactly(buffer.length() as u64))
                    .map_err(|r| fail(uri, r))?,
            };
            if data.len() < buffer.length() {
                return Err(fail(
                    match buffer.source() {
                        gltf::buffer::Source::Bin => "GLB BIN chunk",
                        gltf::buffer::Source::Uri(u) => u,
                    },
                    format!(
                        "truncated: {} bytes, but byteLength is {}",
                        data.len(),
                        buffer.length()
                    ),
                ));
            }
            buffers.push(data);
        }
        Ok(buffers)
    }

    /// Reads what `uri` names within the options' access and `limit`, recording the file it opened.
    fn read_uri(&self, uri: &str, limit: inputs::ReadLimit) -> Result<Vec<u8>, String> {
        inputs::read_uri(
            self.base_dir,
            uri,
            self.options.access(),
            limit,
            &mut |file| self.files.borrow_mut().push(file),
        )
    }

    fn load(self) -> Result<SceneAsset, SceneError> {
        let images = self.load_images();
        let textures = self.load_textures(&images);
        let materials = self.load_materials(&textures);
        for line in super::material_extensions::unrendered_report(&materials) {
            self.warn(line);
        }
        let variants: Vec<String> = self
            .document
            .variants()
            .map(|v| v.map(|v| v.name().to_string()).collect())
            .unwrap_or_default();
        let meshes = self.load_meshes(&materials, variants.len())?;
        let cameras = self.load_cameras();
        let (nodes, roots) = self.load_nodes()?;
        let skins = self.load_skins();
        let animations = self.load_animations();
        let lights = super::lights::read_lights(&self.document, |w| self.warn(w));
        let mut scene = SceneAsset {
            source: self.path.display().to_string(),
            meshes,
            materials,
            images: images
                .into_iter()
                .map(|i| i.unwrap_or_else(placeholder_image))
                .collect(),
            textures,
            cameras,
            skins,
            animations,
            nodes,
            roots,
            variants,
            active_variant: None,
            lights,
            warnings: self.warnings.take(),
            files: self.files.take(),
        };
        scene.files.sort();
        scene.files.dedup();
        detach_empty_skins(&mut scene);
        super::compose::unshare_deformable_meshes(&mut scene);
        if scene.triangle_count() == 0 {
            return Err(SceneError::Empty {
                path: self.path,
                reason: if scene.warnings.is_empty() {
                    "it contains no triangle meshes".into()
                } else {
                    scene.warnings.join("; ")
                },
            });
        }
        let shown = scene.displayed_nodes();
        let world = scene.rest_world_matrices();
        for (n, node) in scene.nodes.iter().enumerate() {
            let det = world[n].determinant();
            if shown[n] && node.camera.is_some() && !(det.is_finite() && det != 0.0) {
                scene.warnings.push(format!(
                    "node {n} `{}`: its camera's world transform is singular (a scale of 0); it cannot be \
                     used as a view",
                    node.name
                ));
            }
        }
        let drawn = (0..scene.nodes.len())
            .filter(|&n| shown[n])
            .filter_map(|n| scene.nodes[n].mesh)
            .any(|m| !scene.meshes[m].triangles.is_empty());
        if !drawn {
            let scenes = self.document.scenes().len();
            return Err(SceneError::Scene {
                path: self.path,
                reason: format!(
                    "the displayed scene draws no triangles (its nodes have no meshes){}",
                    if scenes > 1 {
                        format!("; the file has {scenes} scenes: pick another with --scene N")
                    } else {
                        String::new()
                    }
                ),
            });
        }
        Ok(scene)
    }

    fn load_images(&self) -> Vec<Option<Image>> {
        let mut out = Vec::new();
        let images: Vec<_> = self.document.images().collect();
        for image in images {
            if self.options.skip_images {
                out.push(None);
                continue;
            }
            let name = image.name().unwrap_or("").to_string();
            let label = image_label(self.document.as_json(), image.index());
            let bytes = match self.skip.images.get(&image.index()) {
                Some(reason) => Err(reason.clone()),
                None => self.image_bytes(&image),
            };
            let decoded = bytes.and_then(|b| {
                if super::texture_basisu::is_ktx2(&b) {
                    return Err(
                        "a KTX2 / Basis Universal image, which raykin does not decode; textures \
                         with a PNG/JPEG source as well use that"
                            .into(),
                    );
                }
                inputs::decode_image(&b)
            });
            match decoded {
                Ok(rgba) => out.push(Some(Image {
                    name,
                    width: rgba.width(),
                    height: rgba.height(),
                    rgba8: rgba.into_raw(),
                })),
                Err(reason) => {
                    self.warn(format!(
                        "{label} skipped ({reason}); materials using it fall back to their factors"
                    ));
                    out.push(None);
                }
            }
        }
        out
    }

    /// The encoded bytes of an image: its bufferView's range, or the file its URI names.
    fn image_bytes(&self, image: &gltf::Image) -> Result<Vec<u8>, String> {
        match image.source() {
            gltf::image::Source::View { view, .. } => {
                let buffer = &self.buffers[view.buffer().index()];
                buffer
                    .get(view.offset()..view.offset() + view.length())
                    .map(<[u8]>::to_vec)
                    .ok_or_else(|| "its bufferView lies outside the buffer".to_string())
            }
            gltf::image::Source::Uri { uri, .. } => {
                self.read_uri(uri, inputs::ReadLimit::AtMost(inputs::MAX_IMAGE_FILE_BYTES))
            }
        }
    }

    /// Textures whose image failed to load are `None`; materials then drop that texture.
    fn load_textures(&self, images: &[Option<Image>]) -> Vec<Texture> {
        use gltf::texture::{MagFilter, WrappingMode};
        let wrap = |w: WrappingMode| match w {
            WrappingMode::Repeat => Wrap::Repeat,
            WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
            WrappingMode::ClampToEdge => Wrap::ClampToEdge,
        };
        self.document
            .textures()
            .map(|t| {
                let sampler = t.sampler();
                // KHR_texture_basisu may leave out the core source; its KTX2 image is not decoded.
                let image = super::texture_basisu::core_source(&self.document, t.index());
                if image.is_none()
                    && let Some(ktx2) = super::texture_basisu::basisu_source(&t)
                {
                    self.warn(format!(
                        "texture {} has only a KHR_texture_basisu image ({}), which raykin does not decode; materials using it fall back to their factors",
                        t.index(),
                        image_label(self.document.as_json(), ktx2)
                    ));
                }
                Texture {
                    image: match image {
                        Some(i) if images.get(i).is_some_and(Option::is_some) => i as u32,
                        _ => u32::MAX,
                    },
                    wrap_s: wrap(sampler.wrap_s()),
                    wrap_t: wrap(sampler.wrap_t()),
                    nearest: sampler.mag_filter() == Some(MagFilter::Nearest),
                }
            })
            .collect()
    }

    fn load_materials(&self, textures: &[Texture]) -> Vec<Material> {
        let mut out = Vec::new();
        let mut occluded = Vec::new();
        let materials: Vec<_> = self.document.materials().collect();
        for m in materials {
            let name = m.name().unwrap_or("").to_string();
            let usable: Vec<bool> = textures.iter().map(|t| t.image != u32::MAX).collect();
            let mut slots = SlotResolver {
                usable: &usable,
                material: &name,
                notes: Vec::new(),
            };
            let pbr = m.pbr_metallic_roughness();
            let base_color_texture = slots.resolve(
                pbr.base_color_texture().map(|i| SlotSource::from_info(&i)),
                "baseColor",
            );
            let metallic_roughness_texture = slots.resolve(
                pbr.metallic_roughness_texture()
                    .map(|i| SlotSource::from_info(&i)),
                "metallicRoughness",
            );
            let normal = m.normal_texture();
            let normal_texture = slots.resolve(
                normal.as_ref().map(|n| SlotSource {
                    texture: n.texture().index(),
                    tex_coord: n.tex_coord(),
                    transform: n.extension_value("KHR_texture_transform").cloned(),
                }),
                "normal",
            );
            let emissive_texture = slots.resolve(
                m.emissive_texture().map(|i| SlotSource::from_info(&i)),
                "emissive",
            );
            let extensions = super::material_extensions::read(&m, &mut slots);
            if m.occlusion_texture().is_some() {
                occluded.push(format!("material {} `{name}`", out.len()));
            }
            for w in slots.notes {
                self.warn(w);
            }
            let mut material = Material {
                name,
                // Range and finiteness are checked below, with a warning for each change.
                base_color: Vec4::from(pbr.base_color_factor()),
                base_color_texture,
                metallic: pbr.metallic_factor(),
                roughness: pbr.roughness_factor(),
                metallic_roughness_texture,
                normal_texture,
                normal_scale: normal.as_ref().map_or(1.0, |n| finite_or(n.scale(), 1.0)),
                emissive: Vec3::from(m.emissive_factor()),
                emissive_strength: m.emissive_strength().unwrap_or(1.0),
                emissive_texture,
                alpha_mode: match m.alpha_mode() {
                    gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
                    gltf::material::AlphaMode::Mask => {
                        AlphaMode::Mask(finite_or(m.alpha_cutoff().unwrap_or(0.5), 0.5))
                    }
                    gltf::material::AlphaMode::Blend => AlphaMode::Blend,
                },
                double_sided: m.double_sided(),
                extensions,
            };
            for note in super::plausible::clamp_factors(&mut material) {
                self.warn(format!(
                    "material {} `{}`: {note}",
                    out.len(),
                    material.name
                ));
            }
            out.push(material);
        }
        if !occluded.is_empty() {
            self.warn(format!(
                "occlusion textures ignored ({} materials, e.g. {}): a path tracer computes occlusion itself",
                occluded.len(),
                occluded[0]
            ));
        }
        out
    }

    fn load_meshes(
        &self,
        materials: &[Material],
        variant_count: usize,
    ) -> Result<Vec<MeshData>, SceneError> {
        let meshes: Vec<_> = self.document.meshes().collect();
        let mut out = Vec::with_capacity(meshes.len());
        // Reported once for the file: a model of a hundred primitives with a couple of slivers each (the spheres
        // of MetalRoughSpheresNoTextures) would otherwise repeat one warning a hundred times.
        let mut dropped_by_primitive = Vec::new();
        // Meshes that use glTF's default material get it appended once, after the file's materials.
        let default_material = materials.len() as u32;
        for mesh in meshes {
            let mut data = MeshData {
                name: mesh.name().unwrap_or("").to_string(),
                default_morph_weights: mesh.weights().map(<[f32]>::to_vec).unwrap_or_default(),
                ..Default::default()
            };
            let mut parts = Vec::new();
            let mut mappings = Vec::new();
            for primitive in mesh.primitives() {
                let label = format!(
                    "mesh {} `{}` primitive {}",
                    mesh.index(),
                    data.name,
                    primitive.index()
                );
                if let Some(reason) = self.skip.primitives.get(&(mesh.index(), primitive.index())) {
                    self.warn(format!("{label} skipped: {reason}"));
                    continue;
                }
                match self.read_primitive(&primitive) {
                    Ok((part, dropped)) => {
                        if dropped.any() {
                            dropped_by_primitive.push((label.clone(), dropped));
                        }
                        let mut notes = Vec::new();
                        mappings.push(super::variants::read_mappings(
                            &primitive,
                            variant_count,
                            materials.len(),
                            &mut notes,
                        ));
                        for n in notes {
                            self.warn(format!("{label}: {n}"));
                        }
                        parts.push((
                            part,
                            primitive
                                .material()
                                .index()
                                .map_or(default_material, |i| i as u32),
                        ));
                    }
                    Err(reason) => self.warn(format!("{label} skipped: {reason}")),
                }
            }
            if mappings.iter().any(|m| !m.is_empty()) {
                let mut first = 0u32;
                for ((part, material), mappings) in parts.iter().zip(mappings) {
                    let count = part.triangles.len() as u32;
                    data.primitive_variants
                        .push(super::variants::PrimitiveVariants {
                            triangles: first..first + count,
                            file_material: *material,
                            mappings,
                        });
                    first += count;
                }
            }
            merge_primitives(&mut data, parts);
            let needs_tangents = data.primitives.iter().any(|p| {
                materials
                    .get(p.material as usize)
                    .is_some_and(|m| m.normal_texture.is_some())
            });
            if needs_tangents && data.tangents.is_none() {
                data.tangents = super::tangents::generate(&data);
            }
            out.push(data);
        }
        for warning in dropped_triangle_warnings(&dropped_by_primitive) {
            self.warn(warning);
        }
        Ok(out)
    }

    /// Reads one primitive; returns its data and the triangles it dropped.
    fn read_primitive(
        &self,
        primitive: &gltf::Primitive,
    ) -> Result<(PrimitiveData, DroppedTriangles), String> {
        // Refuse points and lines before decoding anything.
        assemble_triangles(primitive.mode(), &[])?;
        let draco = primitive
            .extension_value(super::draco::EXTENSION)
            .map(|ext| super::draco::decode(primitive, ext, &self.document, &self.buffers))
            .transpose()?;
        let source = VertexSource {
            loader: self,
            draco: draco.as_ref(),
        };
        let position_accessor = primitive
            .get(&gltf::Semantic::Positions)
            .ok_or("it has no POSITION attribute")?;
        let count = draco
            .as_ref()
            .map_or(position_accessor.count(), |d| d.vertex_count);
        let expect = |n: usize, what: &str| -> Result<(), String> {
            if n == count {
                Ok(())
            } else {
                Err(format!(
                    "{what} has {n} elements, POSITION has {count} (accessor lies outside its buffer or counts differ)"
                ))
            }
        };
        let positions: Vec<Vec3> = source
            .vectors::<3>(primitive, gltf::Semantic::Positions, POSITION_TYPES)?
            .ok_or("it has no POSITION attribute")?
            .into_iter()
            .map(Vec3::from)
            .collect();
        expect(positions.len(), "POSITION")?;

        let mut part = PrimitiveData {
            positions,
            ..Default::default()
        };
        if let Some(n) =
            source.vectors::<3>(primitive, gltf::Semantic::Normals, UNIT_VECTOR_TYPES)?
        {
            let normals: Vec<Vec3> = n
                .into_iter()
                .map(|v| finite_or(Vec3::from(v), Vec3::ZERO))
                .collect();
            expect(normals.len(), "NORMAL")?;
            part.normals = Some(normals);
        }
        if let Some(t) =
            source.vectors::<4>(primitive, gltf::Semantic::Tangents, UNIT_VECTOR_TYPES)?
        {
            let tangents: Vec<Vec4> = t
                .into_iter()
                .map(|v| finite_or(Vec4::from(v), Vec4::ZERO))
                .collect();
            expect(tangents.len(), "TANGENT")?;
            part.tangents = Some(tangents);
        }
        for set in 0..2 {
            if let Some(uv) =
                source.vectors::<2>(primitive, gltf::Semantic::TexCoords(set), TEXCOORD_TYPES)?
            {
                let uv: Vec<Vec2> = uv
                    .into_iter()
                    .map(|v| finite_or(Vec2::from(v), Vec2::ZERO))
                    .collect();
                expect(uv.len(), "TEXCOORD")?;
                part.uv[set as usize] = Some(uv);
            }
        }
        if let Some(c) = source.floats(primitive, gltf::Semantic::Colors(0), COLOR_TYPES)? {
            let colors: Vec<Vec4> = match c.dims {
                3 => c
                    .to_arrays::<3>()
                    .into_iter()
                    .map(|v| Vec3::from(v).extend(1.0))
                    .collect(),
                4 => c.to_arrays::<4>().into_iter().map(Vec4::from).collect(),
                d => return Err(format!("COLOR_0 has {d} components; VEC3 or VEC4 expected")),
            };
            let colors: Vec<Vec4> = colors
                .into_iter()
                .map(|v| finite_or(v, Vec4::ONE))
                .collect();
            expect(colors.len(), "COLOR_0")?;
            part.colors = Some(colors);
        }
        let mut sets = 0;
        while let (Some(j), Some(w)) = (
            source.vectors::<4>(primitive, gltf::Semantic::Joints(sets), JOINT_TYPES)?,
            source.vectors::<4>(primitive, gltf::Semantic::Weights(sets), WEIGHT_TYPES)?,
        ) {
            let joints: Vec<[u16; 4]> = j
                .into_iter()
                .map(|j| {
                    j.map(|x| {
                        if x.fract() == 0.0 && (0.0..=65535.0).contains(&x) {
                            Ok(x as u16)
                        } else {
                            Err(format!("JOINTS_{sets} holds {x}, not a joint index"))
                        }
                    })
                    .into_iter()
                    .collect::<Result<Vec<u16>, String>>()
                    .map(|v| [v[0], v[1], v[2], v[3]])
                })
                .collect::<Result<_, _>>()?;
            let weights: Vec<[f32; 4]> = w
                .into_iter()
                .map(|w| w.map(|x| if x.is_finite() { x.max(0.0) } else { 0.0 }))
                .collect();
            expect(joints.len(), "JOINTS")?;
            expect(weights.len(), "WEIGHTS")?;
            part.joints.push(joints);
            part.weights.push(weights);
            sets += 1;
        }
        for (i, target) in primitive.morph_targets().enumerate() {
            let read =
                |a: Option<gltf::Accessor>, types: &[(DataType, Option<bool>)], what: &str| {
                    a.map(|a| source.accessor_vectors::<3>(&a, types, what))
                        .transpose()
                        .map(|v| {
                            v.map(|v| {
                                v.into_iter()
                                    .map(|p| finite_or(Vec3::from(p), Vec3::ZERO))
                                    .collect::<Vec<Vec3>>()
                            })
                        })
                };
            let positions = read(target.positions(), MORPH_POSITION_TYPES, "morph POSITION")?
                .unwrap_or_else(|| vec![Vec3::ZERO; count]);
            expect(positions.len(), &format!("morph target {i} POSITION"))?;
            let normals = read(target.normals(), UNIT_VECTOR_TYPES, "morph NORMAL")?;
            let tangents = read(target.tangents(), UNIT_VECTOR_TYPES, "morph TANGENT")?;
            if let Some(n) = &normals {
                expect(n.len(), "morph target NORMAL")?;
            }
            if let Some(t) = &tangents {
                expect(t.len(), "morph target TANGENT")?;
            }
            part.morph_targets.push(MorphTarget {
                positions,
                normals,
                tangents,
            });
        }

        let indices: Vec<u32> = match (&draco, primitive.indices()) {
            (Some(d), _) => d.indices.clone(),
            (None, Some(accessor)) => {
                source.check_view(&accessor)?;
                accessor::read_indices(&accessor, &self.buffers)?
            }
            (None, None) => (0..count as u32).collect(),
        };
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= count) {
            return Err(format!(
                "index {bad} is out of range: the primitive has {count} vertices"
            ));
        }
        let triangles = assemble_triangles(primitive.mode(), &indices)?;

        let mut dropped = DroppedTriangles::default();
        part.triangles = triangles
            .into_iter()
            .filter(|t| {
                let [a, b, c] = t.map(|i| part.positions[i as usize]);
                if !(a.is_finite() && b.is_finite() && c.is_finite()) {
                    dropped.non_finite += 1;
                    return false;
                }
                // Zero-area triangles can never be hit, and their normals are undefined: drop them.
                if (b - a).cross(c - a).length_squared() <= 0.0 {
                    dropped.zero_area += 1;
                    return false;
                }
                true
            })
            .collect();
        // Non-finite positions must not reach the BVH: they would poison every bound above them.
        for p in &mut part.positions {
            if !p.is_finite() {
                *p = Vec3::ZERO;
            }
        }
        if part.triangles.is_empty() {
            let notes = dropped.notes();
            return Err(if notes.is_empty() {
                "it has no triangles".into()
            } else {
                notes.join(", ")
            });
        }
        Ok((part, dropped))
    }

    fn load_cameras(&self) -> Vec<PerspectiveCamera> {
        let cameras: Vec<_> = self.document.cameras().collect();
        let mut out = Vec::new();
        for c in cameras {
            match c.projection() {
                gltf::camera::Projection::Perspective(p) => out.push(PerspectiveCamera {
                    yfov: {
                        let yfov = p.yfov();
                        let valid = finite_or(yfov, 0.8).clamp(1e-3, 3.1);
                        if valid != yfov {
                            self.warn(format!(
                                "camera {}: yfov {yfov} is not an angle in (0, pi) radians; {valid} used",
                                c.index()
                            ));
                        }
                        valid
                    },
                    aspect_ratio: p.aspect_ratio().filter(|a| a.is_finite() && *a > 0.0),
                    znear: p.znear(),
                }),
                gltf::camera::Projection::Orthographic(_) => {
                    self.warn(format!(
                        "camera {} is orthographic; raykin renders it as a 45 degree perspective camera",
                        c.index()
                    ));
                    out.push(PerspectiveCamera {
                        yfov: 45f32.to_radians(),
                        aspect_ratio: None,
                        znear: 0.01,
                    });
                }
            }
        }
        out
    }

    fn load_nodes(&self) -> Result<(Vec<NodeData>, Vec<usize>), SceneError> {
        let mut nodes: Vec<NodeData> = self
            .document
            .nodes()
            .map(|n| {
                let (t, r, s) = n.transform().decomposed();
                let rotation = Quat::from_array(r);
                NodeData {
                    name: n.name().unwrap_or("").to_string(),
                    parent: None,
                    children: n.children().map(|c| c.index()).collect(),
                    transform: NodeTransform {
                        translation: finite_or(Vec3::from(t), Vec3::ZERO),
                        rotation: if rotation.is_finite() && rotation.length() > 0.0 {
                            rotation.normalize()
                        } else {
                            Quat::IDENTITY
                        },
                        scale: finite_or(Vec3::from(s), Vec3::ONE),
                    },
                    mesh: n.mesh().map(|m| m.index()),
                    camera: n.camera().map(|c| c.index()),
                    skin: n.skin().map(|s| s.index()),
                    light: n.light().map(|l| l.index()),
                    morph_weights: n.weights().map(<[f32]>::to_vec),
                }
            })
            .collect();
        for i in 0..nodes.len() {
            for c in nodes[i].children.clone() {
                if let Some(p) = nodes[c].parent {
                    return Err(self.invalid(format!("node {c} has two parents ({p} and {i}); a glTF node hierarchy must be a forest")));
                }
                nodes[c].parent = Some(i);
            }
        }
        let roots = self.scene_roots(&nodes)?;
        // Walk from the roots: a cycle would revisit a node.
        let mut seen = HashSet::new();
        let mut stack = roots.clone();
        while let Some(n) = stack.pop() {
            if !seen.insert(n) {
                return Err(
                    self.invalid(format!("the node hierarchy has a cycle through node {n}"))
                );
            }
            stack.extend(&nodes[n].children);
        }
        if roots.iter().any(|&r| nodes[r].parent.is_some()) {
            return Err(self.invalid("a scene lists a node that is also another node's child"));
        }
        // Nodes outside the displayed scene: every node must be reachable from a parentless node, else it
        // sits on a cycle (each node has at most one parent, so an unreachable node loops back to itself).
        stack = (0..nodes.len())
            .filter(|&i| nodes[i].parent.is_none() && !seen.contains(&i))
            .collect();
        while let Some(n) = stack.pop() {
            if !seen.insert(n) {
                return Err(
                    self.invalid(format!("the node hierarchy has a cycle through node {n}"))
                );
            }
            stack.extend(&nodes[n].children);
        }
        if let Some(n) = (0..nodes.len()).find(|n| !seen.contains(n)) {
            return Err(self.invalid(format!("the node hierarchy has a cycle through node {n}")));
        }
        let mut instanced = Vec::new();
        for node in self.document.nodes() {
            let label = format!("node {} `{}`", node.index(), node.name().unwrap_or(""));
            match super::instancing::read(&node, &self.document, &self.buffers) {
                Ok(None) => {}
                Ok(Some(_)) if node.mesh().is_none() => self.warn(format!(
                    "{label}: EXT_mesh_gpu_instancing on a node without a mesh; ignored"
                )),
                Ok(Some((transforms, note))) => {
                    if let Some(note) = note {
                        self.warn(format!("{label}: {note}"));
                    }
                    if node.skin().is_some() {
                        self.warn(format!(
                            "{label}: instances of a skinned mesh all follow the skin's joints, so they coincide"
                        ));
                    }
                    instanced.push((node.index(), transforms));
                }
                Err(reason) => self.warn(format!(
                    "{label}: instancing ignored ({reason}); the mesh is drawn once"
                )),
            }
        }
        super::instancing::expand(&mut nodes, instanced);
        Ok((nodes, roots))
    }

    /// Root nodes of the displayed scene: `--scene N`, else the default scene, else the first; a file
    /// without scenes shows every parentless node. Choosing an empty scene is an error that lists the others.
    fn scene_roots(&self, nodes: &[NodeData]) -> Result<Vec<usize>, SceneError> {
        let scenes: Vec<gltf::Scene> = self.document.scenes().collect();
        let listing = || {
            let names: Vec<String> = scenes
                .iter()
                .map(|s| {
                    format!(
                        "{} `{}` ({} root nodes)",
                        s.index(),
                        s.name().unwrap_or(""),
                        s.nodes().len()
                    )
                })
                .collect();
            format!(
                "the file has {} scene(s): {}",
                scenes.len(),
                names.join(", ")
            )
        };
        let fail = |reason: String| SceneError::Scene {
            path: self.path.clone(),
            reason,
        };
        let chosen = match self.options.scene {
            Some(n) => Some(
                scenes
                    .get(n)
                    .ok_or_else(|| fail(format!("there is no scene {n}: {}", listing())))?,
            ),
            None => self
                .document
                .default_scene()
                .map(|s| s.index())
                .or((!scenes.is_empty()).then_some(0))
                .map(|i| &scenes[i]),
        };
        let Some(scene) = chosen else {
            return Ok((0..nodes.len())
                .filter(|&i| nodes[i].parent.is_none())
                .collect());
        };
        let roots: Vec<usize> = scene.nodes().map(|n| n.index()).collect();
        if roots.is_empty() {
            return Err(fail(format!(
                "scene {} `{}`{} lists no nodes, so there is nothing to render; {}{}",
                scene.index(),
                scene.name().unwrap_or(""),
                if self.options.scene.is_none() {
                    " (the default scene)"
                } else {
                    ""
                },
                listing(),
                if scenes.len() > 1 {
                    "; pick another with --scene N"
                } else {
                    ""
                }
            )));
        }
        Ok(roots)
    }

    fn load_skins(&self) -> Vec<SkinData> {
        let buffers = &self.buffers;
        let mut warnings = Vec::new();
        let skins = self
            .document
            .skins()
            .map(|skin| {
                let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
                let reader = skin.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
                let mut ibm: Vec<Mat4> = match reader.read_inverse_bind_matrices() {
                    Some(m) => m.map(|m| Mat4::from_cols_array_2d(&m)).collect(),
                    None => vec![Mat4::IDENTITY; joints.len()],
                };
                if ibm.len() != joints.len() || ibm.iter().any(|m| !m.is_finite()) {
                    warnings.push(format!(
                        "skin {}: inverseBindMatrices unreadable or not finite; identity used",
                        skin.index()
                    ));
                    ibm = vec![Mat4::IDENTITY; joints.len()];
                }
                SkinData {
                    name: skin.name().unwrap_or("").to_string(),
                    joints,
                    inverse_bind_matrices: ibm,
                    skeleton: skin.skeleton().map(|s| s.index()),
                }
            })
            .collect();
        for w in warnings {
            self.warn(w);
        }
        skins
    }

    fn load_animations(&self) -> Vec<AnimationClip> {
        use gltf::animation::util::ReadOutputs;
        let buffers = &self.buffers;
        let mut warnings = Vec::new();
        let mut clips = Vec::new();
        for anim in self.document.animations() {
            let name = anim
                .name()
                .map(str::to_string)
                .unwrap_or_else(|| format!("animation {}", anim.index()));
            let mut channels = Vec::new();
            for channel in anim.channels() {
                if let Some(reason) = self.skip.channels.get(&(anim.index(), channel.index())) {
                    warnings.push(format!(
                        "{name} channel {}: {reason}; channel skipped",
                        channel.index()
                    ));
                    continue;
                }
                let reader = channel.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
                let label = format!("{name} channel {}", channel.index());
                let interpolation = match channel.sampler().interpolation() {
                    gltf::animation::Interpolation::Step => Interpolation::Step,
                    gltf::animation::Interpolation::Linear => Interpolation::Linear,
                    gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
                };
                let Some(times) = reader.read_inputs().map(|t| t.collect::<Vec<f32>>()) else {
                    warnings.push(format!(
                        "{label}: keyframe times unreadable; channel skipped"
                    ));
                    continue;
                };
                let values = match reader.read_outputs() {
                    Some(ReadOutputs::Translations(v)) => {
                        ChannelValues::Translation(v.map(Vec3::from).collect())
                    }
                    Some(ReadOutputs::Rotations(v)) => {
                        ChannelValues::Rotation(v.into_f32().map(Quat::from_array).collect())
                    }
                    Some(ReadOutputs::Scales(v)) => {
                        ChannelValues::Scale(v.map(Vec3::from).collect())
                    }
                    Some(ReadOutputs::MorphTargetWeights(v)) => {
                        let values: Vec<f32> = v.into_f32().collect();
                        let keys = times.len()
                            * if interpolation == Interpolation::CubicSpline {
                                3
                            } else {
                                1
                            };
                        ChannelValues::Weights {
                            count: values.len().checked_div(keys).unwrap_or(0),
                            values,
                        }
                    }
                    None => {
                        warnings.push(format!(
                            "{label}: keyframe values unreadable; channel skipped"
                        ));
                        continue;
                    }
                };
                let channel = AnimationChannel {
                    node: channel.target().node().index(),
                    interpolation,
                    times,
                    values,
                };
                match channel.validate() {
                    Ok(()) => channels.push(channel),
                    Err(reason) => warnings.push(format!("{label}: {reason}; channel skipped")),
                }
            }
            let duration = channels
                .iter()
                .filter_map(|c| c.times.last().copied())
                .fold(0.0f32, f32::max);
            clips.push(AnimationClip {
                name,
                channels,
                duration,
            });
        }
        for w in warnings {
            self.warn(w);
        }
        clips
    }
}

/// A skin without joints places no vertex: its nodes draw their mesh rigidly, with the node's transform. The
/// skin is detached here, and a mesh no skinned node uses loses its JOINTS/WEIGHTS, so the CPU and GPU
/// deformers both see a plain mesh.
fn detach_empty_skins(scene: &mut SceneAsset) {
    for (n, node) in scene.nodes.iter_mut().enumerate() {
        if let Some(s) = node.skin
            && scene.skins.get(s).is_none_or(|skin| skin.joints.is_empty())
        {
            scene.warnings.push(format!(
                "node {n}: skin {s} has no joints; the mesh is drawn rigidly with the node"
            ));
            node.skin = None;
        }
    }
    let mut skinned = vec![false; scene.meshes.len()];
    for node in &scene.nodes {
        if let (Some(m), Some(_)) = (node.mesh, node.skin) {
            skinned[m] = true;
        }
    }
    for (mesh, skinned) in scene.meshes.iter_mut().zip(skinned) {
        if !skinned {
            mesh.skin_weights = None;
        }
    }
}

/// Component types each attribute may have: glTF 2.0's, widened by KHR_mesh_quantization
/// (`Some(true)`: normalized only, `Some(false)`: unnormalized only, `None`: either).
const POSITION_TYPES: &[(DataType, Option<bool>)] = &[
    (DataType::F32, Some(false)),
    (DataType::I8, None),
    (DataType::U8, None),
    (DataType::I16, None),
    (DataType::U16, None),
];
const UNIT_VECTOR_TYPES: &[(DataType, Option<bool>)] = &[
    (DataType::F32, Some(false)),
    (DataType::I8, Some(true)),
    (DataType::I16, Some(true)),
];
const TEXCOORD_TYPES: &[(DataType, Option<bool>)] = POSITION_TYPES;
const MORPH_POSITION_TYPES: &[(DataType, Option<bool>)] = &[
    (DataType::F32, Some(false)),
    (DataType::I8, None),
    (DataType::I16, None),
];
const COLOR_TYPES: &[(DataType, Option<bool>)] = &[
    (DataType::F32, Some(false)),
    (DataType::U8, Some(true)),
    (DataType::U16, Some(true)),
];
const JOINT_TYPES: &[(DataType, Option<bool>)] =
    &[(DataType::U8, Some(false)), (DataType::U16, Some(false))];
const WEIGHT_TYPES: &[(DataType, Option<bool>)] = &[
    (DataType::F32, Some(false)),
    (DataType::U8, Some(true)),
    (DataType::U16, Some(true)),
];

/// Where a primitive's vertex attributes come from: its accessors, or a decoded Draco bitstream (for the
/// attributes the bitstream carries).
struct VertexSource<'l, 'a> {
    loader: &'l Loader<'a>,
    draco: Option<&'l super::draco::DracoPrimitive>,
}

impl VertexSource<'_, '_> {
    /// An attribute's values, or `None` when the primitive lacks it.
    fn floats(
        &self,
        primitive: &gltf::Primitive,
        semantic: gltf::Semantic,
        types: &[(DataType, Option<bool>)],
    ) -> Result<Option<Floats>, String> {
        let name = semantic.to_string();
        let Some(accessor) = primitive.get(&semantic) else {
            return Ok(None);
        };
        if let Some(draco) = self.draco
            && draco.has(&name)
        {
            return Ok(draco.floats(&name, &accessor));
        }
        accessor::check_attribute_type(&accessor, types, &name)?;
        self.check_view(&accessor)?;
        accessor::read_floats(&accessor, &self.loader.buffers, &name).map(Some)
    }

    fn vectors<const N: usize>(
        &self,
        primitive: &gltf::Primitive,
        semantic: gltf::Semantic,
        types: &[(DataType, Option<bool>)],
    ) -> Result<Option<Vec<[f32; N]>>, String> {
        let name = semantic.to_string();
        match self.floats(primitive, semantic, types)? {
            None => Ok(None),
            Some(f) if f.dims == N => Ok(Some(f.to_arrays())),
            Some(f) => Err(format!(
                "{name} has {} components per element, {N} expected",
                f.dims
            )),
        }
    }

    /// Reads an accessor that is never Draco-compressed (morph targets).
    fn accessor_vectors<const N: usize>(
        &self,
        accessor: &gltf::Accessor,
        types: &[(DataType, Option<bool>)],
        what: &str,
    ) -> Result<Vec<[f32; N]>, String> {
        accessor::check_attribute_type(accessor, types, what)?;
        self.check_view(accessor)?;
        accessor::read_vectors::<N>(accessor, &self.loader.buffers, what)
    }

    /// Fails when the accessor's data is in a compressed bufferView that did not decode.
    fn check_view(&self, accessor: &gltf::Accessor) -> Result<(), String> {
        let views = accessor.view().into_iter().chain(
            accessor
                .sparse()
                .into_iter()
                .flat_map(|s| [s.indices().view(), s.values().view()]),
        );
        for view in views {
            if let Some(reason) = self.loader.failed_views.get(&view.index()) {
                return Err(format!(
                    "accessor {} reads bufferView {}, whose meshopt-compressed data cannot be decoded ({reason})",
                    accessor.index(),
                    view.index()
                ));
            }
        }
        Ok(())
    }
}

/// One primitive's attributes before merging into its mesh.
#[derive(Default)]
struct PrimitiveData {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    tangents: Option<Vec<Vec4>>,
    uv: [Option<Vec<Vec2>>; 2],
    colors: Option<Vec<Vec4>>,
    joints: Vec<Vec<[u16; 4]>>,
    weights: Vec<Vec<[f32; 4]>>,
    morph_targets: Vec<MorphTarget>,
    triangles: Vec<[u32; 3]>,
}

/// Concatenates primitives; an attribute some primitives lack is filled with a neutral value for them.
fn merge_primitives(mesh: &mut MeshData, parts: Vec<(PrimitiveData, u32)>) {
    fn merge<T: Clone>(
        parts: &[(PrimitiveData, u32)],
        get: impl Fn(&PrimitiveData) -> Option<&Vec<T>>,
        fill: T,
    ) -> Option<Vec<T>> {
        if !parts.iter().any(|(p, _)| get(p).is_some()) {
            return None;
        }
        let mut out = Vec::new();
        for (p, _) in parts {
            match get(p) {
                Some(v) => out.extend_from_slice(v),
                None => out.extend(std::iter::repeat_n(fill.clone(), p.positions.len())),
            }
        }
        Some(out)
    }
    mesh.normals = merge(&parts, |p| p.normals.as_ref(), Vec3::ZERO);
    mesh.tangents = merge(&parts, |p| p.tangents.as_ref(), Vec4::ZERO);
    mesh.uv0 = merge(&parts, |p| p.uv[0].as_ref(), Vec2::ZERO);
    mesh.uv1 = merge(&parts, |p| p.uv[1].as_ref(), Vec2::ZERO);
    mesh.colors = merge(&parts, |p| p.colors.as_ref(), Vec4::ONE);

    let sets = parts.iter().map(|(p, _)| p.joints.len()).max().unwrap_or(0);
    if sets > 0 {
        let mut skin = SkinWeights {
            sets: sets as u32,
            ..Default::default()
        };
        for (p, _) in &parts {
            for v in 0..p.positions.len() {
                for s in 0..sets {
                    skin.joints.push(p.joints.get(s).map_or([0; 4], |j| j[v]));
                    skin.weights
                        .push(p.weights.get(s).map_or([0.0; 4], |w| w[v]));
                }
            }
        }
        mesh.skin_weights = Some(skin);
    }
    let targets = parts
        .iter()
        .map(|(p, _)| p.morph_targets.len())
        .max()
        .unwrap_or(0);
    for t in 0..targets {
        let has_normals = parts
            .iter()
            .any(|(p, _)| p.morph_targets.get(t).is_some_and(|m| m.normals.is_some()));
        let has_tangents = parts
            .iter()
            .any(|(p, _)| p.morph_targets.get(t).is_some_and(|m| m.tangents.is_some()));
        let mut target = MorphTarget {
            normals: has_normals.then(Vec::new),
            tangents: has_tangents.then(Vec::new),
            ..Default::default()
        };
        for (p, _) in &parts {
            let n = p.positions.len();
            let m = p.morph_targets.get(t);
            target
                .positions
                .extend(m.map_or(vec![Vec3::ZERO; n], |m| m.positions.clone()));
            if let Some(out) = &mut target.normals {
                out.extend(
                    m.and_then(|m| m.normals.clone())
                        .unwrap_or_else(|| vec![Vec3::ZERO; n]),
                );
            }
            if let Some(out) = &mut target.tangents {
                out.extend(
                    m.and_then(|m| m.tangents.clone())
                        .unwrap_or_else(|| vec![Vec3::ZERO; n]),
                );
            }
        }
        mesh.morph_targets.push(target);
    }

    for (p, material) in parts {
        let offset = mesh.positions.len() as u32;
        mesh.primitives.push(PrimitiveRange {
            vertex_offset: offset,
            vertex_count: p.positions.len() as u32,
            material,
        });
        mesh.triangles
            .extend(p.triangles.iter().map(|t| t.map(|i| i + offset)));
        mesh.triangle_materials
            .extend(std::iter::repeat_n(material, p.triangles.len()));
        mesh.positions.extend(p.positions);
    }
}

fn assemble_triangles(mode: Mode, indices: &[u32]) -> Result<Vec<[u32; 3]>, String> {
    Ok(match mode {
        Mode::Triangles => indices
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect(),
        Mode::TriangleStrip => (2..indices.len())
            .map(|i| {
                if i % 2 == 0 {
                    [indices[i - 2], indices[i - 1], indices[i]]
                } else {
                    [indices[i - 1], indices[i - 2], indices[i]]
                }
            })
            .collect(),
        Mode::TriangleFan => (2..indices.len())
            .map(|i| [indices[0], indices[i - 1], indices[i]])
            .collect(),
        other => {
            return Err(format!(
                "mode {other:?} has no triangles (points and lines are not path-traced)"
            ));
        }
    })
}

/// Names an image in messages: index, then its name, else its URI, else its MIME type and bufferView.
/// "image N `name`" for messages, from the JSON: `gltf::Image::source` panics on an image with neither a uri
/// nor a bufferView (which validate.rs reports, and this label names).
fn image_label(root: &gltf::json::Root, index: usize) -> String {
    let Some(json) = root.images.get(index) else {
        return format!("image {index}, which does not exist");
    };
    let what = match (json.name.as_deref(), &json.uri, json.buffer_view) {
        (Some(name), _, _) if !name.is_empty() => format!("`{name}`"),
        (_, Some(uri), _) if !uri.starts_with("data:") => format!("`{uri}`"),
        (_, Some(_), _) => format!(
            "(data URI, {})",
            json.mime_type
                .as_ref()
                .map_or("no MIME type", |m| m.0.as_str())
        ),
        (_, None, Some(view)) => format!(
            "({} in bufferView {})",
            json.mime_type
                .as_ref()
                .map_or("no MIME type", |m| m.0.as_str()),
            view.value()
        ),
        (_, None, None) => "(no uri or bufferView)".to_string(),
    };
    format!("image {index} {what}")
}

/// A 1x1 white image standing in for one that failed to load (its textures are already detached).
fn placeholder_image() -> Image {
    Image {
        name: "missing".into(),
        width: 1,
        height: 1,
        rgba8: vec![255; 4],
    }
}

trait Finite {
    fn all_finite(&self) -> bool;
}
impl Finite for f32 {
    fn all_finite(&self) -> bool {
        self.is_finite()
    }
}
impl Finite for Vec2 {
    fn all_finite(&self) -> bool {
        self.is_finite()
    }
}
impl Finite for Vec3 {
    fn all_finite(&self) -> bool {
        self.is_finite()
    }
}
impl Finite for Vec4 {
    fn all_finite(&self) -> bool {
        self.is_finite()
    }
}
fn finite_or<T: Finite>(v: T, fallback: T) -> T {
    if v.all_finite() { v } else { fallback }
}

/// Triangles a primitive lost on loading.
#[derive(Clone, Copy, Debug, Default)]
struct DroppedTriangles {
    /// With a NaN or infinite vertex position.
    non_finite: usize,
    /// Of zero area (repeated or collinear vertices).
    zero_area: usize,
}

/// What each of [`DroppedTriangles::counts`] counts, as the warnings say it.
const DROPPED_KINDS: [&str; 2] = [
    "triangles with NaN or infinite vertex positions",
    "zero-area triangles",
];

impl DroppedTriangles {
    /// The counts in [`DROPPED_KINDS`]' order.
    fn counts(&self) -> [usize; 2] {
        [self.non_finite, self.zero_area]
    }

    fn any(&self) -> bool {
        self.counts().iter().any(|&n| n > 0)
    }

    fn notes(&self) -> Vec<String> {
        DROPPED_KINDS
            .iter()
            .zip(self.counts())
            .filter(|&(_, n)| n > 0)
            .map(|(what, n)| format!("{n} {what} dropped"))
            .collect()
    }
}

/// The primitives named in a summed warning before "and N more".
const DROPPED_NAMED: usize = 3;

/// One warning per kind of dropped triangle for the whole file: the primitive's label where one primitive
/// dropped any, else the total, the number of primitives and the first few with their counts.
fn dropped_triangle_warnings(dropped: &[(String, DroppedTriangles)]) -> Vec<String> {
    let mut warnings = Vec::new();
    for (kind, what) in DROPPED_KINDS.iter().enumerate() {
        let hit: Vec<(&str, usize)> = dropped
            .iter()
            .map(|(label, d)| (label.as_str(), d.counts()[kind]))
            .filter(|&(_, n)| n > 0)
            .collect();
        match hit.as_slice() {
            [] => {}
            [(label, n)] => warnings.push(format!("{label}: {n} {what} dropped")),
            _ => {
                let total: usize = hit.iter().map(|&(_, n)| n).sum();
                let mut named: Vec<String> = hit
                    .iter()
                    .take(DROPPED_NAMED)
                    .map(|(label, n)| format!("{label}: {n}"))
                    .collect();
                if hit.len() > DROPPED_NAMED {
                    named.push(format!("and {} more", hit.len() - DROPPED_NAMED));
                }
                warnings.push(format!(
                    "{total} {what} dropped from {} primitives ({})",
                    hit.len(),
                    named.join("; ")
                ));
            }
        }
    }
    warnings
}
