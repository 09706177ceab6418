//! Which of the glTF BSDF's extension lobes (KHR_materials_ior, _specular, _transmission, _volume) and layers
//! (KHR_materials_sheen, _clearcoat) a scene's materials use, and the path-tracing kernels compiled for exactly
//! that. The WGSL library reads the choice as the pipeline constant `MATERIAL_LOBES` (`shaders/bsdf/gltf.wgsl`),
//! so a scene without them runs a kernel in which the extension code folds away: measured on the H200, reading
//! the lobes cost scenes that do not use them 12-38% of their trace time (docs/BENCHMARKS.md). The layers are a
//! bit of their own, so scenes without sheen or clearcoat compile the kernels they compiled before the layers.

use super::gpu_scene::{TextureSlots, gpu_material};
use super::layout::{
    CORE_TEXTURE_BASE_COLOR, CORE_TEXTURE_EMISSIVE, CORE_TEXTURE_METALLIC_ROUGHNESS,
    CORE_TEXTURE_NORMAL, GpuMaterial, LOBES_LAYERS, LOBES_LEVEL, MATERIAL_ALPHA_BLEND,
    MATERIAL_ALPHA_MASK, MATERIAL_UNLIT, NONE,
};
use crate::gpu::ComputeModule;
use std::collections::HashMap;

/// What the materials need; the WGSL constant's values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum MaterialLobes {
    /// The core metallic-roughness BSDF only.
    #[default]
    Core = 0,
    /// Extension factors (IOR, specular, transmission, volume; unlit) without their textures.
    Factors = 1,
    /// Factors and the transmission, specular and specular-colour textures.
    Textured = 2,
    /// Extension factors with the sheen and clearcoat layers' factors.
    LayeredFactors = 1 | LOBES_LAYERS as isize,
    /// Everything: factors, layers and all their textures.
    LayeredTextured = 2 | LOBES_LAYERS as isize,
}

impl MaterialLobes {
    const ALL: [Self; 5] = [
        Self::Core,
        Self::Factors,
        Self::Textured,
        Self::LayeredFactors,
        Self::LayeredTextured,
    ];

    /// The pipeline constants that compile a kernel of the WGSL library for this choice.
    pub fn constants(self) -> [(&'static str, f64); 1] {
        [("MATERIAL_LOBES", self as u32 as f64)]
    }

    /// Whether the kernel shades the sheen and clearcoat layers.
    pub fn layered(self) -> bool {
        self as u32 & LOBES_LAYERS != 0
    }

    /// The least choice that shades what `self` and `other` both need.
    pub fn union(self, other: Self) -> Self {
        let level = (self as u32 & LOBES_LEVEL).max(other as u32 & LOBES_LEVEL);
        let layers = (self as u32 | other as u32) & LOBES_LAYERS;
        // Layers come with at least the extension factors (the level-0 kernel reads no extension data).
        let value = if layers != 0 {
            level.max(1) | layers
        } else {
            level
        };
        Self::ALL
            .into_iter()
            .find(|k| *k as u32 == value)
            .unwrap_or(Self::LayeredTextured)
    }

    /// The least the materials need.
    pub fn of(materials: &[GpuMaterial]) -> Self {
        let core = gpu_material(&crate::scene::Material::default(), &TextureSlots::default());
        materials.iter().fold(Self::Core, |need, m| {
            let textures = [
                m.transmission_texture,
                m.specular_texture,
                m.specular_color_texture,
            ];
            let layer_textures = [
                m.clearcoat_texture,
                m.clearcoat_roughness_texture,
                m.clearcoat_normal_texture,
                m.sheen_color_texture,
                m.sheen_roughness_texture,
            ];
            let factors = m.flags & MATERIAL_UNLIT != 0
                || m.specular_f0 != core.specular_f0
                || m.specular_weight != core.specular_weight
                || m.attenuation != core.attenuation
                || m.refraction_ior != core.refraction_ior
                || m.transmission != core.transmission;
            // A layer is there when its factor or colour is not 0 (its textures only multiply those).
            let layers = m.clearcoat > 0.0 || m.sheen_color.iter().any(|&c| c > 0.0);
            let textured = textures.iter().any(|&t| t != NONE)
                || (layers && layer_textures.iter().any(|&t| t != NONE));
            let this = match (layers, textured, factors) {
                (true, true, _) => Self::LayeredTextured,
                (true, false, _) => Self::LayeredFactors,
                (false, true, _) => Self::Textured,
                (false, false, true) => Self::Factors,
                (false, false, false) => Self::Core,
            };
            need.union(this)
        })
    }
}

/// What the path-tracing kernels are compiled for: the lobes, the core texture slots (base colour,
/// metallic-roughness, normal, emissive) some material uses, the pipeline constant `CORE_TEXTURES`
/// (`shaders/scene/texture.wgsl`): lookups of the other slots compile away; and whether any material is
/// alpha-masked (`ALPHA_MASKS`). On GPUs that shortens the kernel;
/// on lavapipe, whose `if`s mask lanes and skip nothing, a texture-less scene's lookups cost 43% of its time
/// (docs/BENCHMARKS.md, "Kernels without the texture slots no material uses").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct MaterialNeeds {
    pub lobes: MaterialLobes,
    pub core_textures: u32,
    /// Some material is alpha-masked: traversal tests the cut-outs (`ALPHA_MASKS`, `shaders/scene/alpha.wgsl`).
    pub alpha_masks: bool,
    /// Some material is alpha-blended: paths may pass through surfaces. Not a constant of the library's; the
    /// wavefront pass picks its kernels by it (`WAVE_PASS_THROUGHS`).
    pub alpha_blend: bool,
}

