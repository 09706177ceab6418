//! Packing the scene asset into GPU layouts: materials, vertex attributes, triangles in BVH leaf order,
//! emissive-triangle lists and texels.

use crate::render::layout::*;
use crate::scene::{AlphaMode, MeshData, SceneAsset, TextureTransform, Wrap};
use glam::Vec3;

/// Texture-info entries for transformed texture slots (KHR_texture_transform). Each distinct (texture,
/// transform) pair that a material uses gets its own entry after the scene's textures: a copy of the texture's
/// entry with the transform's rows and [`TEXTURE_TRANSFORMED`]. A slot word then names that entry, so a slot
/// without a transform costs nothing extra and the shader reads one entry either way.
#[derive(Clone, Debug, Default)]
pub struct TextureSlots {
    entries: std::collections::HashMap<(u32, [u32; 8]), u32>,
}

fn transform_rows(t: &TextureTransform) -> ([f32; 4], [f32; 4]) {
    let [a, b, c, d, e, f] = t.affine_rows();
    let (sin, cos) = t.rotation.sin_cos();
    ([a, b, c, cos], [d, e, f, sin])
}

fn transform_key(t: &TextureTransform) -> [u32; 8] {
    let (u, v) = transform_rows(t);
    let mut key = [0; 8];
    for (k, x) in key.iter_mut().zip(u.iter().chain(&v)) {
        *k = x.to_bits();
    }
    key
}

impl TextureSlots {
    /// Appends an entry to `infos` for every transformed slot of `materials`' GPU slots.
    pub fn build(materials: &[crate::scene::Material], infos: &mut Vec<GpuTexture>) -> Self {
        let mut slots = Self::default();
        let base_count = infos.len();
        for m in materials {
            for t in gpu_texture_slots(m).into_iter().flatten() {
                if t.transform.is_identity() || (t.texture as usize) >= base_count {
                    continue;
                }
                let key = (t.texture, transform_key(&t.transform));
                if slots.entries.contains_key(&key) {
                    continue;
                }
                let (uv_u, uv_v) = transform_rows(&t.transform);
                let base = infos[t.texture as usize];
                slots.entries.insert(key, infos.len() as u32);
                infos.push(GpuTexture {
                    flags: base.flags | TEXTURE_TRANSFORMED,
                    uv_u,
                    uv_v,
                    ..base
                });
            }
        }
        slots
    }

    /// The GPU slot word of a material's texture reference: its texture-info entry in bits 0..24 and its
    /// TEXCOORD set in bit 24; [`NONE`] when absent. A transform this table does not hold (a material edited
    /// after upload) falls back to the untransformed texture.
    pub fn slot_word(&self, t: Option<crate::scene::TextureRef>) -> u32 {
        t.map_or(NONE, |t| {
            let entry = if t.transform.is_identity() {
                t.texture
            } else {
                self.entries
                    .get(&(t.texture, transform_key(&t.transform)))
                    .copied()
                    .unwrap_or(t.texture)
            };
            entry | (t.tex_coord << 24)
        })
    }
}

/// Every texture slot the shader samples: the core four, then transmission, specular and specular colour, then
/// clearcoat, clearcoat roughness, clearcoat normal, sheen colour and sheen roughness.
fn gpu_texture_slots(m: &crate::scene::Material) -> [Option<crate::scene::TextureRef>; 12] {
    let e = &m.extensions;
    let coat = e.clearcoat.as_ref();
    let sheen = e.sheen.as_ref();
    [
        m.base_color_texture,
        m.metallic_roughness_texture,
        m.normal_texture,
        m.emissive_texture,
        e.transmission.as_ref().and_then(|t| t.texture),
        e.specular.as_ref().and_then(|s| s.texture),
        e.specular.as_ref().and_then(|s| s.color_texture),
        coat.and_then(|c| c.texture),
        coat.and_then(|c| c.roughness_texture),
        coat.and_then(|c| c.normal_texture),
        sheen.and_then(|s| s.color_texture),
        sheen.and_then(|s| s.roughness_texture),
    ]
}

