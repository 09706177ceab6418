//! Which of the glTF BSDF's extension lobes (KHR_materials_ior, _specular, _transmission, _volume) a scene's
//! materials use, and the path-tracing kernels compiled for exactly that. The WGSL library reads the choice as
//! the pipeline constant `MATERIAL_LOBES` (`shaders/scene/interaction.wgsl`), so a scene without them runs a
//! kernel in which the extension code folds away: measured on the H200, reading the lobes cost scenes that do
//! not use them 12-38% of their trace time (docs/BENCHMARKS.md).

use super::gpu_scene::{TextureSlots, gpu_material};
use super::layout::{GpuMaterial, NONE};
use crate::gpu::ComputeModule;

/// What the materials need, least first; the WGSL constant's values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
pub enum MaterialLobes {
    /// The core metallic-roughness BSDF only.
    #[default]
    Core = 0,
    /// Extension factors (IOR, specular, transmission, volume) without their textures.
    Factors = 1,
    /// Factors and the transmission, specular and specular-colour textures.
    Textured = 2,
}

impl MaterialLobes {
    /// The pipeline constants that compile a kernel of the WGSL library for this choice.
    pub fn constants(self) -> [(&'static str, f64); 1] {
        [("MATERIAL_LOBES", self as u32 as f64)]
    }

    /// The least the materials need.
    pub fn of(materials: &[GpuMaterial]) -> Self {
        let core = gpu_material(&crate::scene::Material::default(), &TextureSlots::default());
        materials.iter().fold(Self::Core, |need, m| {
            let textured = [
                m.transmission_texture,
                m.specular_texture,
                m.specular_color_texture,
            ]
            .iter()
            .any(|&t| t != NONE);
            let factors = m.specular_f0 != core.specular_f0
                || m.specular_weight != core.specular_weight
                || m.attenuation != core.attenuation
                || m.refraction_ior != core.refraction_ior
                || m.transmission != core.transmission;
            need.max(if textured {
                Self::Textured
            } else if factors {
                Self::Factors
            } else {
                Self::Core
            })
        })
    }
}

/// One compute kernel of the path tracer compiled per [`MaterialLobes`] value on first use (the module is parsed
/// once; a scene that never needs the extension lobes never compiles them).
pub struct LobeKernels {
    label: &'static str,
    entry: &'static str,
    module: ComputeModule,
    pipelines: [Option<wgpu::ComputePipeline>; 3],
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
            pipelines: Default::default(),
        }
    }

    /// The kernel for `lobes`, compiled now if it has not been.
    pub fn get(&mut self, lobes: MaterialLobes) -> &wgpu::ComputePipeline {
        self.pipelines[lobes as usize].get_or_insert_with(|| {
            self.module
                .pipeline(self.label, self.entry, &lobes.constants())
        })
    }

    /// The kernel for `lobes` if [`Self::get`] compiled it.
    pub fn compiled(&self, lobes: MaterialLobes) -> Option<&wgpu::ComputePipeline> {
        self.pipelines[lobes as usize].as_ref()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::gpu_scene::{TextureSlots, gpu_material};
    use crate::scene::material_extensions::{Specular, Transmission};
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
    }
}