impl MaterialNeeds {
    /// The least the materials need.
    pub fn of(materials: &[GpuMaterial]) -> Self {
        Self {
            lobes: MaterialLobes::of(materials),
            core_textures: core_textures(materials),
            alpha_masks: materials.iter().any(|m| m.flags & MATERIAL_ALPHA_MASK != 0),
            alpha_blend: materials
                .iter()
                .any(|m| m.flags & MATERIAL_ALPHA_BLEND != 0),
        }
    }

    /// The pipeline constants that compile a kernel of the WGSL library for this choice.
    pub fn constants(self) -> [(&'static str, f64); 3] {
        let [lobes] = self.lobes.constants();
        [
            lobes,
            ("CORE_TEXTURES", f64::from(self.core_textures)),
            ("ALPHA_MASKS", if self.alpha_masks { 1.0 } else { 0.0 }),
        ]
    }
}

/// The core texture slots some material uses (`CORE_TEXTURE_*` bits).
pub fn core_textures(materials: &[GpuMaterial]) -> u32 {
    materials.iter().fold(0, |slots, m| {
        let slot = |texture: u32, bit: u32| if texture != NONE { bit } else { 0 };
        slots
            | slot(m.base_color_texture, CORE_TEXTURE_BASE_COLOR)
            | slot(
                m.metallic_roughness_texture,
                CORE_TEXTURE_METALLIC_ROUGHNESS,
            )
            | slot(m.normal_texture, CORE_TEXTURE_NORMAL)
            | slot(m.emissive_texture, CORE_TEXTURE_EMISSIVE)
    })
}

/// What a path-tracing kernel is compiled for: the materials' needs, and the instance the top level's one leaf
/// holds where it holds one (`GpuScene::sole_instance`, the pipeline constant `SOLE_INSTANCE` of
/// `shaders/traversal/tlas.wgsl`): traversal starts in that instance and the top-level loop compiles away. A
/// static scene merged into one tree has one leaf; on lavapipe the loop, which it runs for every ray whatever
/// the leaf count, cost that scene 9% (docs/BENCHMARKS.md, "kernels compiled for the scene's shape").
/// The BLAS layouts the leaves use (`GpuScene::blas_layouts`, `BLAS_LAYOUTS`) compile only their traversals: on
/// lavapipe the child-pair BVH2's loop ran for every instance visited of a scene that has none (8% of the Cornell
/// box's render). Where no environment map samples the bilinear density inside its cells
/// (`LightList::environment_cells_uniform`, `ENVIRONMENT_BILINEAR` of `shaders/lights/environment.wgsl`), that
/// code compiles away (9% of the Cornell box's render under the sky gradient). The light kinds next-event
/// estimation can pick (`LightList::next_event_kinds`, `NEXT_EVENT_LIGHT_KINDS` of `shaders/lights/dispatch.wgsl`)
/// keep their sampling code and the others lose it (an environment left to BSDF sampling keeps only its
/// radiance lookup); lavapipe runs every kind's code for every light sample otherwise.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct KernelNeeds {
    pub materials: MaterialNeeds,
    pub sole_instance: Option<u32>,
    /// `BLAS_LAYOUT_*` bits; 0: not known, every layout.
    pub blas_layouts: u32,
    /// Every environment map samples its cells uniformly (false: not known, or some map is bilinear).
    pub environment_cells_uniform: bool,
    /// `1 << LIGHT_*` bits of the kinds next-event estimation can pick; `None`: not known, or the kernel also
    /// samples lights otherwise (the real-time kernel's gradient estimates sample by power), every kind.
    pub next_event_light_kinds: Option<u32>,
    /// Where the top level's buffer holds the wide tree (`GpuScene::wide_top_level`, `WIDE_TOP_LEVEL` of
    /// `shaders/traversal/tlas.wgsl`): its first 16-byte word. Only the waves' kernels traverse it.
    pub wide_top_level: Option<u32>,
}

