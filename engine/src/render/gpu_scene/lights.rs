//! The light list: every light the light sampler picks from, in one array of [`GpuLight`] (`lights`, group 0
//! binding 9) with the sampler's power CDF (`light_cdf`, binding 11), and the environment map with its
//! sampling distribution (`environment_map`, binding 12).
//!
//! Order: emissive triangles first, grouped by instance in TLAS leaf order and sorted by slot within one (a
//! BSDF-sampled hit finds its light by binary search from `GpuInstance::first_light`), then point and spot
//! lights (with the triangles: the lights at finite distance, which the light tree holds, `light_tree`), then
//! directional lights, then the lights at infinity (environment, sun), whose range the frame uniform names for
//! rays that leave the scene. Each part is rebuilt when its inputs change (placements or emission; light
//! components; the environment setting) and the list and tree are uploaded once per frame at most.
//!
//! Power (pbrt-v4's `Light::Phi`, in luminance): triangle pi L A (x2 two-sided), point 4 pi I, spot
//! 2 pi I (1 - (cos inner + cos outer) / 2), directional pi r^2 E, environment pi r^2 x the luminance integral
//! over the sphere, sun pi r^2 L x its solid angle; r is the radius of the scene's bounding sphere.

use super::light_tree::{self, LightBounds};
use super::packing::luminance;
use super::{GpuScene, SceneWrites};
use crate::environment::{BakedEnvironment, EnvironmentDistribution, NextEventSampling};
use crate::gpu::GpuContext;
use crate::gpu::bind::write_or_grow;
use crate::render::layout::*;
use crate::scene::{PunctualKind, PunctualLight};
use glam::{Mat4, Vec3};
use std::f64::consts::PI;

/// A light, the power its selection probability follows, and (at finite distance) its bounds for the tree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WeightedLight {
    pub light: GpuLight,
    pub power: f64,
    pub bounds: Option<LightBounds>,
    /// The power next-event estimation's choice follows: `power`, except for an environment map that it
    /// samples MIS-compensated (`environment::NextEventSampling`: then the power of its light above the
    /// map's mean), and `None` for a smooth environment (a uniform one, the sky gradient), left to BSDF
    /// sampling alone (pbrt-v4's `UniformInfiniteLight` with `allowIncompletePDF`;
    /// `environment::sampling::SMOOTH_PEAK_TO_MEAN`: cosine or glossy-lobe directions sample its light nearly
    /// as well, and the path saves the shadow ray). The power CDF (ReSTIR's candidates) keeps every light at
    /// its full power.
    pub next_event_power: Option<f64>,
}

impl WeightedLight {
    /// The same light with both its powers times `factor` (the lights at infinity and directional lights get
    /// pi r^2 once the scene's size is known).
    fn scaled(self, factor: f64) -> Self {
        Self {
            power: self.power * factor,
            next_event_power: self.next_event_power.map(|p| p * factor),
            ..self
        }
    }
}

/// The lights at infinity of the current environment, their powers before [`WeightedLight::scaled`] by the
/// scene's size.
#[derive(Clone, Debug, Default)]
pub struct InfiniteLights {
    /// The environment map light (`None`: black).
    environment: Option<WeightedLight>,
    sun: Option<WeightedLight>,
}

/// The light list's parts and upload state, inside [`GpuScene`].
#[derive(Debug, Default)]
pub struct LightList {
    triangles: Vec<WeightedLight>,
    punctual: Vec<WeightedLight>,
    infinite: InfiniteLights,
    /// Radius of the scene's bounding sphere (directional and infinite lights' power).
    bounds_radius: f32,
    dirty: bool,
    /// As last uploaded.
    pub count: u32,
    pub infinite_first: u32,
    pub infinite_count: u32,
    /// Emissive triangles in the list.
    pub triangle_count: u32,
    /// Lights in the light tree (the list's first ones); 0 when there is no tree.
    pub tree_count: u32,
    /// The kinds of light next-event estimation can pick, as uploaded: bit `1 << kind` for each kind with a
    /// light it samples (the trace kernels leave the others' sampling code out: `KernelNeeds`).
    pub next_event_kinds: u32,
    /// The list as last uploaded (the real-time path keys its reservoirs' lights by it).
    pub uploaded: Vec<GpuLight>,
}

