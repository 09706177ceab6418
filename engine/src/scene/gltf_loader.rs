//! glTF 2.0 (.gltf with external or data-URI buffers, and .glb) into a [`SceneAsset`].
//!
//! Problems confined to one primitive, texture or animation channel become warnings and that piece is
//! skipped; problems that make the file unusable are a [`SceneError`] naming the file.

use super::*;
use base64::Engine as _;
use gltf::mesh::Mode;
use std::collections::HashSet;
use std::path::Path;

/// glTF extensions raykin honours when a file lists them as required.
const SUPPORTED_REQUIRED_EXTENSIONS: &[&str] =
    &["KHR_materials_emissive_strength", "KHR_lights_punctual"];

#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// Skip decoding images (BVH or geometry-only tools).
    pub skip_images: bool,
}

/// Loads a .gltf or .glb file.
pub fn load_gltf(path: impl AsRef<Path>, options: &LoadOptions) -> Result<SceneAsset, SceneError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    load_gltf_slice(&bytes, &base, path, options)
}

/// Loads glTF bytes; external URIs resolve against `base_dir`, `name` names the source in messages.
pub fn load_gltf_slice(
    bytes: &[u8],
    base_dir: &Path,
    name: &Path,
    options: &LoadOptions,
) -> Result<SceneAsset, SceneError> {
    // The gltf crate and image decoders are not ours: a panic inside them must still become an error.
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        Loader::new(bytes, base_dir, name, options).and_then(Loader::load)
    }));
    result.unwrap_or_else(|panic| {
        let reason = panic
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_else(|| "the decoder panicked".into());
        Err(SceneError::Invalid {
            path: name.to_path_buf(),
            reason,
        })
    })
}

struct Loader<'a> {
    path: PathBuf,
    base_dir: &'a Path,
    options: &'a LoadOptions,
    document: gltf::Document,
    buffers: Vec<Vec<u8>>,
    warnings: std::cell::RefCell<Vec<String>>,
}

impl<'a> Loader<'a> {
    fn new(
        bytes: &[u8],
        base_dir: &'a Path,
        name: &Path,
        options: &'a LoadOptions,
    ) -> Result<Self, SceneError> {
        let path = name.to_path_buf();
        let gltf = gltf::Gltf::from_slice(bytes).map_err(|e| {
            // The crate's validation rejects unknown required extensions; name the extension plainly.
            if let Ok(unvalidated) = gltf::Gltf::from_slice_without_validation(bytes)
                && let Some(ext) = unvalidated
                    .document
                    .extensions_required()
                    .find(|ext| !SUPPORTED_REQUIRED_EXTENSIONS.contains(ext))
            {
                return SceneError::UnsupportedExtension {
                    path: path.clone(),
                    extension: ext.to_string(),
                };
            }
            SceneError::Invalid {
                path: path.clone(),
                reason: describe_gltf_error(&e),
            }
        })?;
        for ext in gltf.document.extensions_required() {
            if !SUPPORTED_REQUIRED_EXTENSIONS.contains(&ext) {
                return Err(SceneError::UnsupportedExtension {
                    path,
                    extension: ext.to_string(),
                });
            }
        }
        let mut loader = Self {
            path,
            base_dir,
            options,
            document: gltf.document,
            buffers: Vec::new(),
            warnings: Default::default(),
        };
        loader.buffers = loader.load_buffers(gltf.blob)?;
        Ok(loader)
    }

