//! The KHR material extensions beyond metallic-roughness, as data: parsed from the file, validated (values
//! outside their schema range are clamped with a note), carried on [`super::Material`] for the renderer.
//! The renderer shades with those in [`RENDERED`]; [`unrendered_report`] names every other one a file uses so
//! nothing is silently dropped. Where the gltf crate has typed support (ior, transmission, volume, specular, unlit)
//! it is used; the others are read from the extension's JSON.

use super::{TextureRef, TextureTransform};
use glam::Vec3;
use serde_json::Value;

/// KHR_materials_transmission: light passing through the surface (a microfacet BTDF sharing the specular
/// lobe's roughness).
#[derive(Clone, Debug, PartialEq)]
pub struct Transmission {
    pub factor: f32,
    /// Red channel multiplies `factor`.
    pub texture: Option<TextureRef>,
}

/// KHR_materials_volume: the medium behind a transmissive surface.
#[derive(Clone, Debug, PartialEq)]
pub struct Volume {
    /// Thickness in the mesh's object space; 0 = thin-walled.
    pub thickness: f32,
    /// Green channel multiplies `thickness`.
    pub thickness_texture: Option<TextureRef>,
    /// Distance light travels before its colour becomes `attenuation_color` (Beer-Lambert);
    /// `f32::INFINITY` = no attenuation.
    pub attenuation_distance: f32,
    pub attenuation_color: Vec3,
}

/// KHR_materials_specular: strength and colour of the dielectric specular lobe.
#[derive(Clone, Debug, PartialEq)]
pub struct Specular {
    pub factor: f32,
    /// Alpha channel multiplies `factor`.
    pub texture: Option<TextureRef>,
    pub color: Vec3,
    /// RGB multiplies `color` (sRGB-encoded).
    pub color_texture: Option<TextureRef>,
}

/// KHR_materials_clearcoat: a dielectric coat (IOR 1.5) over the base material.
#[derive(Clone, Debug, PartialEq)]
pub struct Clearcoat {
    pub factor: f32,
    /// Red channel multiplies `factor`.
    pub texture: Option<TextureRef>,
    pub roughness: f32,
    /// Green channel multiplies `roughness`.
    pub roughness_texture: Option<TextureRef>,
    pub normal_texture: Option<TextureRef>,
    pub normal_scale: f32,
}

/// KHR_materials_sheen: a Charlie-distribution sheen layer (cloth).
#[derive(Clone, Debug, PartialEq)]
pub struct Sheen {
    pub color: Vec3,
    /// RGB multiplies `color` (sRGB-encoded).
    pub color_texture: Option<TextureRef>,
    pub roughness: f32,
    /// Alpha channel multiplies `roughness`.
    pub roughness_texture: Option<TextureRef>,
}

/// KHR_materials_iridescence: a thin film over the base.
#[derive(Clone, Debug, PartialEq)]
pub struct Iridescence {
    pub factor: f32,
    /// Red channel multiplies `factor`.
    pub texture: Option<TextureRef>,
    pub ior: f32,
    /// Film thickness in nanometres: the green channel of `thickness_texture` mixes from min to max.
    pub thickness_min: f32,
    pub thickness_max: f32,
    pub thickness_texture: Option<TextureRef>,
}

/// KHR_materials_anisotropy: stretched specular highlights along a tangent direction.
#[derive(Clone, Debug, PartialEq)]
pub struct Anisotropy {
    pub strength: f32,
    /// Radians, counter-clockwise from the tangent.
    pub rotation: f32,
    /// RG = direction in tangent space, B = strength multiplier.
    pub texture: Option<TextureRef>,
}

/// KHR_materials_diffuse_transmission: light scattered diffusely through thin surfaces (leaves, paper).
#[derive(Clone, Debug, PartialEq)]
pub struct DiffuseTransmission {
    pub factor: f32,
    /// Alpha channel multiplies `factor`.
    pub texture: Option<TextureRef>,
    pub color: Vec3,
    /// RGB multiplies `color` (sRGB-encoded).
    pub color_texture: Option<TextureRef>,
}