impl LightList {
    pub(super) fn set_triangles(&mut self, triangles: Vec<WeightedLight>) {
        self.triangles = triangles;
        self.dirty = true;
    }

    /// Total power of the emissive triangles (what their share of the power CDF follows).
    pub fn triangle_power(&self) -> f64 {
        self.triangles.iter().map(|l| l.power).sum()
    }

    /// Whether no uploaded environment map samples the bilinear density inside its cells (either of its
    /// distributions): the trace kernels then leave that code out (`KernelNeeds`). Asked every frame, so only
    /// the lights at infinity are looked at, not the emissive triangles before them.
    pub fn environment_cells_uniform(&self) -> bool {
        let bilinear = LIGHT_ENVIRONMENT_BILINEAR | LIGHT_ENVIRONMENT_COMPENSATED_BILINEAR;
        let first = self.infinite_first as usize;
        let at_infinity = &self.uploaded[first..first + self.infinite_count as usize];
        !at_infinity
            .iter()
            .any(|l| l.kind == LIGHT_ENVIRONMENT && l.flags & bilinear != 0)
    }

    pub(super) fn set_bounds_radius(&mut self, radius: f32) {
        if radius != self.bounds_radius {
            self.bounds_radius = radius;
            self.dirty = true;
        }
    }
}

/// A punctual light placed by its node's world matrix (glTF: at the node's origin, shining along its -Z).
pub fn punctual_light(world: Mat4, light: &PunctualLight) -> WeightedLight {
    let position = world.transform_point3(Vec3::ZERO);
    let direction = world
        .transform_vector3(Vec3::NEG_Z)
        .normalize_or(Vec3::NEG_Z);
    let color = light.scaled_color();
    let lum = luminance(color) as f64;
    let mut gpu = GpuLight {
        kind: LIGHT_POINT,
        index_a: 0,
        index_b: 0,
        flags: 0,
        position: position.to_array(),
        range: light.range.unwrap_or(0.0),
        direction: direction.to_array(),
        cos_outer: -1.0,
        radiance: color.to_array(),
        cos_inner: -1.0,
    };
    let mut bounds = None;
    let power = match light.kind {
        PunctualKind::Point => 4.0 * PI * lum,
        PunctualKind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => {
            gpu.kind = LIGHT_SPOT;
            gpu.cos_inner = inner_cone_angle.cos();
            gpu.cos_outer = outer_cone_angle.cos();
            2.0 * PI * lum * (1.0 - 0.5 * (gpu.cos_inner + gpu.cos_outer) as f64)
        }
        PunctualKind::Directional => {
            gpu.kind = LIGHT_DIRECTIONAL;
            gpu.range = 0.0;
            // Times pi r^2 once the scene's size is known.
            lum
        }
    };
    if gpu.kind != LIGHT_DIRECTIONAL {
        bounds = Some(LightBounds::punctual(&gpu));
    }
    WeightedLight {
        light: gpu,
        power,
        bounds,
        next_event_power: Some(power),
    }
}

impl GpuScene {
    /// Replaces the punctual lights (world matrix and light per node, in a stable order); true when they
    /// differ from the current ones.
    pub fn set_punctual_lights(&mut self, placed: &[(Mat4, PunctualLight)]) -> bool {
        let lights: Vec<WeightedLight> = placed
            .iter()
            .map(|(world, light)| punctual_light(*world, light))
            .collect();
        if lights == self.lights.punctual {
            return false;
        }
        self.lights.punctual = lights;
        self.lights.dirty = true;
        true
    }

