//! The environment setting made into lights: [`bake`] turns any [`Environment`] into a map with its sampling
//! distribution (and the sun), which `GpuScene::set_environment` uploads.

use super::settings::Environment;
use crate::environment::{BakedEnvironment, EnvironmentError, EnvironmentMap};

/// Rows of the baked sky gradient (its radiance is linear in cos(theta); 64 rows keep the bilinear
/// reconstruction within 0.1% of it).
const GRADIENT_ROWS: u32 = 65;

/// What a map texel costs in `environment_map`: the texel (`ENVIRONMENT_TEXEL_WORDS` f32: rgb and a pad) and
/// its entry in each of the two distributions' conditional CDFs (1 f32 each).
const GPU_BYTES_PER_TEXEL: u64 = 4 * (super::layout::ENVIRONMENT_TEXEL_WORDS as u64 + 2);

/// The environment as a map (and a sun). `byte_limit` bounds an HDR map's GPU copy (it is halved until it
/// fits, with a note). Errors name the map file.
pub fn bake(
    environment: &Environment,
    byte_limit: u64,
) -> Result<BakedEnvironment, EnvironmentError> {
    Ok(match environment {
        Environment::Constant(c) => {
            BakedEnvironment::from_map(EnvironmentMap::constant(*c), 0.0, 1.0)
        }
        Environment::Sky => BakedEnvironment::from_map(gradient_sky(), 0.0, 1.0),
        Environment::Map(settings) => {
            BakedEnvironment::load_map(settings, GPU_BYTES_PER_TEXEL, byte_limit)?
        }
        Environment::SunSky(settings) => BakedEnvironment::sun_sky(settings),
    })
}

/// The sky gradient: mix(white, (0.5, 0.7, 1), (y + 1) / 2) along direction y.
fn gradient_sky() -> EnvironmentMap {
    let texels = (0..GRADIENT_ROWS)
        .map(|j| {
            let y = (std::f32::consts::PI * j as f32 / (GRADIENT_ROWS - 1) as f32).cos();
            let t = 0.5 * (y + 1.0);
            [1.0 - 0.5 * t, 1.0 - 0.3 * t, 1.0]
        })
        .collect();
    EnvironmentMap::new(1, GRADIENT_ROWS, texels)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gradient_follows_the_direction_height() {
        let map = gradient_sky();
        for y in [-0.9f32, -0.2, 0.0, 0.5, 0.95] {
            let d = glam::Vec3::new((1.0 - y * y).sqrt(), y, 0.0);
            let t = 0.5 * (y + 1.0);
            let got = map.lookup(d);
            assert!((got[0] - (1.0 - 0.5 * t)).abs() < 2e-3, "{y}: {got:?}");
        }
    }
}
