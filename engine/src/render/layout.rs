//! The one source of everything Rust and WGSL share: the scene's GPU structs (byte for byte the structs of
//! `shaders/scene/types.wgsl` and `shaders/view.wgsl`; the naga test checks sizes and field offsets) and every
//! shared constant, emitted as the WGSL library's generated `constants` module ([`WGSL_CONSTANTS`]).

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3, Vec4};

/// "No texture / attribute absent" marker.
pub const NONE: u32 = u32::MAX;
/// Encoded normal/tangent that the shader treats as missing (never produced by `pack2x16snorm`).
pub const INVALID_OCT: u32 = 0x8000_8000;

pub const MATERIAL_DOUBLE_SIDED: u32 = 1;
pub const MATERIAL_ALPHA_MASK: u32 = 2;
pub const MATERIAL_ALPHA_BLEND: u32 = 4;
/// KHR_materials_unlit: the surface shows its base colour as radiance and scatters nothing (shaded from the
/// extension-factor kernels up).
pub const MATERIAL_UNLIT: u32 = 8;

/// `MATERIAL_LOBES` (the trace kernels' pipeline constant, `render::material_lobes`): bits 0-1 the extension
/// level (0 core, 1 factors, [`LOBES_TEXTURED`] factors and textures), [`LOBES_LAYERS`] the sheen and clearcoat
/// layers.
pub const LOBES_LEVEL: u32 = 3;
pub const LOBES_TEXTURED: u32 = 2;
pub const LOBES_LAYERS: u32 = 4;

/// `CORE_TEXTURES` (the trace kernels' pipeline constant, `render::material_lobes::MaterialNeeds`): the core
/// texture slots some material of the scene uses, one bit each.
pub const CORE_TEXTURE_BASE_COLOR: u32 = 1;
pub const CORE_TEXTURE_METALLIC_ROUGHNESS: u32 = 2;
pub const CORE_TEXTURE_NORMAL: u32 = 4;
pub const CORE_TEXTURE_EMISSIVE: u32 = 8;
pub const CORE_TEXTURES_ALL: u32 = 15;

pub const TEXTURE_NEAREST: u32 = 1 << 4;
/// The texture-info entry carries a KHR_texture_transform (its `uv_u`/`uv_v` rows apply to the UVs).
pub const TEXTURE_TRANSFORMED: u32 = 1 << 5;

/// Set in `GpuMesh::blas_root` when the root indexes the compressed wide node buffer.
pub const WIDE_BLAS: u32 = 1 << 31;

/// `BLAS_LAYOUTS` (the trace kernels' pipeline constant, `render::material_lobes::KernelNeeds`): the BLAS layouts
/// the top level's leaves use, one bit each.
pub const BLAS_LAYOUT_WIDE: u32 = 1;
pub const BLAS_LAYOUT_BINARY: u32 = 2;
pub const BLAS_LAYOUTS_ALL: u32 = 3;

/// CPU adapters read the scene's buffers from textures (`render::scene_texels`): rows of `1 << SCENE_TEXEL_ROW_LOG2`
/// 16-byte texels (64 KiB), so a 128 MiB buffer needs 2048 rows.
pub const SCENE_TEXEL_ROW_LOG2: u32 = 12;

/// Words per vertex position in the vertex pool: x, y, z and a zero, each mesh's positions starting at a
/// multiple of four words, so that CPU adapters read a position as one 16-byte texel (three words could straddle
/// two: 5-7% of the Cornell box's render on lavapipe, docs/BENCHMARKS.md).
pub const POSITION_WORDS: u32 = 4;

/// Words per texel of an environment map in `environment_map`: r, g, b and a zero, one 16-byte texel on CPU
/// adapters (docs/BENCHMARKS.md, "Vertex positions and environment texels padded to 16 bytes").
pub const ENVIRONMENT_TEXEL_WORDS: u32 = 4;