    /// Uploads the environment map and its distribution (`None` or a black map: no environment light) and
    /// the sun.
    pub fn set_environment(&mut self, ctx: &GpuContext, baked: Option<&BakedEnvironment>) {
        self.lights.dirty = true;
        self.lights.infinite = InfiniteLights::default();
        let Some(baked) = baked.filter(|b| !b.is_black() || b.sun.is_some()) else {
            return;
        };
        if !baked.is_black() {
            let map = &baked.map;
            let dist = &baked.distribution;
            let cdf_words = dist.conditional_cdf.len() + dist.marginal_cdf.len();
            // Texels padded to ENVIRONMENT_TEXEL_WORDS: one 16-byte load each where the scene is read through
            // textures (CPU adapters), instead of two loads and the word selects of a texel straddling two.
            let texel_words = ENVIRONMENT_TEXEL_WORDS as usize;
            let mut words: Vec<f32> =
                Vec::with_capacity(map.texels.len() * texel_words + 2 * cdf_words);
            for texel in &map.texels {
                words.extend(texel);
                words.resize(words.len() + texel_words - texel.len(), 0.0);
            }
            let compensated = match &baked.next_event {
                NextEventSampling::Compensated(c) => Some(c),
                _ => None,
            };
            for d in std::iter::once(dist).chain(compensated) {
                words.extend(&d.conditional_cdf);
                words.extend(&d.marginal_cdf);
            }
            self.written |= SceneWrites::ENVIRONMENT_MAP;
            if write_or_grow(
                ctx,
                &mut self.environment_map,
                bytemuck::cast_slice(&words),
                "environment map",
            ) {
                self.generation += 1;
            }
            let (sin, cos) = baked.rotation_degrees.to_radians().sin_cos();
            let mut flags = 0;
            if dist.bilinear {
                flags |= LIGHT_ENVIRONMENT_BILINEAR;
            }
            if let Some(c) = compensated {
                flags |= LIGHT_ENVIRONMENT_COMPENSATED;
                if c.bilinear {
                    flags |= LIGHT_ENVIRONMENT_COMPENSATED_BILINEAR;
                }
            }
            let light = GpuLight {
                kind: LIGHT_ENVIRONMENT,
                index_a: map.width,
                index_b: map.height,
                flags,
                position: [cos, sin, 0.0],
                range: compensated.map_or(0.0, |c| c.offset),
                direction: [0.0; 3],
                cos_outer: 0.0,
                radiance: [baked.strength; 3],
                cos_inner: 0.0,
            };
            let power = |d: &EnvironmentDistribution| d.luminance_integral * baked.strength as f64;
            let next_event_power = match &baked.next_event {
                NextEventSampling::None => None,
                NextEventSampling::Full => Some(power(dist)),
                NextEventSampling::Compensated(c) => Some(power(c)),
            };
            self.lights.infinite.environment = Some(WeightedLight {
                light,
                power: power(dist),
                bounds: None,
                next_event_power,
            });
        }
        if let Some(sun) = &baked.sun {
            let light = GpuLight {
                kind: LIGHT_SUN,
                index_a: 0,
                index_b: 0,
                flags: 0,
                position: [0.0; 3],
                range: sun.one_minus_cos,
                direction: sun.direction.to_array(),
                cos_outer: 0.0,
                radiance: sun.radiance,
                cos_inner: 0.0,
            };
            let solid_angle = 2.0 * PI * sun.one_minus_cos as f64;
            let power = luminance(Vec3::from(sun.radiance)) as f64 * solid_angle;
            self.lights.infinite.sun = Some(WeightedLight {
                light,
                power,
                bounds: None,
                next_event_power: Some(power),
            });
        }
    }

