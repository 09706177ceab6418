//! Scenes on the CPU: the asset data a glTF file becomes (meshes, materials, images, cameras, node tree),
//! and the ECS side: one entity per node with its transform, mesh instance and camera.

mod accessor;
pub mod compose;
mod draco;
mod extensions;
mod gltf_loader;
pub mod gltf_writer;
pub mod inputs;
mod instancing;
pub mod lights;
pub mod material_extensions;
mod materials;
mod meshopt;
pub mod plausible;
pub mod procedural;
mod spawn;
mod tangents;
mod texture_basisu;
mod texture_transform;
mod validate;
pub mod variants;

pub use compose::{compose, unshare_deformable_meshes};
pub use gltf_loader::{LoadOptions, load_gltf, load_gltf_slice};
pub use gltf_writer::{SaveError, save_edited, save_with_materials};
pub(crate) use inputs::percent_decode;
pub use lights::{LightSource, PunctualKind, PunctualLight};
pub use material_extensions::MaterialExtensions;
pub use materials::Materials;
pub use spawn::{
    CameraComponent, GlobalTransform, MeshInstance, MorphWeights, SceneNode, SceneNodes,
    ScenePlugin, SceneRoot, SkinnedMesh, Transform, propagate_transforms, spawn_scene,
};
pub use texture_transform::TextureTransform;
pub use variants::ActiveVariant;

use bevy_ecs::prelude::Resource;
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use std::path::PathBuf;
use std::sync::Arc;

/// Errors that stop a scene from loading. Each names the file; problems that only affect one primitive or
/// texture become warnings in [`SceneAsset::warnings`] instead, and the rest of the scene still renders.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{path}: cannot read the file: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: not a valid glTF 2.0 file: {reason}")]
    Invalid { path: PathBuf, reason: String },
    #[error("{path}: buffer {index} ({uri}) cannot be loaded: {reason}")]
    Buffer {
        path: PathBuf,
        index: usize,
        uri: String,
        reason: String,
    },
    #[error("{path}: requires the glTF extension `{extension}`, which raykin does not support")]
    UnsupportedExtension { path: PathBuf, extension: String },
    #[error("{path}: the scene has no renderable triangles ({reason})")]
    Empty { path: PathBuf, reason: String },
    /// The scene to display (`--scene N`) does not exist or is empty.
    #[error("{path}: {reason}")]
    Scene { path: PathBuf, reason: String },
    /// A decoder panicked: a bug in raykin or a library it calls, never the user's fault.
    #[error(
        "{path}: internal error while reading the file (a bug; please report it with this file): {message}"
    )]
    Internal { path: PathBuf, message: String },
    #[error("{path}: no material variant is called `{name}`: {known}")]
    UnknownVariant {
        path: PathBuf,
        name: String,
        known: String,
    },
}

/// How a material treats base-colour alpha (glTF `alphaMode`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    Opaque,
    /// Cut-out: a hit whose alpha is below the cutoff is ignored by traversal.
    Mask(f32),
    /// Treated as stochastic coverage: a path passes through with probability 1 - alpha.
    Blend,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    /// Index into [`SceneAsset::textures`].
    pub texture: u32,
    /// TEXCOORD_n set (0 or 1), after KHR_texture_transform's override.
    pub tex_coord: u32,
    /// KHR_texture_transform of this slot (identity without it).
    pub transform: TextureTransform,
}

impl TextureRef {
    /// A slot without a texture transform.
    pub fn new(texture: u32, tex_coord: u32) -> Self {
        Self {
            texture,
            tex_coord,
            transform: TextureTransform::IDENTITY,
        }
    }
}