/// Everything a material has beyond the core metallic-roughness model (all absent by default).
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialExtensions {
    /// KHR_materials_ior (1.5 without it). 0 is allowed: Fresnel's f0 is then 1.
    pub ior: f32,
    pub transmission: Option<Transmission>,
    pub volume: Option<Volume>,
    pub specular: Option<Specular>,
    pub clearcoat: Option<Clearcoat>,
    pub sheen: Option<Sheen>,
    /// KHR_materials_unlit: the base colour is the emitted radiance; no lighting.
    pub unlit: bool,
    pub iridescence: Option<Iridescence>,
    pub anisotropy: Option<Anisotropy>,
    /// KHR_materials_dispersion: Abbe number as 20 / V (0 = none).
    pub dispersion: f32,
    pub diffuse_transmission: Option<DiffuseTransmission>,
}

impl Default for MaterialExtensions {
    fn default() -> Self {
        Self {
            ior: 1.5,
            transmission: None,
            volume: None,
            specular: None,
            clearcoat: None,
            sheen: None,
            unlit: false,
            iridescence: None,
            anisotropy: None,
            dispersion: 0.0,
            diffuse_transmission: None,
        }
    }
}

impl MaterialExtensions {
    /// Every texture slot of the extensions, for remapping (scene composition).
    pub fn texture_slots_mut(&mut self) -> Vec<&mut Option<TextureRef>> {
        let mut slots = Vec::new();
        if let Some(t) = &mut self.transmission {
            slots.push(&mut t.texture);
        }
        if let Some(v) = &mut self.volume {
            slots.push(&mut v.thickness_texture);
        }
        if let Some(s) = &mut self.specular {
            slots.extend([&mut s.texture, &mut s.color_texture]);
        }
        if let Some(c) = &mut self.clearcoat {
            slots.extend([
                &mut c.texture,
                &mut c.roughness_texture,
                &mut c.normal_texture,
            ]);
        }
        if let Some(s) = &mut self.sheen {
            slots.extend([&mut s.color_texture, &mut s.roughness_texture]);
        }
        if let Some(i) = &mut self.iridescence {
            slots.extend([&mut i.texture, &mut i.thickness_texture]);
        }
        if let Some(a) = &mut self.anisotropy {
            slots.push(&mut a.texture);
        }
        if let Some(d) = &mut self.diffuse_transmission {
            slots.extend([&mut d.texture, &mut d.color_texture]);
        }
        slots
    }

    /// Names of the extensions in use (those that differ from the default material).
    pub fn in_use(&self) -> Vec<&'static str> {
        let mut used = Vec::new();
        if self.ior != 1.5 {
            used.push("KHR_materials_ior");
        }
        for (present, name) in [
            (self.transmission.is_some(), "KHR_materials_transmission"),
            (self.volume.is_some(), "KHR_materials_volume"),
            (self.specular.is_some(), "KHR_materials_specular"),
            (self.clearcoat.is_some(), "KHR_materials_clearcoat"),
            (self.sheen.is_some(), "KHR_materials_sheen"),
            (self.unlit, "KHR_materials_unlit"),
            (self.iridescence.is_some(), "KHR_materials_iridescence"),
            (self.anisotropy.is_some(), "KHR_materials_anisotropy"),
            (self.dispersion != 0.0, "KHR_materials_dispersion"),
            (
                self.diffuse_transmission.is_some(),
                "KHR_materials_diffuse_transmission",
            ),
        ] {
            if present {
                used.push(name);
            }
        }
        used
    }
}

/// Where a texture slot points in the file, before it is checked.
pub(super) struct SlotSource {
    pub texture: usize,
    pub tex_coord: u32,
    /// The slot's KHR_texture_transform object, if any.
    pub transform: Option<Value>,
}

