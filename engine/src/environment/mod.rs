//! The environment on the CPU: radiance arriving from infinitely far away. Whatever the user picks (a
//! constant, the sky gradient, an HDR map, the sun and sky) becomes one equirectangular map with its
//! importance-sampling distribution, plus, for daylight, the sun as a separate disc light; the renderer uploads
//! both as lights (`render::gpu_scene::lights`).
//!
//! - [`map`]: `.hdr` / `.exr` maps and the direction <-> texel convention (Mitsuba 3's `envmap`);
//! - [`sampling`]: the 2D distribution over the map (luminance x sin theta) and its density;
//! - [`sun_sky`]: the Preetham sky and the sun.
//!
//! No GPU here: everything is tested on the CPU, and the WGSL twins are checked against it.

pub mod map;
pub mod sampling;
pub mod sun_sky;

pub use map::{EnvironmentError, EnvironmentMap};
pub use sampling::{EnvironmentDistribution, NextEventSampling};
pub use sun_sky::{SunDisc, SunSkyParams};

use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// An HDR map as the user gives it (`--env-map FILE --env-rotation DEG --env-strength S`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MapSettings {
    pub path: PathBuf,
    /// Turn about +Y in degrees (Mitsuba's `to_world = rotate([0, 1, 0], DEG)`).
    pub rotation_degrees: f32,
    /// Radiance scale.
    pub strength: f32,
}

/// The sun and sky as the user gives them.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SunSkySettings {
    pub elevation_degrees: f32,
    pub azimuth_degrees: f32,
    pub turbidity: f32,
    /// Scale of both sky and sun radiance.
    pub strength: f32,
}

impl Default for SunSkySettings {
    fn default() -> Self {
        Self {
            elevation_degrees: 35.0,
            azimuth_degrees: 40.0,
            turbidity: 3.0,
            strength: 1.0,
        }
    }
}

impl SunSkySettings {
    pub fn params(&self) -> SunSkyParams {
        SunSkyParams {
            elevation_degrees: self.elevation_degrees,
            azimuth_degrees: self.azimuth_degrees,
            turbidity: self.turbidity,
        }
    }
}

/// An environment ready to upload: the map with its distribution, how it is turned and scaled, and the sun.
#[derive(Clone, Debug)]
pub struct BakedEnvironment {
    pub map: EnvironmentMap,
    pub distribution: EnvironmentDistribution,
    /// How next-event estimation samples the map (none, the full distribution, or compensated).
    pub next_event: NextEventSampling,
    pub rotation_degrees: f32,
    pub strength: f32,
    pub sun: Option<SunDisc>,
    /// What the user should know (downscaled to fit, repaired texels, ...).
    pub notes: Vec<String>,
}

impl BakedEnvironment {
    pub fn from_map(map: EnvironmentMap, rotation_degrees: f32, strength: f32) -> Self {
        let distribution = EnvironmentDistribution::new(&map);
        let next_event = sampling::next_event_sampling(&map, &distribution);
        Self {
            map,
            distribution,
            next_event,
            rotation_degrees,
            strength,
            sun: None,
            notes: Vec::new(),
        }
    }

    /// Whether the map emits anything (a black environment needs no light).
    pub fn is_black(&self) -> bool {
        self.strength <= 0.0 || self.distribution.luminance_integral <= 0.0
    }

    /// Sky map plus sun disc, both scaled by the settings' strength.
    pub fn sun_sky(settings: &SunSkySettings) -> Self {
        let params = settings.params();
        let mut baked = Self::from_map(params.sky_map(), 0.0, settings.strength);
        baked.sun = params.sun().map(|mut sun| {
            sun.radiance = sun.radiance.map(|c| c * settings.strength);
            sun
        });
        baked
    }

    /// Loads an HDR map, halving it until its GPU copy, `bytes_per_texel` for each texel, fits `byte_limit`.
    pub fn load_map(
        settings: &MapSettings,
        bytes_per_texel: u64,
        byte_limit: u64,
    ) -> Result<Self, EnvironmentError> {
        let (mut map, mut notes) = EnvironmentMap::load(&settings.path)?;
        let (w, h) = (map.width, map.height);
        let halvings = map.fit_to(bytes_per_texel, byte_limit);
        if halvings > 0 {
            notes.push(format!(
                "{}: {w}x{h} is over this GPU's buffer limit; downscaled to {}x{}",
                settings.path.display(),
                map.width,
                map.height
            ));
        }
        let mut baked = Self::from_map(map, settings.rotation_degrees, settings.strength);
        baked.notes = notes;
        Ok(baked)
    }
}