/// An object-to-world placement of a mesh (rows of 3x4 matrices).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuInstance {
    pub world_from_object: [[f32; 4]; 3],
    pub object_from_world: [[f32; 4]; 3],
    pub mesh: u32,
    /// This instance's emissive triangles in the light list: `first_light .. first_light + light_count`,
    /// sorted by triangle slot (how a BSDF-sampled hit finds its light for MIS).
    pub first_light: u32,
    pub light_count: u32,
    /// `NONE`, except on the merged static tree's pseudo-instance: where its hits' (member instance, member
    /// triangle slot) pairs sit in the triangle buffer (`gpu_scene::static_merge::StaticMerge::origins`).
    pub merged_origins: u32,
}

impl GpuInstance {
    pub fn new(world: Mat4, mesh: u32) -> Self {
        let rows = |m: Mat4| {
            [
                m.row(0).to_array(),
                m.row(1).to_array(),
                m.row(2).to_array(),
            ]
        };
        Self {
            world_from_object: rows(world),
            object_from_world: rows(world.inverse()),
            mesh,
            first_light: 0,
            light_count: 0,
            merged_origins: NONE,
        }
    }
}

/// Where a mesh's data sits in the shared buffers. Attribute offsets are in 32-bit words of the vertex pool.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuMesh {
    pub blas_root: u32,
    pub triangle_offset: u32,
    pub position_offset: u32,
    pub normal_offset: u32,
    pub tangent_offset: u32,
    pub uv0_offset: u32,
    pub uv1_offset: u32,
    pub color_offset: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuMaterial {
    pub base_color: [f32; 4],
    pub emissive: [f32; 3],
    pub metallic: f32,
    pub roughness: f32,
    pub alpha_cutoff: f32,
    pub normal_scale: f32,
    pub flags: u32,
    /// Texture index in bits 0..24, TEXCOORD set in bit 24; [`NONE`] when absent.
    pub base_color_texture: u32,
    pub metallic_roughness_texture: u32,
    pub normal_texture: u32,
    pub emissive_texture: u32,
    /// The dielectric Fresnel's f0 before the texture: `((ior - 1) / (ior + 1))^2` times the specular colour
    /// (KHR_materials_ior, KHR_materials_specular); the shader multiplies the colour texture in and clamps to 1.
    pub specular_f0: [f32; 3],
    /// KHR_materials_specular's factor: the dielectric layer's weight (its f90).
    pub specular_weight: f32,
    /// Absorption coefficient per world unit of the medium behind the surface (KHR_materials_volume's
    /// `-ln(attenuationColor) / attenuationDistance`); 0 without a volume.
    pub attenuation: [f32; 3],
    /// The index of refraction that bends transmitted rays; 1 for thin-walled transmission (no volume, or
    /// thickness 0), where transmitted rays go on without bending.
    pub refraction_ior: f32,
    /// KHR_materials_transmission's factor.
    pub transmission: f32,
    pub transmission_texture: u32,
    pub specular_texture: u32,
    pub specular_color_texture: u32,
    /// KHR_materials_clearcoat: factor and roughness (textures: red and green channel).
    pub clearcoat: f32,
    pub clearcoat_roughness: f32,
    pub clearcoat_texture: u32,
    pub clearcoat_roughness_texture: u32,
    /// KHR_materials_sheen: colour (texture: sRGB RGB) and roughness (texture: alpha); colour 0 = no sheen.
    pub sheen_color: [f32; 3],
    pub sheen_roughness: f32,
    pub clearcoat_normal_texture: u32,
    pub clearcoat_normal_scale: f32,
    pub sheen_color_texture: u32,
    pub sheen_roughness_texture: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuTexture {
    /// First texel in the texel buffer.
    pub offset: u32,
    pub width: u32,
    pub height: u32,
    /// wrap_s in bits 0..2, wrap_t in bits 2..4 (0 repeat, 1 mirrored, 2 clamp), [`TEXTURE_NEAREST`],
    /// [`TEXTURE_TRANSFORMED`].
    pub flags: u32,
    /// With [`TEXTURE_TRANSFORMED`]: `u' = dot(uv_u.xyz, (u, v, 1))`, `v' = dot(uv_v.xyz, (u, v, 1))` (the
    /// spec's `T * R * S`); `uv_u.w`, `uv_v.w` = cos and sin of the rotation, which turns tangent-space normals.
    pub uv_u: [f32; 4],
    pub uv_v: [f32; 4],
}

pub const LIGHT_TRIANGLE: u32 = 0;
pub const LIGHT_POINT: u32 = 1;
pub const LIGHT_SPOT: u32 = 2;
pub const LIGHT_DIRECTIONAL: u32 = 3;
pub const LIGHT_ENVIRONMENT: u32 = 4;
pub const LIGHT_SUN: u32 = 5;
/// `GpuLight::flags` of an environment map: points inside a cell follow the bilinear interpolation of its
/// corners' luminance (set where some cell's corners differ enough for it to pay; see
/// `environment::EnvironmentDistribution::bilinear`).
pub const LIGHT_ENVIRONMENT_BILINEAR: u32 = 1;
/// The same for next-event estimation's MIS-compensated distribution.
pub const LIGHT_ENVIRONMENT_COMPENSATED_BILINEAR: u32 = 2;
/// Next-event estimation samples the map MIS-compensated (its second distribution follows the first in
/// `environment_map`; see `environment::NextEventSampling`); else it samples the full distribution.
pub const LIGHT_ENVIRONMENT_COMPENSATED: u32 = 4;

/// One light of any kind (`shaders/scene/types.wgsl` `Light`; `shaders/lights/` reads it). What each field
/// holds per kind:
///
/// | kind | index_a, index_b | position, range | direction, cos_outer | radiance, cos_inner |
/// |---|---|---|---|---|
/// | triangle | instance, triangle slot | - | - | - (the material's emission) |
/// | point | - | world position, range (0: none) | - | intensity (W/sr) |
/// | spot | - | world position, range | axis it shines along, cos outer cone | intensity, cos inner cone |
/// | directional | - | - | direction it travels | irradiance (W/m^2) |
/// | environment | map width, height | (cos, sin) of the turn about +Y, compensation offset | - | strength |
/// (an environment's `flags`: [`LIGHT_ENVIRONMENT_BILINEAR`], [`LIGHT_ENVIRONMENT_COMPENSATED`],
/// [`LIGHT_ENVIRONMENT_COMPENSATED_BILINEAR`])
/// | sun | - | -, 1 - cos(angular radius) | towards the sun | radiance |
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuLight {
    pub kind: u32,
    pub index_a: u32,
    pub index_b: u32,
    pub flags: u32,
    pub position: [f32; 3],
    pub range: f32,
    pub direction: [f32; 3],
    pub cos_outer: f32,
    pub radiance: [f32; 3],
    pub cos_inner: f32,
}

/// A node of the light sampler's tree (`shaders/scene/types.wgsl` `LightTreeNode`; built by
/// `render::gpu_scene::light_tree`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuLightTreeNode {
    pub lo: [f32; 3],
    pub phi: f32,
    pub hi: [f32; 3],
    pub cos_theta_o: f32,
    pub w: [f32; 3],
    pub cos_theta_e: f32,
    /// Interior node: index of the second child (the first follows the node); leaf: the light's index.
    pub child_or_light: u32,
    /// [`LIGHT_TREE_LEAF`], [`LIGHT_TREE_TWO_SIDED`].
    pub flags: u32,
    pub _pad: [u32; 2],
}