/// The glTF metallic-roughness material, with the extensions raykin renders.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub base_color: Vec4,
    pub base_color_texture: Option<TextureRef>,
    pub metallic: f32,
    pub roughness: f32,
    /// Blue = metallic, green = roughness, both multiplied by the factors.
    pub metallic_roughness_texture: Option<TextureRef>,
    pub normal_texture: Option<TextureRef>,
    pub normal_scale: f32,
    /// glTF `emissiveFactor` (linear).
    pub emissive: Vec3,
    /// KHR_materials_emissive_strength (1 without the extension); emitted radiance = emissive x strength.
    pub emissive_strength: f32,
    pub emissive_texture: Option<TextureRef>,
    pub alpha_mode: AlphaMode,
    pub double_sided: bool,
    /// The KHR material extensions beyond metallic-roughness (parsed; not shaded yet).
    pub extensions: MaterialExtensions,
}

impl Material {
    /// Emitted radiance (before the emissive texture): factor x strength.
    pub fn emitted_radiance(&self) -> Vec3 {
        // An unlit material shows its base colour instead (KHR_materials_unlit): it is no light.
        if self.extensions.unlit {
            return Vec3::ZERO;
        }
        self.emissive * self.emissive_strength
    }

    /// Every texture slot in use, core and extensions.
    pub fn texture_slots(&self) -> Vec<TextureRef> {
        let mut m = self.clone();
        m.texture_slots_mut()
            .into_iter()
            .filter_map(|t| *t)
            .collect()
    }

    /// Every texture slot, core and extensions, for remapping texture indices.
    pub fn texture_slots_mut(&mut self) -> Vec<&mut Option<TextureRef>> {
        let mut slots = vec![
            &mut self.base_color_texture,
            &mut self.metallic_roughness_texture,
            &mut self.normal_texture,
            &mut self.emissive_texture,
        ];
        slots.extend(self.extensions.texture_slots_mut());
        slots
    }
}

impl Default for Material {
    /// glTF's default material: white, fully metallic, fully rough.
    fn default() -> Self {
        Self {
            name: "default".into(),
            base_color: Vec4::ONE,
            base_color_texture: None,
            metallic: 1.0,
            roughness: 1.0,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            emissive: Vec3::ZERO,
            emissive_strength: 1.0,
            emissive_texture: None,
            alpha_mode: AlphaMode::Opaque,
            double_sided: false,
            extensions: MaterialExtensions::default(),
        }
    }
}

/// Decoded RGBA8 pixels of one glTF image.
#[derive(Clone, Debug)]
pub struct Image {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub rgba8: Vec<u8>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Wrap {
    #[default]
    Repeat,
    MirroredRepeat,
    ClampToEdge,
}

/// A glTF texture: an image and how it is sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Texture {
    /// Index into [`SceneAsset::images`].
    pub image: u32,
    pub wrap_s: Wrap,
    pub wrap_t: Wrap,
    pub nearest: bool,
}

/// Where one glTF primitive's vertices and triangles sit inside its [`MeshData`].
#[derive(Clone, Debug, PartialEq)]
pub struct PrimitiveRange {
    pub vertex_offset: u32,
    pub vertex_count: u32,
    pub material: u32,
}

/// Skinning inputs of a mesh's vertices (4 influences per vertex set).
#[derive(Clone, Debug, Default)]
pub struct SkinWeights {
    /// One entry per vertex per influence set (JOINTS_0/WEIGHTS_0, then JOINTS_1/WEIGHTS_1 ...).
    pub joints: Vec<[u16; 4]>,
    pub weights: Vec<[f32; 4]>,
    /// Influence sets per vertex (1 for JOINTS_0 only).
    pub sets: u32,
}

/// Position/normal/tangent offsets of one morph target, per vertex of the mesh (zero where a primitive lacks it).
#[derive(Clone, Debug, Default)]
pub struct MorphTarget {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub tangents: Option<Vec<Vec3>>,
}