    fn invalid(&self, reason: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            path: self.path.clone(),
            reason: reason.into(),
        }
    }

    fn warn(&self, message: String) {
        tracing::warn!("{}: {message}", self.path.display());
        self.warnings.borrow_mut().push(message);
    }

    fn load_buffers(&self, mut blob: Option<Vec<u8>>) -> Result<Vec<Vec<u8>>, SceneError> {
        let mut buffers = Vec::new();
        for buffer in self.document.buffers() {
            let index = buffer.index();
            let fail = |uri: &str, reason: String| SceneError::Buffer {
                path: self.path.clone(),
                index,
                uri: uri.to_string(),
                reason,
            };
            let data = match buffer.source() {
                gltf::buffer::Source::Bin => blob
                    .take()
                    .ok_or_else(|| fail("GLB BIN chunk", "the .glb has no binary chunk".into()))?,
                gltf::buffer::Source::Uri(uri) => self.read_uri(uri).map_err(|r| fail(uri, r))?,
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

    fn read_uri(&self, uri: &str) -> Result<Vec<u8>, String> {
        read_uri(self.base_dir, uri)
    }

    fn load(self) -> Result<SceneAsset, SceneError> {
        let images = self.load_images();
        let textures = self.load_textures(&images);
        let materials = self.load_materials(&textures);
        let meshes = self.load_meshes(&materials)?;
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
            lights,
            warnings: self.warnings.take(),
        };
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
            let bytes = match image.source() {
                gltf::image::Source::View { view, .. } => {
                    let buffer = &self.buffers[view.buffer().index()];
                    buffer
                        .get(view.offset()..view.offset() + view.length())
                        .map(<[u8]>::to_vec)
                        .ok_or_else(|| "its bufferView lies outside the buffer".to_string())
                }
                gltf::image::Source::Uri { uri, .. } => self.read_uri(uri),
            };
            let decoded = bytes.and_then(|b| {
                image::load_from_memory(&b)
                    .map(|img| img.to_rgba8())
                    .map_err(|e| format!("cannot decode: {e}"))
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
                        "image {} `{name}` skipped ({reason}); materials using it fall back to their factors",
                        image.index()
                    ));
                    out.push(None);
                }
            }
        }
        out
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
                let image = t.source().index();
                Texture {
                    image: if images[image].is_some() {
                        image as u32
                    } else {
                        u32::MAX
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
        let materials: Vec<_> = self.document.materials().collect();
        for m in materials {
            let name = m.name().unwrap_or("").to_string();
            let texture = |info: Option<(gltf::Texture, u32)>,
                           slot: &str,
                           warnings: &mut Vec<String>| {
                let (tex, tex_coord) = info?;
                if textures[tex.index()].image == u32::MAX {
                    return None;
                }
                if tex_coord > 1 {
                    warnings.push(format!(
                        "material `{name}`: {slot} texture uses TEXCOORD_{tex_coord}; only sets 0 and 1 are read, texture ignored"
                    ));
                    return None;
                }
                Some(TextureRef {
                    texture: tex.index() as u32,
                    tex_coord,
                })
            };
            let pbr = m.pbr_metallic_roughness();
            let mut warnings = Vec::new();
            let base_color_texture = texture(
                pbr.base_color_texture()
                    .map(|i| (i.texture(), i.tex_coord())),
                "baseColor",
                &mut warnings,
            );
            let metallic_roughness_texture = texture(
                pbr.metallic_roughness_texture()
                    .map(|i| (i.texture(), i.tex_coord())),
                "metallicRoughness",
                &mut warnings,
            );
            let normal = m.normal_texture();
            let normal_texture = texture(
                normal.as_ref().map(|n| (n.texture(), n.tex_coord())),
                "normal",
                &mut warnings,
            );
            let emissive_texture = texture(
                m.emissive_texture().map(|i| (i.texture(), i.tex_coord())),
                "emissive",
                &mut warnings,
            );
            for w in warnings {
                self.warn(w);
            }
            let strength = m.emissive_strength().unwrap_or(1.0);
            let material = Material {
                name,
                base_color: finite_or(Vec4::from(pbr.base_color_factor()), Vec4::ONE),
                base_color_texture,
                metallic: finite_or(pbr.metallic_factor(), 1.0).clamp(0.0, 1.0),
                roughness: finite_or(pbr.roughness_factor(), 1.0).clamp(0.0, 1.0),
                metallic_roughness_texture,
                normal_texture,
                normal_scale: normal.as_ref().map_or(1.0, |n| finite_or(n.scale(), 1.0)),
                emissive: finite_or(Vec3::from(m.emissive_factor()), Vec3::ZERO).max(Vec3::ZERO),
                emissive_strength: finite_or(strength, 1.0).max(0.0),
                emissive_texture,
                alpha_mode: match m.alpha_mode() {
                    gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
                    gltf::material::AlphaMode::Mask => {
                        AlphaMode::Mask(finite_or(m.alpha_cutoff().unwrap_or(0.5), 0.5))
                    }
                    gltf::material::AlphaMode::Blend => AlphaMode::Blend,
                },
                double_sided: m.double_sided(),
            };
            out.push(material);
        }
        out
    }

    fn load_meshes(&self, materials: &[Material]) -> Result<Vec<MeshData>, SceneError> {
        let meshes: Vec<_> = self.document.meshes().collect();
        let mut out = Vec::with_capacity(meshes.len());
        // Meshes that use glTF's default material get it appended once, after the file's materials.
        let default_material = materials.len() as u32;
        for mesh in meshes {
            let mut data = MeshData {
                name: mesh.name().unwrap_or("").to_string(),
                default_morph_weights: mesh.weights().map(<[f32]>::to_vec).unwrap_or_default(),
                ..Default::default()
            };
            let mut parts = Vec::new();
            for primitive in mesh.primitives() {
                let label = format!(
                    "mesh {} `{}` primitive {}",
                    mesh.index(),
                    data.name,
                    primitive.index()
                );
                match self.read_primitive(&primitive) {
                    Ok((part, note)) => {
                        if let Some(note) = note {
                            self.warn(format!("{label}: {note}"));
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
        Ok(out)
    }

    /// Reads one primitive; returns its data and an optional note about dropped triangles.
    fn read_primitive(
        &self,
        primitive: &gltf::Primitive,
    ) -> Result<(PrimitiveData, Option<String>), String> {
        let buffers = &self.buffers;
        let reader = primitive.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
        let position_accessor = primitive
            .get(&gltf::Semantic::Positions)
            .ok_or("it has no POSITION attribute")?;
        let count = position_accessor.count();
        let expect = |n: usize, what: &str| -> Result<(), String> {
            if n == count {
                Ok(())
            } else {
                Err(format!(
                    "{what} has {n} elements, POSITION has {count} (accessor lies outside its buffer or counts differ)"
                ))
            }
        };
        let positions: Vec<Vec3> = reader
            .read_positions()
            .ok_or("POSITION accessor lies outside its buffer or is not float VEC3")?
            .map(Vec3::from)
            .collect();
        expect(positions.len(), "POSITION")?;

        let mut part = PrimitiveData {
            positions,
            ..Default::default()
        };
        if let Some(n) = reader.read_normals() {
            let normals: Vec<Vec3> = n.map(|v| finite_or(Vec3::from(v), Vec3::ZERO)).collect();
            expect(normals.len(), "NORMAL")?;
            part.normals = Some(normals);
        }
        if let Some(t) = reader.read_tangents() {
            let tangents: Vec<Vec4> = t.map(|v| finite_or(Vec4::from(v), Vec4::ZERO)).collect();
            expect(tangents.len(), "TANGENT")?;
            part.tangents = Some(tangents);
        }
        for set in 0..2 {
            if let Some(uv) = reader.read_tex_coords(set) {
                let uv: Vec<Vec2> = uv
                    .into_f32()
                    .map(|v| finite_or(Vec2::from(v), Vec2::ZERO))
                    .collect();
                expect(uv.len(), "TEXCOORD")?;
                part.uv[set as usize] = Some(uv);
            }
        }
        if let Some(c) = reader.read_colors(0) {
            let colors: Vec<Vec4> = c
                .into_rgba_f32()
                .map(|v| finite_or(Vec4::from(v), Vec4::ONE))
                .collect();
            expect(colors.len(), "COLOR_0")?;
            part.colors = Some(colors);
        }
        let mut sets = 0;
        while let (Some(j), Some(w)) = (reader.read_joints(sets), reader.read_weights(sets)) {
            let joints: Vec<[u16; 4]> = j.into_u16().collect();
            let weights: Vec<[f32; 4]> = w
                .into_f32()
                .map(|w| w.map(|x| if x.is_finite() { x.max(0.0) } else { 0.0 }))
                .collect();
            expect(joints.len(), "JOINTS")?;
            expect(weights.len(), "WEIGHTS")?;
            part.joints.push(joints);
            part.weights.push(weights);
            sets += 1;
        }
        for (i, (p, n, t)) in reader.read_morph_targets().enumerate() {
            let positions: Vec<Vec3> = p
                .map(|p| p.map(|v| finite_or(Vec3::from(v), Vec3::ZERO)).collect())
                .unwrap_or_else(|| vec![Vec3::ZERO; count]);
            expect(positions.len(), &format!("morph target {i} POSITION"))?;
            let normals: Option<Vec<Vec3>> =
                n.map(|n| n.map(|v| finite_or(Vec3::from(v), Vec3::ZERO)).collect());
            let tangents: Option<Vec<Vec3>> =
                t.map(|t| t.map(|v| finite_or(Vec3::from(v), Vec3::ZERO)).collect());
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

        let indices: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None if primitive.indices().is_some() => {
                return Err("its index accessor lies outside its buffer".into());
            }
            None => (0..count as u32).collect(),
        };
        if let Some(accessor) = primitive.indices()
            && indices.len() != accessor.count()
        {
            return Err("its index accessor lies outside its buffer".into());
        }
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= count) {
            return Err(format!(
                "index {bad} is out of range: the primitive has {count} vertices"
            ));
        }
        let triangles = assemble_triangles(primitive.mode(), &indices)?;

        let (mut non_finite, mut degenerate) = (0usize, 0usize);
        part.triangles = triangles
            .into_iter()
            .filter(|t| {
                let [a, b, c] = t.map(|i| part.positions[i as usize]);
                if !(a.is_finite() && b.is_finite() && c.is_finite()) {
                    non_finite += 1;
                    return false;
                }
                // Zero-area triangles can never be hit, and their normals are undefined: drop them.
                if (b - a).cross(c - a).length_squared() <= 0.0 {
                    degenerate += 1;
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
        let mut notes = Vec::new();
        if non_finite > 0 {
            notes.push(format!(
                "{non_finite} triangles with NaN or infinite vertex positions dropped"
            ));
        }
        if degenerate > 0 {
            notes.push(format!("{degenerate} zero-area triangles dropped"));
        }
        if part.triangles.is_empty() {
            return Err(if notes.is_empty() {
                "it has no triangles".into()
            } else {
                notes.join(", ")
            });
        }
        Ok((part, (!notes.is_empty()).then(|| notes.join(", "))))
    }

    fn load_cameras(&self) -> Vec<PerspectiveCamera> {
        let cameras: Vec<_> = self.document.cameras().collect();
        let mut out = Vec::new();
        for c in cameras {
            match c.projection() {
                gltf::camera::Projection::Perspective(p) => out.push(PerspectiveCamera {
                    yfov: finite_or(p.yfov(), 0.8).clamp(1e-3, 3.1),
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
        let roots: Vec<usize> = match self
            .document
            .default_scene()
            .or_else(|| self.document.scenes().next())
        {
            Some(scene) => scene.nodes().map(|n| n.index()).collect(),
            None => (0..nodes.len())
                .filter(|&i| nodes[i].parent.is_none())
                .collect(),
        };
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
        Ok((nodes, roots))
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
                match crate::animation::validate_channel(&channel) {
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

/// The bytes behind a glTF URI: a base64 data URI, or a (percent-encoded) path relative to `base_dir`.
pub(super) fn read_uri(base_dir: &Path, uri: &str) -> Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, payload) = rest
            .split_once(";base64,")
            .ok_or("data URI is not base64")?;
        return base64::engine::general_purpose::STANDARD
            .decode(payload)
            .map_err(|e| format!("bad base64 data URI: {e}"));
    }
    let file = base_dir.join(percent_decode(uri));
    std::fs::read(&file).map_err(|e| format!("cannot read {}: {e}", file.display()))
}

/// glTF URIs are percent-encoded (`%20` for a space).
pub(crate) fn percent_decode(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%'
            && i + 2 < bytes.len()
            && let Ok(v) = u8::from_str_radix(
                std::str::from_utf8(&bytes[i + 1..i + 3]).unwrap_or("zz"),
                16,
            )
        {
            out.push(v);
            i += 3;
            continue;
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn describe_gltf_error(e: &gltf::Error) -> String {
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