pub const LIGHT_TREE_LEAF: u32 = 1;
pub const LIGHT_TREE_TWO_SIDED: u32 = 2;

/// Workgroup size of the skin + morph pass (`deform.wgsl`): vertices per workgroup.
pub const DEFORM_GROUP: u32 = 64;
/// Workgroup size of the refit pass (`refit.wgsl`): one workgroup sweeps one mesh.
pub const REFIT_GROUP: u32 = 256;

/// The wavefront's counters at the head of its queues' buffer (`Queues::control` in
/// `passes/wavefront/wavefront.wgsl`), and the one of them the pass copies to the view's ray counter.
pub const WAVE_CONTROL_WORDS: u32 = 16;
pub const WAVE_CONTROL_RAYS: u32 = 7;
const _: () = assert!(WAVE_CONTROL_RAYS < WAVE_CONTROL_WORDS);

/// The wavefront's ray sort (`passes/wavefront/wavefront.wgsl`, `WAVE_SORT`): its keys, the keys one
/// `sort_prefix` workgroup sums and that kernel's workgroups, and the words of its bins at the head of the
/// queues' buffer (each key's count and first slot, each block's total). `sort_scatter` reads one block total
/// per invocation of its 128.
pub const SORT_BINS: u32 = 32768;
pub const SORT_BLOCK: u32 = 256;
pub const SORT_BLOCKS: u32 = SORT_BINS / SORT_BLOCK;
pub const SORT_WORDS: u32 = 2 * SORT_BINS + SORT_BLOCKS;
const _: () = assert!(SORT_BLOCKS == 128);