/// A triangle mesh: all primitives of one glTF mesh merged, each keeping its vertices in accessor order.
/// Attributes no primitive has are `None`, so memory holds only what the file provides.
#[derive(Clone, Debug, Default)]
pub struct MeshData {
    pub name: String,
    pub positions: Vec<Vec3>,
    /// Absent: the renderer shades with the geometric normal (the glTF rule: flat normals).
    pub normals: Option<Vec<Vec3>>,
    /// xyz tangent, w = handedness.
    pub tangents: Option<Vec<Vec4>>,
    pub uv0: Option<Vec<Vec2>>,
    pub uv1: Option<Vec<Vec2>>,
    /// Linear RGBA vertex colour (COLOR_0), multiplied into base colour.
    pub colors: Option<Vec<Vec4>>,
    /// Vertex indices (into this mesh's vertices) of each triangle, and the triangle's material.
    pub triangles: Vec<[u32; 3]>,
    pub triangle_materials: Vec<u32>,
    pub primitives: Vec<PrimitiveRange>,
    pub skin_weights: Option<SkinWeights>,
    pub morph_targets: Vec<MorphTarget>,
    pub default_morph_weights: Vec<f32>,
    /// KHR_materials_variants mappings, one per primitive (empty when the mesh has none).
    pub primitive_variants: Vec<variants::PrimitiveVariants>,
}

impl MeshData {
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.positions.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        )
    }

    /// True when the mesh deforms (skin or morph targets): its BVH is refit instead of built once.
    pub fn is_deformable(&self) -> bool {
        self.skin_weights.is_some() || !self.morph_targets.is_empty()
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PerspectiveCamera {
    /// Vertical field of view in radians.
    pub yfov: f32,
    pub aspect_ratio: Option<f32>,
    pub znear: f32,
}

/// A glTF skin: the joints' nodes and their inverse bind matrices.
#[derive(Clone, Debug)]
pub struct SkinData {
    pub name: String,
    pub joints: Vec<usize>,
    pub inverse_bind_matrices: Vec<Mat4>,
    pub skeleton: Option<usize>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeTransform {
    pub translation: Vec3,
    pub rotation: Quat,
    pub scale: Vec3,
}

impl Default for NodeTransform {
    fn default() -> Self {
        Self {
            translation: Vec3::ZERO,
            rotation: Quat::IDENTITY,
            scale: Vec3::ONE,
        }
    }
}

impl NodeTransform {
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }
}

#[derive(Clone, Debug, Default)]
pub struct NodeData {
    pub name: String,
    pub parent: Option<usize>,
    pub children: Vec<usize>,
    pub transform: NodeTransform,
    pub mesh: Option<usize>,
    pub camera: Option<usize>,
    pub skin: Option<usize>,
    /// KHR_lights_punctual light index ([`SceneAsset::lights`]).
    pub light: Option<usize>,
    /// node.weights: overrides the mesh's default morph weights.
    pub morph_weights: Option<Vec<f32>>,
}

/// Keyframe interpolation of an animation sampler.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    Step,
    Linear,
    CubicSpline,
}

#[derive(Clone, Debug)]
pub enum ChannelValues {
    Translation(Vec<Vec3>),
    Rotation(Vec<Quat>),
    Scale(Vec<Vec3>),
    /// Morph weights: `count` values per keyframe (x3 for cubic splines).
    Weights {
        values: Vec<f32>,
        count: usize,
    },
}

#[derive(Clone, Debug)]
pub struct AnimationChannel {
    pub node: usize,
    pub interpolation: Interpolation,
    pub times: Vec<f32>,
    /// For CUBICSPLINE: in-tangent, value, out-tangent per keyframe.
    pub values: ChannelValues,
}