    /// Uploads the light list and its CDF when a part changed; true when it did.
    pub fn upload_lights(&mut self, ctx: &GpuContext) -> bool {
        if !self.lights.dirty {
            return false;
        }
        self.lights.dirty = false;
        let list = &self.lights;
        let disc = PI * (list.bounds_radius as f64).powi(2);
        let mut all: Vec<WeightedLight> = list.triangles.clone();
        let (finite, directional): (Vec<WeightedLight>, Vec<WeightedLight>) = list
            .punctual
            .iter()
            .partition(|w| w.light.kind != LIGHT_DIRECTIONAL);
        all.extend(finite);
        let tree_lights = all.len();
        all.extend(directional.into_iter().map(|w| w.scaled(disc)));
        let infinite_first = all.len() as u32;
        all.extend(
            [list.infinite.environment, list.infinite.sun]
                .into_iter()
                .flatten()
                .map(|w| w.scaled(disc)),
        );
        let infinite_count = all.len() as u32 - infinite_first;
        // Two CDFs in one buffer: by power over every light, then next-event estimation's.
        let mut cdf = power_cdf(&all);
        cdf.extend(next_event_cdf(&all));
        // The tree over the lights at finite distance; each light's bit trail goes in its flags.
        let bounded: Vec<(u32, LightBounds)> = all[..tree_lights]
            .iter()
            .enumerate()
            .filter_map(|(i, w)| w.bounds.map(|b| (i as u32, b)))
            .collect();
        let tree = light_tree::build(&bounded);
        if tree.is_none() && !bounded.is_empty() {
            tracing::warn!(
                "{} lights make a light tree deeper than {} levels; lights are sampled by power",
                bounded.len(),
                light_tree::MAX_LIGHT_TREE_DEPTH
            );
        }
        let mut gpu: Vec<GpuLight> = all.iter().map(|w| w.light).collect();
        self.written |= SceneWrites::LIGHTS | SceneWrites::LIGHT_CDF | SceneWrites::LIGHT_TREE;
        let mut recreated = false;
        let tree_count = match &tree {
            Some((nodes, trails)) => {
                for &(light, trail) in trails {
                    gpu[light as usize].flags = trail;
                }
                recreated |= write_or_grow(
                    ctx,
                    &mut self.light_tree,
                    bytemuck::cast_slice(nodes),
                    "light tree",
                );
                tree_lights as u32
            }
            None => 0,
        };
        if !gpu.is_empty() {
            recreated |= write_or_grow(
                ctx,
                &mut self.light_buffer,
                bytemuck::cast_slice(&gpu),
                "lights",
            );
            recreated |= write_or_grow(
                ctx,
                &mut self.light_cdf,
                bytemuck::cast_slice(&cdf),
                "light cdf",
            );
        }
        if recreated {
            self.generation += 1;
        }
        self.lights.count = gpu.len() as u32;
        self.lights.infinite_first = infinite_first;
        self.lights.infinite_count = infinite_count;
        self.lights.triangle_count = self.lights.triangles.len() as u32;
        self.lights.tree_count = tree_count;
        self.lights.next_event_kinds = all
            .iter()
            .filter(|w| w.next_event_power.is_some())
            .fold(0, |kinds, w| kinds | 1 << w.light.kind);
        self.memory.lights = ((gpu.len() * 64 + cdf.len() * 4) as u64)
            + tree.map_or(0, |(nodes, _)| nodes.len() as u64 * 64)
            + self.environment_map.size();
        self.lights.uploaded = gpu;
        true
    }
}

/// Cumulative selection probabilities in proportion to power; the last entry is exactly 1 (a list whose
/// powers are all zero is sampled uniformly).
pub fn power_cdf(lights: &[WeightedLight]) -> Vec<f32> {
    cdf_by(lights, |w| Some(w.power))
}

/// Next-event estimation's CDF: in proportion to the power it samples of each light
/// ([`WeightedLight::next_event_power`]), the lights it leaves to BSDF sampling never chosen (probability 0);
/// all zeros when it samples none (then it picks nothing and BSDF sampling alone lights the scene).
pub fn next_event_cdf(lights: &[WeightedLight]) -> Vec<f32> {
    cdf_by(lights, |w| w.next_event_power)
}