/// Relative IORs closer to 1 than this bend rays too little to matter but would make the refraction's
/// half vector degenerate: such surfaces transmit like thin walls (straight through when smooth).
const MIN_REFRACTION: f32 = 1e-3;

/// The extension lobes' GPU parameters (KHR_materials_ior, specular, transmission, volume): dielectric f0
/// colour and weight, absorption coefficient, the IOR that bends rays and the transmission factor.
fn gpu_extension_factors(m: &crate::scene::Material) -> ([f32; 3], f32, [f32; 3], f32, f32) {
    let e = &m.extensions;
    // In f64 so that the default IOR 1.5 gives exactly the core specification's 0.04.
    let ior = e.ior as f64;
    let f0 = (((ior - 1.0) / (ior + 1.0)).powi(2)) as f32;
    let (weight, color) = e
        .specular
        .as_ref()
        .map_or((1.0, Vec3::ONE), |s| (s.factor, s.color));
    let transmission = e.transmission.as_ref().map_or(0.0, |t| t.factor);
    // A volume needs a transmissive surface; thickness 0 (or no volume) is thin-walled.
    let volume = e
        .volume
        .as_ref()
        .filter(|v| v.thickness > 0.0 && e.transmission.is_some());
    let refraction_ior = match volume {
        Some(_) if e.ior >= 1.0 + MIN_REFRACTION => e.ior,
        _ => 1.0,
    };
    let attenuation = volume
        .filter(|v| v.attenuation_distance.is_finite())
        .map_or(Vec3::ZERO, |v| {
            // A black channel absorbs everything within a few distances instead of at once (no inf * 0).
            -v.attenuation_color.max(Vec3::splat(1e-6)).map(f32::ln) / v.attenuation_distance
        });
    (
        (f0 * color).to_array(),
        weight,
        attenuation.to_array(),
        refraction_ior,
        transmission,
    )
}

pub fn gpu_material(m: &crate::scene::Material, textures: &TextureSlots) -> GpuMaterial {
    let (cutoff, alpha_flags) = match m.alpha_mode {
        AlphaMode::Opaque => (0.0, 0),
        AlphaMode::Mask(c) => (c, MATERIAL_ALPHA_MASK),
        AlphaMode::Blend => (0.0, MATERIAL_ALPHA_BLEND),
    };
    let (specular_f0, specular_weight, attenuation, refraction_ior, transmission) =
        gpu_extension_factors(m);
    let slots = gpu_texture_slots(m);
    let coat = m.extensions.clearcoat.as_ref();
    let sheen = m.extensions.sheen.as_ref();
    GpuMaterial {
        base_color: m.base_color.to_array(),
        emissive: m.emitted_radiance().to_array(),
        metallic: m.metallic,
        roughness: m.roughness,
        alpha_cutoff: cutoff,
        normal_scale: m.normal_scale,
        flags: alpha_flags
            | if m.double_sided {
                MATERIAL_DOUBLE_SIDED
            } else {
                0
            }
            | if m.extensions.unlit {
                MATERIAL_UNLIT
            } else {
                0
            },
        base_color_texture: textures.slot_word(m.base_color_texture),
        metallic_roughness_texture: textures.slot_word(m.metallic_roughness_texture),
        normal_texture: textures.slot_word(m.normal_texture),
        emissive_texture: textures.slot_word(m.emissive_texture),
        specular_f0,
        specular_weight,
        attenuation,
        refraction_ior,
        transmission,
        transmission_texture: textures.slot_word(slots[4]),
        specular_texture: textures.slot_word(slots[5]),
        specular_color_texture: textures.slot_word(slots[6]),
        clearcoat: coat.map_or(0.0, |c| c.factor),
        clearcoat_roughness: coat.map_or(0.0, |c| c.roughness),
        clearcoat_texture: textures.slot_word(slots[7]),
        clearcoat_roughness_texture: textures.slot_word(slots[8]),
        sheen_color: sheen.map_or([0.0; 3], |s| s.color.to_array()),
        sheen_roughness: sheen.map_or(0.0, |s| s.roughness),
        clearcoat_normal_texture: textures.slot_word(slots[9]),
        clearcoat_normal_scale: coat.map_or(1.0, |c| c.normal_scale),
        sheen_color_texture: textures.slot_word(slots[10]),
        sheen_roughness_texture: textures.slot_word(slots[11]),
    }
}

pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// Pads the vertex pool to where positions may start (a multiple of [`POSITION_WORDS`]).
pub(super) fn align_positions(pool: &mut Vec<u32>) {
    pool.resize(pool.len().next_multiple_of(POSITION_WORDS as usize), 0);
}

/// A position as the vertex pool holds it ([`POSITION_WORDS`] words).
pub fn position_words(p: Vec3) -> [u32; POSITION_WORDS as usize] {
    [p.x.to_bits(), p.y.to_bits(), p.z.to_bits(), 0]
}

/// Appends a mesh's attributes to the vertex pool; returns the mesh's offsets.
pub(super) fn pack_vertices(mesh: &MeshData, pool: &mut Vec<u32>) -> GpuMesh {
    align_positions(pool);
    let mut gpu = GpuMesh {
        blas_root: 0,
        triangle_offset: 0,
        position_offset: pool.len() as u32,
        normal_offset: NONE,
        tangent_offset: NONE,
        uv0_offset: NONE,
        uv1_offset: NONE,
        color_offset: NONE,
    };
    pool.extend(mesh.positions.iter().flat_map(|&p| position_words(p)));
    if let Some(n) = &mesh.normals {
        gpu.normal_offset = pool.len() as u32;
        pool.extend(n.iter().map(|n| oct_encode(*n)));
    }
    if let Some(t) = &mesh.tangents {
        gpu.tangent_offset = pool.len() as u32;
        pool.extend(t.iter().flat_map(|t| {
            [
                oct_encode(t.truncate()),
                if t.w < 0.0 { -1f32 } else { 1f32 }.to_bits(),
            ]
        }));
    }
    for (uv, offset) in [
        (&mesh.uv0, &mut gpu.uv0_offset),
        (&mesh.uv1, &mut gpu.uv1_offset),
    ] {
        if let Some(uv) = uv {
            // From an even word: a UV pair never straddles two 16-byte texels (CPU adapters read it as one).
            pool.resize(pool.len().next_multiple_of(2), 0);
            *offset = pool.len() as u32;
            pool.extend(uv.iter().flat_map(|v| v.to_array().map(f32::to_bits)));
        }
    }
    if let Some(c) = &mesh.colors {
        gpu.color_offset = pool.len() as u32;
        pool.extend(c.iter().map(|c| pack_unorm4x8(*c)));
    }
    gpu
}

/// Halves images (box filter) until all texels fit `budget` bytes; returns the images and a note if any shrank.
type FittedImage = (u32, u32, Vec<u8>);

fn fit_images(scene: &SceneAsset, budget: u64) -> (Vec<FittedImage>, Option<String>) {
    let mut images: Vec<(u32, u32, Vec<u8>)> = scene
        .images
        .iter()
        .map(|i| (i.width, i.height, i.rgba8.clone()))
        .collect();
    let total = |imgs: &[(u32, u32, Vec<u8>)]| imgs.iter().map(|i| i.2.len() as u64).sum::<u64>();
    let before = total(&images);
    let mut halvings = 0;
    while total(&images) > budget {
        let Some(largest) = (0..images.len()).max_by_key(|&i| images[i].2.len()) else {
            break;
        };
        let (w, h, px) = &images[largest];
        if *w <= 1 && *h <= 1 {
            break;
        }
        let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
        let mut out = vec![0u8; (nw * nh * 4) as usize];
        for y in 0..nh {
            for x in 0..nw {
                for c in 0..4 {
                    let mut sum = 0u32;
                    for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        let sx = (2 * x + dx).min(w - 1);
                        let sy = (2 * y + dy).min(h - 1);
                        sum += px[((sy * w + sx) * 4 + c) as usize] as u32;
                    }
                    out[((y * nw + x) * 4 + c) as usize] = ((sum + 2) / 4) as u8;
                }
            }
        }
        images[largest] = (nw, nh, out);
        halvings += 1;
    }
    let note = (halvings > 0).then(|| {
        format!(
            "textures ({:.1} MiB) exceed the GPU's buffer limit; downscaled {halvings} time(s) to {:.1} MiB",
            before as f64 / 1048576.0,
            total(&images) as f64 / 1048576.0
        )
    });
    (images, note)
}