impl AnimationChannel {
    /// Rejects channels that would sample to NaN or index out of range: empty or non-finite times,
    /// times not strictly increasing, value counts that do not match the keyframes, non-finite values.
    pub fn validate(&self) -> Result<(), String> {
        if self.times.is_empty() {
            return Err("no keyframes".into());
        }
        if self.times.iter().any(|t| !t.is_finite()) {
            return Err("non-finite keyframe time".into());
        }
        if self.times.windows(2).any(|w| w[1] <= w[0]) {
            return Err("keyframe times are not strictly increasing".into());
        }
        let per_key = if self.interpolation == Interpolation::CubicSpline {
            3
        } else {
            1
        };
        let keys = self.times.len() * per_key;
        let (len, finite) = match &self.values {
            ChannelValues::Translation(v) | ChannelValues::Scale(v) => {
                (v.len(), v.iter().all(|x| x.is_finite()))
            }
            ChannelValues::Rotation(v) => (v.len(), v.iter().all(|x| x.is_finite())),
            ChannelValues::Weights { values, count } => {
                if *count == 0 || values.len() != keys * count {
                    return Err(format!(
                        "{} weight values do not fill {} keyframes",
                        values.len(),
                        keys
                    ));
                }
                (keys, values.iter().all(|x| x.is_finite()))
            }
        };
        if len != keys {
            return Err(format!(
                "{len} values for {} keyframes (sampler/accessor count mismatch)",
                self.times.len()
            ));
        }
        if !finite {
            return Err("NaN or infinite keyframe value".into());
        }
        Ok(())
    }
}

#[derive(Clone, Debug)]
pub struct AnimationClip {
    pub name: String,
    pub channels: Vec<AnimationChannel>,
    /// The last keyframe time over all channels.
    pub duration: f32,
}

/// Everything a scene file holds, immutable once loaded (animation and editing write ECS components).
#[derive(Clone, Debug, Default)]
pub struct SceneAsset {
    /// The file it came from (or a name for built-in scenes), for messages.
    pub source: String,
    pub meshes: Vec<MeshData>,
    pub materials: Vec<Material>,
    pub images: Vec<Image>,
    pub textures: Vec<Texture>,
    pub cameras: Vec<PerspectiveCamera>,
    pub skins: Vec<SkinData>,
    pub animations: Vec<AnimationClip>,
    pub nodes: Vec<NodeData>,
    /// Root nodes of the displayed glTF scene.
    pub roots: Vec<usize>,
    /// KHR_materials_variants names, in file order.
    pub variants: Vec<String>,
    /// The selected variant (index into `variants`), `None` for the file's own materials.
    pub active_variant: Option<usize>,
    /// KHR_lights_punctual lights, referenced by [`NodeData::light`].
    pub lights: Vec<PunctualLight>,
    /// Problems that were worked around (skipped primitives, missing textures...), one line each.
    pub warnings: Vec<String>,
    /// The files the scene was read from (canonical paths): the .gltf/.glb and every buffer and image file
    /// its URIs name. Outputs must never overwrite one of them.
    pub files: Vec<PathBuf>,
}

impl SceneAsset {
    /// Node world matrices in the file's rest pose.
    pub fn rest_world_matrices(&self) -> Vec<Mat4> {
        let mut world = vec![Mat4::IDENTITY; self.nodes.len()];
        let mut stack: Vec<(usize, Mat4)> =
            self.roots.iter().map(|&r| (r, Mat4::IDENTITY)).collect();
        while let Some((node, parent)) = stack.pop() {
            let m = parent * self.nodes[node].transform.matrix();
            world[node] = m;
            for &c in &self.nodes[node].children {
                stack.push((c, m));
            }
        }
        world
    }

    /// By node index: whether the node belongs to the displayed scene (reachable from [`Self::roots`]).
    /// Nodes of other glTF scenes are loaded (animations and skins may name them) but never drawn.
    pub fn displayed_nodes(&self) -> Vec<bool> {
        let mut shown = vec![false; self.nodes.len()];
        let mut stack = self.roots.clone();
        while let Some(n) = stack.pop() {
            if n < shown.len() && !shown[n] {
                shown[n] = true;
                stack.extend(&self.nodes[n].children);
            }
        }
        shown
    }

