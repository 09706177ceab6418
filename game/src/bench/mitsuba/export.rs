//! A bench scene written the way `scripts/mitsuba-side-by-side.py` reads it, so that Mitsuba 3 renders the
//! same pixels raykin does: world-space triangle groups (one per mesh instance and material) in one binary
//! file, textures as PNGs where their factor is 1 and as EXRs with the factor baked in elsewhere (Mitsuba's
//! bitmap has no factor), emission x factor x strength and coverage alpha baked per material as EXR, the
//! environment as the equirectangular EXR raykin itself samples, and the camera raykin resolved.
//!
//! What the script cannot reproduce is listed in `scene.json`'s `unsupported` (the comparison then says so):
//! the KHR material extensions beyond metallic-roughness, vertex colours, punctual lights, a thin lens.

use super::super::scenes::BenchScene;
use anyhow::{Context, Result};
use glam::{Mat3, Mat4, Vec3};
use raykin::camera::CameraView;
use raykin::render::RenderSettings;
use raykin::scene::{AlphaMode, Image, Material, MeshData, SceneAsset, TextureRef, Wrap};
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::path::Path;

/// What the renders are to be: the bench's error image size and depth, the curve's sample counts and the
/// reference's.
pub struct Renders {
    pub width: u32,
    pub height: u32,
    pub max_depth: u32,
    pub checkpoints: Vec<u32>,
    pub reference_spp: u32,
}

/// Writes `scene` seen by `camera` under `settings`' environment into `dir` (`scene.json`, `geometry.bin`,
/// `textures/`, `environment.exr`).
pub fn export(
    scene: &BenchScene,
    camera: &CameraView,
    settings: &RenderSettings,
    renders: &Renders,
    dir: &Path,
) -> Result<()> {
    // A fresh textures/ folder: baked files are reused by name within one export only.
    let _ = std::fs::remove_dir_all(dir.join("textures"));
    std::fs::create_dir_all(dir.join("textures"))
        .with_context(|| format!("{}: cannot create the export folder", dir.display()))?;
    let asset = &scene.scene;
    let mut unsupported = Vec::new();
    let mut geometry = Geometry::default();
    let shapes = geometry.flatten(asset, &mut unsupported);
    std::fs::write(dir.join("geometry.bin"), &geometry.bytes)
        .with_context(|| format!("{}: cannot write geometry.bin", dir.display()))?;
    let mut textures = Textures::new(dir, asset);
    // Triangles without a material name the one past the end: glTF's default material, which the renderer
    // appends.
    let mut all_materials = asset.materials.clone();
    all_materials.push(Material::default());
    let materials = all_materials
        .iter()
        .enumerate()
        .map(|(i, m)| material_json(i, m, &mut textures, &mut unsupported))
        .collect::<Result<Vec<_>>>()?;
    if !asset.lights.is_empty() {
        unsupported.push(format!("{} punctual lights", asset.lights.len()));
    }
    if settings.lens.aperture_radius > 0.0 {
        unsupported.push("thin-lens depth of field".into());
    }
    let environment = environment_json(settings, dir)?;
    let forward = camera.forward();
    let up = camera.world_from_camera.y_axis.truncate();
    let description = json!({
        "scene": scene.name,
        "width": renders.width,
        "height": renders.height,
        "raykin_max_depth": renders.max_depth,
        "checkpoints": renders.checkpoints,
        "reference_spp": renders.reference_spp,
        "camera": {
            "eye": camera.position().to_array(),
            "target": (camera.position() + forward).to_array(),
            "up": up.to_array(),
            "yfov_deg": camera.yfov.to_degrees(),
        },
        "environment": environment,
        "shapes": shapes,
        "materials": materials,
        "unsupported": unsupported,
        "raykin_commit": crate::provenance::commit(),
    });
    let path = dir.join("scene.json");
    std::fs::write(&path, serde_json::to_vec_pretty(&description)?)
        .with_context(|| format!("{}: cannot write", path.display()))?;
    Ok(())
}

/// The triangle groups' arrays, little-endian, one after another; `scene.json` gives each group's offsets.
#[derive(Default)]
struct Geometry {
    bytes: Vec<u8>,
}

impl Geometry {
    fn push_f32(&mut self, values: impl IntoIterator<Item = f32>) -> usize {
        let offset = self.bytes.len();
        for v in values {
            self.bytes.extend_from_slice(&v.to_le_bytes());
        }
        offset
    }