impl KernelNeeds {
    /// The pipeline constants that compile a kernel of the WGSL library for this choice.
    pub fn constants(self) -> Vec<(&'static str, f64)> {
        let mut constants = self.materials.constants().to_vec();
        if let Some(instance) = self.sole_instance {
            constants.push(("SOLE_INSTANCE", f64::from(instance)));
        }
        if self.blas_layouts != 0 {
            constants.push(("BLAS_LAYOUTS", f64::from(self.blas_layouts)));
        }
        if self.environment_cells_uniform {
            constants.push(("ENVIRONMENT_BILINEAR", 0.0));
        }
        if let Some(kinds) = self.next_event_light_kinds {
            constants.push(("NEXT_EVENT_LIGHT_KINDS", f64::from(kinds)));
        }
        if let Some(word) = self.wide_top_level {
            constants.push(("WIDE_TOP_LEVEL", f64::from(word)));
        }
        constants
    }
}

/// One compute kernel of the path tracer compiled per [`KernelNeeds`] value on first use (the module is parsed
/// once; a scene that never needs the extension lobes never compiles them).
pub struct LobeKernels {
    label: &'static str,
    entry: &'static str,
    module: ComputeModule,
    /// Pipeline constants of the module's own, the same for every lobe choice.
    constants: Vec<(&'static str, f64)>,
    pipelines: HashMap<KernelNeeds, wgpu::ComputePipeline>,
}

impl LobeKernels {
    pub fn new(
        ctx: &crate::gpu::GpuContext,
        label: &'static str,
        source: String,
        layouts: &[Option<&wgpu::BindGroupLayout>],
        entry: &'static str,
    ) -> Self {
        Self {
            label,
            entry,
            module: ComputeModule::new(ctx, source, layouts),
            constants: Vec::new(),
            pipelines: HashMap::new(),
        }
    }