impl SlotSource {
    pub fn from_info(info: &gltf::texture::Info) -> Self {
        Self {
            texture: info.texture().index(),
            tex_coord: info.tex_coord(),
            transform: info.extension_value("KHR_texture_transform").cloned(),
        }
    }

    /// A textureInfo object in extension JSON (`{"index": i, "texCoord": n, "extensions": {...}}`).
    fn from_json(value: &Value) -> Option<Self> {
        Some(Self {
            texture: value.get("index")?.as_u64()? as usize,
            tex_coord: value.get("texCoord").and_then(Value::as_u64).unwrap_or(0) as u32,
            transform: value
                .get("extensions")
                .and_then(|e| e.get("KHR_texture_transform"))
                .cloned(),
        })
    }
}

/// Resolves texture slots of one material: checks indices, TEXCOORD sets and transforms, collecting notes.
pub(super) struct SlotResolver<'a> {
    /// Per texture of the file: whether its image loaded.
    pub usable: &'a [bool],
    pub material: &'a str,
    pub notes: Vec<String>,
}

impl SlotResolver<'_> {
    pub fn resolve(&mut self, source: Option<SlotSource>, slot: &str) -> Option<TextureRef> {
        let source = source?;
        let Some(&usable) = self.usable.get(source.texture) else {
            self.notes.push(format!(
                "material `{}`: {slot} texture {} does not exist; ignored",
                self.material, source.texture
            ));
            return None;
        };
        if !usable {
            return None;
        }
        let transform = match &source.transform {
            Some(json) => {
                let (t, note) = TextureTransform::from_json(json);
                if let Some(note) = note {
                    self.notes.push(format!(
                        "material `{}`: {slot} texture: {note}",
                        self.material
                    ));
                }
                t
            }
            None => TextureTransform::IDENTITY,
        };
        let tex_coord = transform.tex_coord.unwrap_or(source.tex_coord);
        if tex_coord > 1 {
            self.notes.push(format!(
                "material `{}`: {slot} texture uses TEXCOORD_{tex_coord}; only sets 0 and 1 are read, texture ignored",
                self.material
            ));
            return None;
        }
        Some(TextureRef {
            texture: source.texture as u32,
            tex_coord,
            transform,
        })
    }

    /// A value kept inside `[lo, hi]`; outside it (or not finite) it is clamped (or `default`) with a note.
    pub fn clamp(&mut self, what: &str, v: f32, lo: f32, hi: f32, default: f32) -> f32 {
        if v.is_nan() {
            self.notes.push(format!(
                "material `{}`: {what} {v} is not a number; {default} used",
                self.material
            ));
            return default;
        }
        if v < lo || v > hi {
            let c = v.clamp(lo, hi);
            self.notes.push(format!(
                "material `{}`: {what} {v} is outside [{lo}, {hi}]; clamped to {c}",
                self.material
            ));
            return c;
        }
        v
    }

    fn clamp3(&mut self, what: &str, v: Vec3, lo: f32, hi: f32, default: Vec3) -> Vec3 {
        Vec3::new(
            self.clamp(what, v.x, lo, hi, default.x),
            self.clamp(what, v.y, lo, hi, default.y),
            self.clamp(what, v.z, lo, hi, default.z),
        )
    }

    /// A number of an extension's JSON object (absent: `default`).
    fn number(&mut self, ext: &Value, key: &str, lo: f32, hi: f32, default: f32) -> f32 {
        match ext.get(key) {
            None => default,
            Some(v) => match v.as_f64() {
                Some(x) => self.clamp(key, x as f32, lo, hi, default),
                None => {
                    self.notes.push(format!(
                        "material `{}`: {key} is not a number; {default} used",
                        self.material
                    ));
                    default
                }
            },
        }
    }

    fn color(&mut self, ext: &Value, key: &str, hi: f32, default: Vec3) -> Vec3 {
        match ext.get(key).and_then(Value::as_array) {
            None => default,
            Some(a) if a.len() == 3 && a.iter().all(Value::is_number) => {
                let v = Vec3::new(
                    a[0].as_f64().unwrap_or_default() as f32,
                    a[1].as_f64().unwrap_or_default() as f32,
                    a[2].as_f64().unwrap_or_default() as f32,
                );
                self.clamp3(key, v, 0.0, hi, default)
            }
            Some(_) => {
                self.notes.push(format!(
                    "material `{}`: {key} is not three numbers; {default} used",
                    self.material
                ));
                default
            }
        }
    }

    fn json_texture(&mut self, ext: &Value, key: &str, slot: &str) -> Option<TextureRef> {
        let value = ext.get(key)?;
        match SlotSource::from_json(value) {
            Some(source) => self.resolve(Some(source), slot),
            None => {
                self.notes.push(format!(
                    "material `{}`: {slot} texture has no valid index; ignored",
                    self.material
                ));
                None
            }
        }
    }
}