    fn push_u32(&mut self, values: impl IntoIterator<Item = u32>) -> usize {
        let offset = self.bytes.len();
        for v in values {
            self.bytes.extend_from_slice(&v.to_le_bytes());
        }
        offset
    }

    /// Every displayed mesh instance in its rest pose, split by material into world-space groups (vertices
    /// compacted per group; a mirroring transform reverses the winding, as raykin's loader does).
    fn flatten(&mut self, asset: &SceneAsset, unsupported: &mut Vec<String>) -> Vec<Value> {
        let world = asset.rest_world_matrices();
        let shown = asset.displayed_nodes();
        let mut shapes = Vec::new();
        let mut vertex_colours = false;
        for (n, node) in asset.nodes.iter().enumerate() {
            let Some(mesh) = node.mesh.filter(|_| shown[n]).map(|m| &asset.meshes[m]) else {
                continue;
            };
            // White vertex colours (the Cornell box has them) change nothing.
            vertex_colours |= mesh
                .colors
                .as_ref()
                .is_some_and(|c| c.iter().any(|c| *c != glam::Vec4::ONE));
            let mut by_material: BTreeMap<u32, Vec<[u32; 3]>> = BTreeMap::new();
            for (t, m) in mesh.triangles.iter().zip(&mesh.triangle_materials) {
                by_material.entry(*m).or_default().push(*t);
            }
            for (material, triangles) in by_material {
                shapes.push(self.group(mesh, world[n], material, &triangles, shapes.len()));
            }
        }
        if vertex_colours {
            unsupported.push("vertex colours (COLOR_0)".into());
        }
        shapes
    }

    fn group(
        &mut self,
        mesh: &MeshData,
        world: Mat4,
        material: u32,
        triangles: &[[u32; 3]],
        index: usize,
    ) -> Value {
        let mut remap = vec![u32::MAX; mesh.positions.len()];
        let mut used = Vec::new();
        for &v in triangles.iter().flatten() {
            if remap[v as usize] == u32::MAX {
                remap[v as usize] = used.len() as u32;
                used.push(v as usize);
            }
        }
        let mirrored = world.determinant() < 0.0;
        let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
        let positions = used
            .iter()
            .flat_map(|&v| world.transform_point3(mesh.positions[v]).to_array());
        let positions = self.push_f32(positions);
        let normals = mesh.normals.as_ref().map(|normals| {
            let n = used.iter().flat_map(|&v| {
                (normal_matrix * normals[v])
                    .normalize_or(Vec3::Y)
                    .to_array()
            });
            self.push_f32(n)
        });
        let uvs = mesh
            .uv0
            .as_ref()
            .map(|uv| self.push_f32(used.iter().flat_map(|&v| uv[v].to_array())));
        let indices = self.push_u32(triangles.iter().flat_map(|t| {
            let [a, b, c] = t.map(|v| remap[v as usize]);
            if mirrored { [a, c, b] } else { [a, b, c] }
        }));
        json!({
            "name": format!("{}_{index}", mesh.name),
            "material": material,
            "vertices": used.len(),
            "triangles": triangles.len(),
            "positions": positions,
            "normals": normals,
            "uvs": uvs,
            "indices": indices,
        })
    }
}

/// Texture files written so far, by (image, kind).
struct Textures<'a> {
    dir: &'a Path,
    asset: &'a SceneAsset,
    written: BTreeMap<(u32, &'static str), String>,
}

impl<'a> Textures<'a> {
    fn new(dir: &'a Path, asset: &'a SceneAsset) -> Self {
        Self {
            dir,
            asset,
            written: BTreeMap::new(),
        }
    }