/// Every constant the WGSL library shares with Rust, by its WGSL name; `render::shaders` writes them as the
/// `constants` module, so a kernel can never disagree with the code that fills its buffers.
pub const WGSL_CONSTANTS: &[(&str, u32)] = &[
    ("NONE", NONE),
    ("INVALID_OCT", INVALID_OCT),
    ("MATERIAL_DOUBLE_SIDED", MATERIAL_DOUBLE_SIDED),
    ("MATERIAL_ALPHA_MASK", MATERIAL_ALPHA_MASK),
    ("MATERIAL_ALPHA_BLEND", MATERIAL_ALPHA_BLEND),
    ("MATERIAL_UNLIT", MATERIAL_UNLIT),
    ("LOBES_LEVEL", LOBES_LEVEL),
    ("LOBES_TEXTURED", LOBES_TEXTURED),
    ("LOBES_LAYERS", LOBES_LAYERS),
    ("CORE_TEXTURE_BASE_COLOR", CORE_TEXTURE_BASE_COLOR),
    (
        "CORE_TEXTURE_METALLIC_ROUGHNESS",
        CORE_TEXTURE_METALLIC_ROUGHNESS,
    ),
    ("CORE_TEXTURE_NORMAL", CORE_TEXTURE_NORMAL),
    ("CORE_TEXTURE_EMISSIVE", CORE_TEXTURE_EMISSIVE),
    ("CORE_TEXTURES_ALL", CORE_TEXTURES_ALL),
    ("TEXTURE_NEAREST", TEXTURE_NEAREST),
    ("TEXTURE_TRANSFORMED", TEXTURE_TRANSFORMED),
    ("WIDE_BLAS", WIDE_BLAS),
    ("BLAS_LAYOUT_WIDE", BLAS_LAYOUT_WIDE),
    ("BLAS_LAYOUT_BINARY", BLAS_LAYOUT_BINARY),
    ("BLAS_LAYOUTS_ALL", BLAS_LAYOUTS_ALL),
    ("SCENE_TEXEL_ROW_LOG2", SCENE_TEXEL_ROW_LOG2),
    ("POSITION_WORDS", POSITION_WORDS),
    ("ENVIRONMENT_TEXEL_WORDS", ENVIRONMENT_TEXEL_WORDS),
    ("FRAME_NEE", FRAME_NEE),
    ("FRAME_HIT_AOV", FRAME_HIT_AOV),
    ("LIGHT_TRIANGLE", LIGHT_TRIANGLE),
    ("LIGHT_POINT", LIGHT_POINT),
    ("LIGHT_SPOT", LIGHT_SPOT),
    ("LIGHT_DIRECTIONAL", LIGHT_DIRECTIONAL),
    ("LIGHT_ENVIRONMENT", LIGHT_ENVIRONMENT),
    ("LIGHT_SUN", LIGHT_SUN),
    ("LIGHT_ENVIRONMENT_BILINEAR", LIGHT_ENVIRONMENT_BILINEAR),
    (
        "LIGHT_ENVIRONMENT_COMPENSATED_BILINEAR",
        LIGHT_ENVIRONMENT_COMPENSATED_BILINEAR,
    ),
    (
        "LIGHT_ENVIRONMENT_COMPENSATED",
        LIGHT_ENVIRONMENT_COMPENSATED,
    ),
    ("LIGHT_TREE_LEAF", LIGHT_TREE_LEAF),
    ("LIGHT_TREE_TWO_SIDED", LIGHT_TREE_TWO_SIDED),
    // A BVH2 traversal stack needs at most one entry per level below the root; builds deeper than
    // MAX_TRAVERSAL_DEPTH are refused on the CPU, so neither stack can overflow.
    ("BLAS_STACK_SIZE", crate::bvh::MAX_TRAVERSAL_DEPTH),
    ("TLAS_STACK_SIZE", crate::bvh::MAX_TRAVERSAL_DEPTH),
    ("WIDE_STACK_SIZE", crate::bvh::wide::MAX_WIDE_DEPTH),
    (
        "WIDE_TLAS_STACK_SIZE",
        crate::bvh::tlas::MAX_WIDE_TLAS_DEPTH,
    ),
    ("DEFORM_GROUP", DEFORM_GROUP),
    ("WAVE_CONTROL_WORDS", WAVE_CONTROL_WORDS),
    ("WAVE_CONTROL_RAYS", WAVE_CONTROL_RAYS),
    ("SORT_BINS", SORT_BINS),
    ("SORT_BLOCK", SORT_BLOCK),
    ("SORT_BLOCKS", SORT_BLOCKS),
    ("SORT_WORDS", SORT_WORDS),
    ("REFIT_GROUP", REFIT_GROUP),
    ("RT_TEMPORAL", RT_TEMPORAL),
    ("RT_HISTORY", RT_HISTORY),
    ("RT_GRADIENTS", RT_GRADIENTS),
    ("RT_RESTIR", RT_RESTIR),
    ("RT_RESTIR_TEMPORAL", RT_RESTIR_TEMPORAL),
    ("RT_RESTIR_SPATIAL", RT_RESTIR_SPATIAL),
    ("RT_RESTIR_UNBIASED", RT_RESTIR_UNBIASED),
    ("RT_RESTIR_VISIBILITY", RT_RESTIR_VISIBILITY),
    ("RT_RESTIR_HISTORY", RT_RESTIR_HISTORY),
    ("RT_LIGHTS_REMAPPED", RT_LIGHTS_REMAPPED),
    ("RT_MATERIALS_EDITED", RT_MATERIALS_EDITED),
    ("RT_INJECT_NONFINITE", RT_INJECT_NONFINITE),
    ("GRADIENT_STRATUM", GRADIENT_STRATUM),
];