/// Reads every supported material extension of `m`.
pub(super) fn read(m: &gltf::Material, r: &mut SlotResolver) -> MaterialExtensions {
    let mut out = MaterialExtensions::default();
    if let Some(ior) = m.ior() {
        // The ratified schema allows exactly 0 (f0 = 1) besides [1, inf).
        out.ior = if ior == 0.0 {
            0.0
        } else {
            r.clamp("KHR_materials_ior ior", ior, 1.0, f32::MAX, 1.5)
        };
    }
    if let Some(t) = m.transmission() {
        out.transmission = Some(Transmission {
            factor: r.clamp("transmissionFactor", t.transmission_factor(), 0.0, 1.0, 0.0),
            texture: r.resolve(
                t.transmission_texture().map(|i| SlotSource::from_info(&i)),
                "transmission",
            ),
        });
    }
    if let Some(v) = m.volume() {
        let distance = v.attenuation_distance();
        out.volume = Some(Volume {
            thickness: r.clamp("thicknessFactor", v.thickness_factor(), 0.0, f32::MAX, 0.0),
            thickness_texture: r.resolve(
                v.thickness_texture().map(|i| SlotSource::from_info(&i)),
                "thickness",
            ),
            // The schema requires a positive distance: 0 or less would absorb everything at once.
            attenuation_distance: if distance > 0.0 {
                distance
            } else {
                r.notes.push(format!(
                    "material `{}`: attenuationDistance {distance} must be positive; no attenuation used",
                    r.material
                ));
                f32::INFINITY
            },
            attenuation_color: r.clamp3(
                "attenuationColor",
                Vec3::from(v.attenuation_color()),
                0.0,
                1.0,
                Vec3::ONE,
            ),
        });
    }
    if let Some(s) = m.specular() {
        out.specular = Some(Specular {
            factor: r.clamp("specularFactor", s.specular_factor(), 0.0, 1.0, 1.0),
            texture: r.resolve(
                s.specular_texture().map(|i| SlotSource::from_info(&i)),
                "specular",
            ),
            color: r.clamp3(
                "specularColorFactor",
                Vec3::from(s.specular_color_factor()),
                0.0,
                f32::MAX,
                Vec3::ONE,
            ),
            color_texture: r.resolve(
                s.specular_color_texture()
                    .map(|i| SlotSource::from_info(&i)),
                "specularColor",
            ),
        });
    }
    out.unlit = m.unlit();
    if let Some(e) = m.extension_value("KHR_materials_clearcoat") {
        out.clearcoat = Some(Clearcoat {
            factor: r.number(e, "clearcoatFactor", 0.0, 1.0, 0.0),
            texture: r.json_texture(e, "clearcoatTexture", "clearcoat"),
            roughness: r.number(e, "clearcoatRoughnessFactor", 0.0, 1.0, 0.0),
            roughness_texture: r.json_texture(e, "clearcoatRoughnessTexture", "clearcoatRoughness"),
            normal_texture: r.json_texture(e, "clearcoatNormalTexture", "clearcoatNormal"),
            normal_scale: e
                .get("clearcoatNormalTexture")
                .map_or(1.0, |n| r.number(n, "scale", f32::MIN, f32::MAX, 1.0)),
        });
    }
    if let Some(e) = m.extension_value("KHR_materials_sheen") {
        out.sheen = Some(Sheen {
            color: r.color(e, "sheenColorFactor", 1.0, Vec3::ZERO),
            color_texture: r.json_texture(e, "sheenColorTexture", "sheenColor"),
            roughness: r.number(e, "sheenRoughnessFactor", 0.0, 1.0, 0.0),
            roughness_texture: r.json_texture(e, "sheenRoughnessTexture", "sheenRoughness"),
        });
    }
    if let Some(e) = m.extension_value("KHR_materials_iridescence") {
        out.iridescence = Some(Iridescence {
            factor: r.number(e, "iridescenceFactor", 0.0, 1.0, 0.0),
            texture: r.json_texture(e, "iridescenceTexture", "iridescence"),
            ior: r.number(e, "iridescenceIor", 1.0, f32::MAX, 1.3),
            thickness_min: r.number(e, "iridescenceThicknessMinimum", 0.0, f32::MAX, 100.0),
            thickness_max: r.number(e, "iridescenceThicknessMaximum", 0.0, f32::MAX, 400.0),
            thickness_texture: r.json_texture(
                e,
                "iridescenceThicknessTexture",
                "iridescenceThickness",
            ),
        });
    }
    if let Some(e) = m.extension_value("KHR_materials_anisotropy") {
        out.anisotropy = Some(Anisotropy {
            strength: r.number(e, "anisotropyStrength", 0.0, 1.0, 0.0),
            rotation: r.number(e, "anisotropyRotation", f32::MIN, f32::MAX, 0.0),
            texture: r.json_texture(e, "anisotropyTexture", "anisotropy"),
        });
    }
    if let Some(e) = m.extension_value("KHR_materials_dispersion") {
        out.dispersion = r.number(e, "dispersion", 0.0, f32::MAX, 0.0);
    }
    if let Some(e) = m.extension_value("KHR_materials_diffuse_transmission") {
        out.diffuse_transmission = Some(DiffuseTransmission {
            factor: r.number(e, "diffuseTransmissionFactor", 0.0, 1.0, 0.0),
            texture: r.json_texture(e, "diffuseTransmissionTexture", "diffuseTransmission"),
            color: r.color(e, "diffuseTransmissionColorFactor", 1.0, Vec3::ONE),
            color_texture: r.json_texture(
                e,
                "diffuseTransmissionColorTexture",
                "diffuseTransmissionColor",
            ),
        });
    }
    out
}