    fn image(&self, slot: &TextureRef) -> Option<&'a Image> {
        let texture = self.asset.textures.get(slot.texture as usize)?;
        self.asset.images.get(texture.image as usize)
    }

    /// A texture slot as the script's bitmap, its sampler and KHR_texture_transform as a 3x3 UV matrix: the
    /// image's RGB as a PNG (`srgb`: decoded on load) where `factor` is 1, else baked into an EXR with the
    /// factor applied per channel (Mitsuba's bitmap has no factor). Slots on TEXCOORD_1 are listed.
    fn slot(
        &mut self,
        slot: &Option<TextureRef>,
        srgb: bool,
        factor: [f32; 3],
        what: &str,
        unsupported: &mut Vec<String>,
    ) -> Result<Value> {
        let Some(slot) = slot else {
            return Ok(Value::Null);
        };
        let (Some(image), Some(texture)) = (
            self.image(slot),
            self.asset.textures.get(slot.texture as usize),
        ) else {
            return Ok(Value::Null);
        };
        if slot.tex_coord != 0 {
            unsupported.push(format!("{what} on TEXCOORD_{}", slot.tex_coord));
        }
        let kind = if srgb { "srgb" } else { "linear" };
        if factor != [1.0; 3] {
            let name = format!(
                "image{}_{kind}_{:08x}{:08x}{:08x}",
                texture.image,
                factor[0].to_bits(),
                factor[1].to_bits(),
                factor[2].to_bits()
            );
            let decode = |c: f32| if srgb { srgb_to_linear(c) } else { c };
            return self.baked(slot, &name, |p| [0, 1, 2].map(|c| decode(p[c]) * factor[c]));
        }
        let key = (texture.image, kind);
        let file = match self.written.get(&key) {
            Some(f) => f.clone(),
            None => {
                let file = format!("textures/image{}_{kind}.png", texture.image);
                let rgba: Vec<u8> = image
                    .rgba8
                    .chunks_exact(4)
                    .flat_map(|p| [p[0], p[1], p[2], 255])
                    .collect();
                raykin::image_io::write_png(
                    &self.dir.join(&file),
                    image.width,
                    image.height,
                    &rgba,
                )?;
                self.written.insert(key, file.clone());
                file
            }
        };
        Ok(bitmap_json(&file, srgb, texture, slot))
    }

    /// A per-material EXR: `value(u, v, texel rgba in 0..1)` for every texel of the slot's image.
    fn baked(
        &mut self,
        slot: &TextureRef,
        name: &str,
        value: impl Fn([f32; 4]) -> [f32; 3],
    ) -> Result<Value> {
        let Some(image) = self.image(slot) else {
            return Ok(Value::Null);
        };
        let texture = &self.asset.textures[slot.texture as usize];
        let rgb: Vec<[f32; 3]> = image
            .rgba8
            .chunks_exact(4)
            .map(|p| value([0, 1, 2, 3].map(|c| p[c] as f32 / 255.0)))
            .collect();
        let file = format!("textures/{name}.exr");
        if !self.dir.join(&file).exists() {
            raykin::image_io::write_exr(&self.dir.join(&file), image.width, image.height, &rgb)?;
        }
        Ok(bitmap_json(&file, false, texture, slot))
    }
}

fn bitmap_json(
    file: &str,
    srgb: bool,
    texture: &raykin::scene::Texture,
    slot: &TextureRef,
) -> Value {
    json!({
        "file": file,
        "srgb": srgb,
        "wrap": [wrap(texture.wrap_s), wrap(texture.wrap_t)],
        "filter": if texture.nearest { "nearest" } else { "bilinear" },
        "to_uv": uv_matrix(slot),
    })
}

fn wrap(w: Wrap) -> &'static str {
    match w {
        Wrap::Repeat => "repeat",
        Wrap::MirroredRepeat => "mirror",
        Wrap::ClampToEdge => "clamp",
    }
}