    /// By node index: whether the node draws a mesh that never moves or changes shape: displayed, its mesh
    /// neither skinned nor morphed, and no animation channel moving it or an ancestor. (The editor can still
    /// move one; the renderer notices that.)
    pub fn still_nodes(&self) -> Vec<bool> {
        let mut moved = vec![false; self.nodes.len()];
        for channel in self.animations.iter().flat_map(|clip| &clip.channels) {
            if !matches!(channel.values, ChannelValues::Weights { .. })
                && let Some(m) = moved.get_mut(channel.node)
            {
                *m = true;
            }
        }
        // Roots first: a moved parent moves its subtree.
        let mut stack: Vec<(usize, bool)> = self.roots.iter().map(|&r| (r, false)).collect();
        let mut still = vec![false; self.nodes.len()];
        let mut seen = vec![false; self.nodes.len()];
        while let Some((n, parent_moves)) = stack.pop() {
            if n >= self.nodes.len() || std::mem::replace(&mut seen[n], true) {
                continue;
            }
            let moves = parent_moves || moved[n];
            let node = &self.nodes[n];
            still[n] = !moves
                && node
                    .mesh
                    .and_then(|m| self.meshes.get(m))
                    .is_some_and(|m| !m.is_deformable());
            stack.extend(node.children.iter().map(|&c| (c, moves)));
        }
        still
    }

    /// World-space bounds of every displayed mesh instance in the rest pose.
    pub fn rest_bounds(&self) -> Option<(Vec3, Vec3)> {
        let world = self.rest_world_matrices();
        let shown = self.displayed_nodes();
        let mut lo = Vec3::splat(f32::MAX);
        let mut hi = Vec3::splat(f32::MIN);
        let mut any = false;
        for (i, node) in self.nodes.iter().enumerate() {
            let Some(mesh) = node.mesh.filter(|_| shown[i]) else {
                continue;
            };
            for p in &self.meshes[mesh].positions {
                let w = world[i].transform_point3(*p);
                lo = lo.min(w);
                hi = hi.max(w);
                any = true;
            }
        }
        any.then_some((lo, hi))
    }

    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.triangles.len()).sum()
    }
}

/// The loaded scene, shared by the systems that read asset data.
#[derive(Resource, Clone)]
pub struct SceneAssets(pub Arc<SceneAsset>);

#[cfg(test)]
mod tests {
    use super::*;

    fn triangle_mesh(morphed: bool) -> MeshData {
        MeshData {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            triangles: vec![[0, 1, 2]],
            morph_targets: if morphed {
                vec![Default::default()]
            } else {
                Vec::new()
            },
            ..Default::default()
        }
    }

    /// Roots 0 -> 1 -> {2, 3 (no mesh)} and 4 -> 5 (a morphed mesh); node 6 is in no displayed scene. A
    /// translation channel on node 1 moves it and its subtree; a weights channel on node 4 moves nothing.
    #[test]
    fn still_nodes_are_the_displayed_rigid_meshes_no_channel_moves() {
        let node = |mesh: Option<usize>, parent: Option<usize>, children: Vec<usize>| NodeData {
            mesh,
            parent,
            children,
            ..Default::default()
        };
        let scene = SceneAsset {
            meshes: vec![triangle_mesh(false), triangle_mesh(true)],
            nodes: vec![
                node(Some(0), None, vec![1]),
                node(Some(0), Some(0), vec![2, 3]),
                node(Some(0), Some(1), vec![]),
                node(None, Some(1), vec![]),
                node(Some(0), None, vec![5]),
                node(Some(1), Some(4), vec![]),
                node(Some(0), None, vec![]),
            ],
            roots: vec![0, 4],
            animations: vec![AnimationClip {
                name: "move".into(),
                channels: vec![
                    AnimationChannel {
                        node: 1,
                        interpolation: Interpolation::Linear,
                        times: vec![0.0, 1.0],
                        values: ChannelValues::Translation(vec![Vec3::ZERO, Vec3::X]),
                    },
                    AnimationChannel {
                        node: 4,
                        interpolation: Interpolation::Linear,
                        times: vec![0.0],
                        values: ChannelValues::Weights {
                            values: vec![0.5],
                            count: 1,
                        },
                    },
                ],
                duration: 1.0,
            }],
            ..Default::default()
        };
        assert_eq!(
            scene.still_nodes(),
            vec![true, false, false, false, true, false, false]
        );
    }
}