/// The material extensions the renderer shades with (`shaders/bsdf/gltf.wgsl`).
pub const RENDERED: &[&str] = &[
    "KHR_materials_ior",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
    "KHR_materials_unlit",
];

/// One line per material extension that the file uses but the renderer does not shade with yet, naming the
/// materials, so nothing is dropped silently.
pub(super) fn unrendered_report(materials: &[super::Material]) -> Vec<String> {
    let mut by_extension: Vec<(&'static str, Vec<&str>)> = Vec::new();
    for m in materials {
        for name in m
            .extensions
            .in_use()
            .into_iter()
            .filter(|n| !RENDERED.contains(n))
        {
            match by_extension.iter_mut().find(|(n, _)| *n == name) {
                Some((_, list)) => list.push(&m.name),
                None => by_extension.push((name, vec![&m.name])),
            }
        }
    }
    let list = |names: &[&str]| {
        let shown: Vec<String> = names.iter().take(4).map(|n| format!("`{n}`")).collect();
        let more = names.len().saturating_sub(4);
        if more > 0 {
            format!("{} and {more} more", shown.join(", "))
        } else {
            shown.join(", ")
        }
    };
    let lines: Vec<String> = by_extension
        .iter()
        .map(|(name, users)| {
            format!(
                "{name} (materials {}): parsed but not rendered yet; those materials render as metallic-roughness",
                list(users)
            )
        })
        .collect();
    lines
}