/// KHR_texture_transform as a row-major 3x3 matrix on (u, v, 1): translation x rotation x scale.
fn uv_matrix(slot: &TextureRef) -> [f32; 9] {
    let t = &slot.transform;
    let (s, c) = t.rotation.sin_cos();
    [
        c * t.scale.x,
        s * t.scale.y,
        t.offset.x,
        -s * t.scale.x,
        c * t.scale.y,
        t.offset.y,
        0.0,
        0.0,
        1.0,
    ]
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn material_json(
    index: usize,
    m: &Material,
    textures: &mut Textures,
    unsupported: &mut Vec<String>,
) -> Result<Value> {
    let ext = &m.extensions;
    let mut extensions = Vec::new();
    if ext.unlit {
        extensions.push("unlit");
    }
    if ext.transmission.is_some() {
        extensions.push("transmission");
    }
    if ext.clearcoat.is_some() {
        extensions.push("clearcoat");
    }
    if ext.sheen.is_some() {
        extensions.push("sheen");
    }
    if ext.volume.is_some() {
        extensions.push("volume");
    }
    if ext.specular.is_some() {
        extensions.push("specular");
    }
    if (ext.ior - 1.5).abs() > 1e-6 {
        extensions.push("ior");
    }
    if !extensions.is_empty() {
        unsupported.push(format!(
            "material {index} `{}`: {}",
            m.name,
            extensions.join(", ")
        ));
    }
    let emission = m.emitted_radiance();
    let emission_texture = match (&m.emissive_texture, emission.max_element() > 0.0) {
        (Some(slot), true) => textures.baked(slot, &format!("material{index}_emission"), |p| {
            [0, 1, 2].map(|c| srgb_to_linear(p[c]) * emission[c])
        })?,
        _ => Value::Null,
    };
    let (alpha_mode, cutoff) = match m.alpha_mode {
        AlphaMode::Opaque => ("opaque", 0.0),
        AlphaMode::Mask(cutoff) => ("mask", cutoff),
        AlphaMode::Blend => ("blend", 0.0),
    };
    let factor_alpha = m.base_color.w;
    // Coverage as the path sees it: MASK is all or nothing per texel, BLEND the fraction (raykin passes
    // through with probability 1 - alpha).
    let coverage = |a: f32| match m.alpha_mode {
        AlphaMode::Mask(cutoff) => f32::from(a >= cutoff),
        _ => a,
    };
    let alpha_texture = match (&m.base_color_texture, m.alpha_mode) {
        (Some(slot), AlphaMode::Mask(_) | AlphaMode::Blend) => {
            textures.baked(slot, &format!("material{index}_alpha"), |p| {
                [coverage(p[3] * factor_alpha); 3]
            })?
        }
        _ => Value::Null,
    };
    // Mitsuba's normalmap reads (2c - 1) as the tangent-space normal: glTF's scale on x and y is baked in.
    let normal_texture = match &m.normal_texture {
        Some(slot) if m.normal_scale != 1.0 => {
            let scale = m.normal_scale;
            textures.baked(slot, &format!("material{index}_normal"), |p| {
                let n = Vec3::new(
                    (2.0 * p[0] - 1.0) * scale,
                    (2.0 * p[1] - 1.0) * scale,
                    2.0 * p[2] - 1.0,
                )
                .normalize_or(Vec3::Z);
                (n * 0.5 + Vec3::splat(0.5)).to_array()
            })?
        }
        slot => textures.slot(slot, false, [1.0; 3], "normal map", unsupported)?,
    };
    Ok(json!({
        "name": m.name,
        // With a texture the factor is baked into it (the value then is the texture's alone).
        "base_color": m.base_color.truncate().to_array(),
        "base_color_texture": textures.slot(
            &m.base_color_texture,
            true,
            m.base_color.truncate().to_array(),
            "base colour",
            unsupported,
        )?,
        "metallic": m.metallic,
        "roughness": m.roughness,
        "metallic_roughness_texture": textures.slot(
            &m.metallic_roughness_texture,
            false,
            [1.0, m.roughness, m.metallic],
            "metallic-roughness",
            unsupported,
        )?,
        "normal_texture": normal_texture,
        "emission": emission.to_array(),
        "emission_texture": emission_texture,
        "alpha_mode": alpha_mode,
        "alpha_cutoff": cutoff,
        "alpha": coverage(factor_alpha),
        "alpha_texture": alpha_texture,
        "double_sided": m.double_sided,
    }))
}

/// The environment as raykin bakes it (the sky gradient, a constant, a map), written as an EXR with its
/// rotation and strength; `null` when it is black.
fn environment_json(settings: &RenderSettings, dir: &Path) -> Result<Value> {
    let baked = raykin::render::environment::bake(&settings.environment, u64::MAX)?;
    anyhow::ensure!(
        baked.sun.is_none(),
        "the sun of a sun-and-sky environment is not exported to Mitsuba"
    );
    if baked.is_black() {
        return Ok(Value::Null);
    }
    // Mitsuba's envmap wants at least two columns; a one-column gradient is the same repeated.
    let map = &baked.map;
    let repeat = if map.width < 4 { 4 } else { 1 };
    let texels: Vec<[f32; 3]> = (0..map.height as usize)
        .flat_map(|j| {
            (0..(map.width * repeat) as usize)
                .map(move |i| map.texels[j * map.width as usize + i / repeat as usize])
        })
        .collect();
    let file = "environment.exr";
    raykin::image_io::write_exr(&dir.join(file), map.width * repeat, map.height, &texels)?;
    Ok(json!({
        "file": file,
        "rotation_degrees": baked.rotation_degrees,
        "strength": baked.strength,
    }))
}