/// `GpuRealtimeFrame::flags`: which stages of the real-time path run this frame, and what history exists.
/// Temporal accumulation of colour.
pub const RT_TEMPORAL: u32 = 1;
/// The previous frame's G-buffer and colour history are valid (same size, nothing reset).
pub const RT_HISTORY: u32 = 2;
/// A-SVGF temporal gradients shorten the history where lighting changed.
pub const RT_GRADIENTS: u32 = 4;
/// Direct light at the first hit from ReSTIR DI (else next-event estimation in the path).
pub const RT_RESTIR: u32 = 8;
pub const RT_RESTIR_TEMPORAL: u32 = 16;
pub const RT_RESTIR_SPATIAL: u32 = 32;
/// Visibility in the MIS weights of reuse (unbiased; shadow rays per neighbour).
pub const RT_RESTIR_UNBIASED: u32 = 64;
/// Test the initial candidate's visibility before reuse (always on with `RT_RESTIR_UNBIASED`).
pub const RT_RESTIR_VISIBILITY: u32 = 128;
/// Last frame's reservoirs are valid.
pub const RT_RESTIR_HISTORY: u32 = 256;
/// The light list changed since last frame: reservoirs' light indices go through `light_remap`.
pub const RT_LIGHTS_REMAPPED: u32 = 512;
/// Some materials were edited since last frame (`edited_materials` lists them).
pub const RT_MATERIALS_EDITED: u32 = 1024;
/// Tests only: the real-time trace writes NaN and infinite samples at some pixels.
pub const RT_INJECT_NONFINITE: u32 = 2048;
/// Side of a temporal-gradient stratum in pixels (A-SVGF: 3).
pub const GRADIENT_STRATUM: u32 = 3;

/// The real-time path's per-frame constants (`shaders/realtime/frame.wgsl` `RealtimeFrame`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuRealtimeFrame {
    pub camera_from_world: [[f32; 4]; 4],
    pub prev_camera_from_world: [[f32; 4]; 4],
    pub prev_camera_origin: [f32; 3],
    pub prev_tan_half_fov: f32,
    pub flags: u32,
    pub history_cap: f32,
    pub strata_width: u32,
    pub strata_height: u32,
    pub restir_candidates: u32,
    pub restir_neighbours: u32,
    pub restir_radius: f32,
    pub restir_max_confidence: f32,
    pub depth_tolerance: f32,
    pub normal_tolerance: f32,
    pub _pad: [u32; 2],
}