/// Every image's texels in one RGBA8 buffer (downscaled to fit `budget` bytes) and each texture's GPU
/// description; a note when images had to shrink.
pub(super) fn pack_textures(
    scene: &SceneAsset,
    budget: u64,
) -> (Vec<u32>, Vec<GpuTexture>, Option<String>) {
    let (images, note) = fit_images(scene, budget);
    let mut texels: Vec<u32> = Vec::new();
    let mut image_offsets = Vec::new();
    for (_, _, px) in &images {
        image_offsets.push(texels.len() as u32);
        texels.extend(
            px.chunks_exact(4)
                .map(|p| u32::from_le_bytes([p[0], p[1], p[2], p[3]])),
        );
    }
    let wrap_bits = |w: Wrap| match w {
        Wrap::Repeat => 0,
        Wrap::MirroredRepeat => 1,
        Wrap::ClampToEdge => 2,
    };
    let texture_infos: Vec<GpuTexture> = scene
        .textures
        .iter()
        .map(|t| {
            let i = (t.image as usize).min(images.len().saturating_sub(1));
            let (w, h) = images.get(i).map_or((1, 1), |im| (im.0, im.1));
            GpuTexture {
                offset: image_offsets.get(i).copied().unwrap_or(0),
                width: w,
                height: h,
                flags: wrap_bits(t.wrap_s)
                    | (wrap_bits(t.wrap_t) << 2)
                    | if t.nearest { TEXTURE_NEAREST } else { 0 },
                uv_u: [1.0, 0.0, 0.0, 1.0],
                uv_v: [0.0, 1.0, 0.0, 0.0],
            }
        })
        .collect();

    (texels, texture_infos, note)
}

/// A mesh's triangles in its BVH's leaf order, as the upload and an in-place rebuild both need them.
pub(super) struct OrderedTriangles {
    /// Vertex indices per triangle (kept on the CPU for refits).
    pub indices: Vec<[u32; 3]>,
    /// The GPU form: vertex indices + material.
    pub packed: Vec<[u32; 4]>,
    /// Emissive triangles: (slot in the triangle buffer, material).
    pub emissive: Vec<(u32, u32)>,
}

/// `triangle_materials`: each triangle's material (file order) under the variant shown.
pub(super) fn order_triangles(
    mesh: &MeshData,
    triangle_materials: &[u32],
    order: &[u32],
    triangle_offset: u32,
    materials: &[GpuMaterial],
) -> OrderedTriangles {
    let indices = crate::bvh::ordered_triangles(order, &mesh.triangles);
    let packed = pack_triangles(&indices, order, triangle_materials);
    OrderedTriangles {
        indices,
        packed,
        emissive: emissive_slots(triangle_materials, order, triangle_offset, materials),
    }
}

/// The GPU triangles: vertex indices in BVH order (`indices`) with the material of the triangle each slot
/// holds (`order`: original triangle of each slot).
pub(super) fn pack_triangles(
    indices: &[[u32; 3]],
    order: &[u32],
    triangle_materials: &[u32],
) -> Vec<[u32; 4]> {
    order
        .iter()
        .zip(indices)
        .map(|(&t, [a, b, c])| [*a, *b, *c, triangle_materials[t as usize]])
        .collect()
}

/// A mesh's emissive triangles in BVH order (`order`: original triangle of each slot): (slot in the
/// triangle buffer, material).
pub(super) fn emissive_slots(
    triangle_materials: &[u32],
    order: &[u32],
    triangle_offset: u32,
    materials: &[GpuMaterial],
) -> Vec<(u32, u32)> {
    order
        .iter()
        .enumerate()
        .filter_map(|(slot, &t)| {
            let material = triangle_materials[t as usize];
            (luminance(Vec3::from(materials[material as usize].emissive)) > 0.0)
                .then_some((triangle_offset + slot as u32, material))
        })
        .collect()
}