    /// The same kernels compiled with these values of the module's other pipeline constants.
    pub fn with_constants(self, constants: &[(&'static str, f64)]) -> Self {
        Self {
            constants: constants.to_vec(),
            ..self
        }
    }

    /// The kernel for `needs`, compiled now if it has not been.
    pub fn get(&mut self, needs: KernelNeeds) -> &wgpu::ComputePipeline {
        self.pipelines.entry(needs).or_insert_with(|| {
            let constants: Vec<_> = needs
                .constants()
                .into_iter()
                .chain(self.constants.iter().copied())
                .collect();
            self.module.pipeline(self.label, self.entry, &constants)
        })
    }

    /// The kernel for `needs` if [`Self::get`] compiled it.
    pub fn compiled(&self, needs: KernelNeeds) -> Option<&wgpu::ComputePipeline> {
        self.pipelines.get(&needs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::gpu_scene::{TextureSlots, gpu_material};
    use crate::scene::material_extensions::{Clearcoat, Sheen, Specular, Transmission};
    use crate::scene::{Material, TextureRef};

    fn need(m: &Material) -> MaterialLobes {
        MaterialLobes::of(&[
            gpu_material(&Material::default(), &TextureSlots::default()),
            gpu_material(m, &TextureSlots::default()),
        ])
    }

    #[test]
    fn the_kernel_follows_what_the_materials_use() {
        let mut m = Material::default();
        assert_eq!(need(&m), MaterialLobes::Core);
        m.extensions.ior = 1.4;
        assert_eq!(need(&m), MaterialLobes::Factors);
        m.extensions.ior = 1.5;
        m.extensions.transmission = Some(Transmission {
            factor: 0.5,
            texture: None,
        });
        assert_eq!(need(&m), MaterialLobes::Factors);
        m.extensions.specular = Some(Specular {
            factor: 1.0,
            texture: Some(TextureRef::new(0, 0)),
            color: glam::Vec3::ONE,
            color_texture: None,
        });
        assert_eq!(need(&m), MaterialLobes::Textured);
        m.extensions.clearcoat = Some(Clearcoat {
            factor: 1.0,
            texture: None,
            roughness: 0.0,
            roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
        });
        assert_eq!(need(&m), MaterialLobes::LayeredTextured);
        m.extensions.specular = None;
        assert_eq!(need(&m), MaterialLobes::LayeredFactors);
        // A layer of factor 0 is no layer, whatever its textures.
        m.extensions.clearcoat = None;
        m.extensions.transmission = None;
        m.extensions.sheen = Some(Sheen {
            color: glam::Vec3::ZERO,
            color_texture: Some(TextureRef::new(0, 0)),
            roughness: 0.5,
            roughness_texture: None,
        });
        assert_eq!(need(&m), MaterialLobes::Core);
        m.extensions.sheen.as_mut().unwrap().color = glam::Vec3::splat(0.5);
        assert_eq!(need(&m), MaterialLobes::LayeredTextured);
    }

    /// The texture slots and alpha test the kernels keep are exactly those some material uses.
    #[test]
    fn kernels_keep_the_texture_slots_and_alpha_test_materials_use() {
        let plain = Material::default();
        let needs = |materials: &[&Material]| {
            let gpu: Vec<_> = materials
                .iter()
                .map(|m| gpu_material(m, &TextureSlots::default()))
                .collect();
            MaterialNeeds::of(&gpu)
        };
        let none = needs(&[&plain]);
        assert_eq!((none.core_textures, none.alpha_masks), (0, false));
        let mut base = plain.clone();
        base.base_color_texture = Some(TextureRef::new(0, 0));
        let mut lit = plain.clone();
        lit.emissive = glam::Vec3::ONE;
        lit.emissive_texture = Some(TextureRef::new(1, 0));
        lit.normal_texture = Some(TextureRef::new(2, 0));
        let mut cut = plain.clone();
        cut.metallic_roughness_texture = Some(TextureRef::new(3, 0));
        cut.alpha_mode = crate::scene::AlphaMode::Mask(0.5);
        assert_eq!(
            needs(&[&plain, &base]).core_textures,
            CORE_TEXTURE_BASE_COLOR
        );
        assert_eq!(
            needs(&[&lit, &plain]).core_textures,
            CORE_TEXTURE_EMISSIVE | CORE_TEXTURE_NORMAL
        );
        let all = needs(&[&base, &lit, &cut]);
        assert_eq!(all.core_textures, crate::render::layout::CORE_TEXTURES_ALL);
        assert!(all.alpha_masks && !needs(&[&base, &lit]).alpha_masks);
        // Blending is not a cut-out: it needs no test in traversal.
        let mut blend = plain.clone();
        blend.alpha_mode = crate::scene::AlphaMode::Blend;
        assert!(!needs(&[&blend]).alpha_masks);
        assert!(needs(&[&blend]).alpha_blend && !needs(&[&cut]).alpha_blend);
        assert_eq!(
            all.constants().map(|(name, _)| name),
            ["MATERIAL_LOBES", "CORE_TEXTURES", "ALPHA_MASKS"]
        );
    }

    #[test]
    fn union_keeps_every_need() {
        use MaterialLobes::*;
        assert_eq!(Textured.union(LayeredFactors), LayeredTextured);
        assert_eq!(Factors.union(Core), Factors);
        assert_eq!(LayeredFactors.union(Factors), LayeredFactors);
        assert!(LayeredFactors.layered() && !Textured.layered());
    }
}