/// An instance's previous placement and stable object id (`shaders/realtime/motion.wgsl` `MotionInstance`),
/// by current instance index.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuMotionInstance {
    pub prev_world_from_object: [[f32; 4]; 3],
    pub object: u32,
    pub _pad: [u32; 3],
}

/// One pixel of the real-time G-buffer (`shaders/realtime/gbuffer.wgsl` `GSurface`), as read back.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuSurface {
    pub position: [f32; 3],
    /// Camera depth; < 0 where the ray left the scene.
    pub depth: f32,
    /// Stable object id, [`NONE`] where nothing was hit.
    pub object: u32,
    pub triangle: u32,
    pub bary: [f32; 2],
    pub normal: u32,
    pub geometric: u32,
    pub bsdf: [u32; 2],
    /// Previous minus current screen position of the hit, pixels (+y down).
    pub motion: [f32; 2],
    pub prev_depth: f32,
    pub material: u32,
}

/// One pixel's real-time sample (`shaders/realtime/sample.wgsl` `RealtimeSample`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuRealtimeSample {
    pub radiance: [f32; 3],
    pub valid: u32,
    pub unscattered: [f32; 3],
    pub _pad: u32,
}

/// Per-dispatch constants of the view (a uniform buffer, `shaders/view.wgsl` `Frame`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuFrame {
    pub world_from_camera: [[f32; 4]; 4],
    pub tan_half_fov: f32,
    /// Thin-lens aperture radius in scene units (0: a pinhole).
    pub lens_radius: f32,
    /// Distance of the sharp plane along the view axis.
    pub focus_distance: f32,
    /// Lights in the light list (and entries of its CDF).
    pub light_count: u32,
    pub width: u32,
    pub height: u32,
    /// Samples per pixel already accumulated before this dispatch (the sample index base for the RNG).
    pub sample_base: u32,
    pub spp: u32,
    pub max_depth: u32,
    pub seed: u32,
    /// Path depth from which Russian roulette may end a path (u32::MAX: never).
    pub rr_depth: u32,
    /// Bit 0: next-event estimation on; bit 1: write the primary-hit AOV.
    pub flags: u32,
    /// The lights at infinity (environment, sun), which rays leaving the scene see: a range of the light list.
    pub infinite_light_first: u32,
    pub infinite_light_count: u32,
    /// Lights in the light tree, the list's first ones (0: the light sampler samples by power alone).
    pub tree_light_count: u32,
    /// Invocations that share each pixel's samples in the trace pass (`passes::trace::sample_lanes`).
    pub sample_lanes: u32,
}

pub const FRAME_NEE: u32 = 1;
/// Bit 1: write the primary-hit AOV (first dispatch after a reset only).
pub const FRAME_HIT_AOV: u32 = 2;

/// Octahedral encoding of a unit vector into two snorm16 values (WGSL `unpack2x16snorm` decodes it).
pub fn oct_encode(v: Vec3) -> u32 {
    let len = v.length();
    if !len.is_finite() || len < 1e-12 {
        return INVALID_OCT;
    }
    let n = v / (v.x.abs() + v.y.abs() + v.z.abs());
    let (x, y) = if n.z >= 0.0 {
        (n.x, n.y)
    } else {
        (
            (1.0 - n.y.abs()) * n.x.signum(),
            (1.0 - n.x.abs()) * n.y.signum(),
        )
    };
    let q = |f: f32| ((f.clamp(-1.0, 1.0) * 32767.0).round() as i32 as i16 as u16) as u32;
    q(x) | (q(y) << 16)
}

pub fn pack_unorm4x8(c: Vec4) -> u32 {
    let q = |f: f32| ((f.clamp(0.0, 1.0) * 255.0).round() as u32) & 0xff;
    q(c.x) | (q(c.y) << 8) | (q(c.z) << 16) | (q(c.w) << 24)
}