/// Cumulative probabilities in proportion to `weight` over the lights it gives one (`None`: never chosen);
/// uniform over those when their weights are all zero; exactly 1 from the last chosen light on, so no u < 1
/// reaches a light after it; all zeros when none is chosen.
fn cdf_by(lights: &[WeightedLight], weight: impl Fn(&WeightedLight) -> Option<f64>) -> Vec<f32> {
    let weights: Vec<Option<f64>> = lights
        .iter()
        .map(|w| weight(w).map(|p| p.max(0.0)))
        .collect();
    let Some(last) = weights.iter().rposition(Option::is_some) else {
        return vec![0.0; lights.len()];
    };
    let total: f64 = weights.iter().flatten().sum();
    let chosen = weights.iter().flatten().count();
    let (mut running, mut seen) = (0.0, 0);
    weights
        .iter()
        .enumerate()
        .map(|(k, w)| {
            if let Some(p) = w {
                running += p;
                seen += 1;
            }
            if k >= last {
                1.0
            } else if total > 0.0 {
                ((running / total) as f32).min(1.0)
            } else {
                seen as f32 / chosen as f32
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use bytemuck::Zeroable;

    fn point(intensity: f32) -> PunctualLight {
        PunctualLight {
            name: String::new(),
            kind: PunctualKind::Point,
            color: Vec3::ONE,
            intensity,
            range: None,
        }
    }

    #[test]
    fn cdf_follows_power_and_ends_at_one() {
        let lights: Vec<WeightedLight> = [1.0, 3.0, 0.0, 4.0]
            .map(|p| WeightedLight {
                light: GpuLight::zeroed(),
                power: p,
                bounds: None,
                next_event_power: Some(p),
            })
            .to_vec();
        assert_eq!(power_cdf(&lights), vec![0.125, 0.5, 0.5, 1.0]);
    }

    #[test]
    fn next_event_estimation_never_picks_what_it_leaves_to_bsdf_sampling() {
        let light = |power, next_event_power| WeightedLight {
            light: GpuLight::zeroed(),
            power,
            bounds: None,
            next_event_power,
        };
        // A lamp, a uniform environment, a sun: the environment's share goes to the others.
        let lights = [
            light(1.0, Some(1.0)),
            light(6.0, None),
            light(3.0, Some(3.0)),
        ];
        assert_eq!(power_cdf(&lights), vec![0.1, 0.7, 1.0]);
        assert_eq!(next_event_cdf(&lights), vec![0.25, 0.25, 1.0]);
        // A compensated environment map: chosen by the power it samples.
        let lights = [light(1.0, Some(1.0)), light(6.0, Some(3.0))];
        assert_eq!(next_event_cdf(&lights), vec![0.25, 1.0]);
        // Trailing lights it skips sit at 1: no u < 1 reaches them.
        let lights = [light(1.0, Some(1.0)), light(6.0, None)];
        assert_eq!(next_event_cdf(&lights), vec![1.0, 1.0]);
        // Only a uniform environment: nothing to pick (every probability 0).
        assert_eq!(next_event_cdf(&[light(6.0, None)]), vec![0.0]);
        // Sampled lights without power: uniform among them.
        let lights = [
            light(0.0, Some(0.0)),
            light(6.0, None),
            light(0.0, Some(0.0)),
        ];
        assert_eq!(next_event_cdf(&lights), vec![0.5, 0.5, 1.0]);
    }

    #[test]
    fn punctual_lights_follow_their_node() {
        let world = Mat4::from_rotation_translation(
            glam::Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2),
            Vec3::new(1.0, 2.0, 3.0),
        );
        let mut spot = point(2.0);
        spot.kind = PunctualKind::Spot {
            inner_cone_angle: 0.1,
            outer_cone_angle: 0.4,
        };
        let w = punctual_light(world, &spot);
        assert_eq!(w.light.kind, LIGHT_SPOT);
        assert_eq!(w.light.position, [1.0, 2.0, 3.0]);
        // Local -Z turned by -90 degrees about X points down.
        assert!((Vec3::from(w.light.direction) - Vec3::NEG_Y).length() < 1e-6);
        assert!(w.light.cos_inner > w.light.cos_outer);
        assert!((punctual_light(Mat4::IDENTITY, &point(2.0)).power - 8.0 * PI).abs() < 1e-9);
    }
}
