//! A physically based daylight: the Preetham et al. sky ("A Practical Analytic Model for Daylight",
//! SIGGRAPH 1999) and the sun as a sampled disc light.
//!
//! - Sky: the paper's Perez distributions of luminance Y and chromaticity (x, y) for turbidity T, scaled by its
//!   zenith values; xyY -> CIE XYZ -> linear sRGB (D65). Luminance in cd/m^2 becomes radiance through
//!   683 lm/W, so radiance is in W/(m^2 sr) weighted by the luminous efficiency (a white surface under a
//!   high sun reads about 30-40: use an exposure of about -5 stops). Below the horizon the model has no
//!   meaning and the sky is black (ground is geometry). The sky is baked into an environment map (512 x 257
//!   texels, about 0.7 degrees) and importance-sampled like any map.
//! - Sun: a disc of angular radius 0.2666 degrees whose extraterrestrial illuminance is 128 klux with the
//!   chromaticity of a 5778 K black body (Kim et al.'s Planckian-locus fit), attenuated per RGB channel by
//!   Rayleigh and Angstrom aerosol transmittance (the paper's appendix: beta = 0.04608 T - 0.04586,
//!   alpha = 1.3) at effective wavelengths 612, 549 and 465 nm, over Kasten & Young's (1989) relative air mass.
//!   Ozone, water vapour and mixed-gas absorption are left out (a few percent in the visible).
//!
//! Directions: the sun's azimuth is measured like the map's u (0 degrees: towards -Z, 90: towards +X), its
//! elevation above the XZ plane.

use super::map::{EnvironmentMap, uv_to_direction};
use glam::{DVec3, Vec3};

/// Luminous efficacy used to turn photometric into radiometric units (lm/W).
const LUMENS_PER_WATT: f64 = 683.0;
/// Solar illuminance outside the atmosphere (lux).
const SOLAR_ILLUMINANCE: f64 = 128_000.0;
/// Angular radius of the sun's disc (radians).
pub const SUN_ANGULAR_RADIUS: f64 = 0.2666 * std::f64::consts::PI / 180.0;
/// Colour temperature of the extraterrestrial sun (K).
const SUN_TEMPERATURE: f64 = 5778.0;
/// Effective wavelengths of the R, G, B channels for the transmittance (micrometres).
const CHANNEL_WAVELENGTHS: [f64; 3] = [0.612, 0.549, 0.465];
pub const SKY_MAP_WIDTH: u32 = 512;
pub const SKY_MAP_HEIGHT: u32 = 257;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunSkyParams {
    /// Degrees above the horizon.
    pub elevation_degrees: f32,
    /// Degrees, 0 towards -Z, 90 towards +X.
    pub azimuth_degrees: f32,
    /// Atmospheric turbidity, 2 (very clear) to 10 (hazy); the model is fitted for 2..10.
    pub turbidity: f32,
}

/// The sun as a light: a cone of directions around `direction` with uniform radiance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunDisc {
    /// Unit direction towards the sun.
    pub direction: Vec3,
    /// 1 - cos(angular radius), kept apart from cos for precision.
    pub one_minus_cos: f32,
    /// Linear RGB radiance of the disc.
    pub radiance: [f32; 3],
}

impl SunSkyParams {
    pub fn sun_direction(&self) -> Vec3 {
        let (el, az) = (
            (self.elevation_degrees as f64).to_radians(),
            (self.azimuth_degrees as f64).to_radians(),
        );
        DVec3::new(el.cos() * az.sin(), el.sin(), -el.cos() * az.cos()).as_vec3()
    }

    fn turbidity(&self) -> f64 {
        (self.turbidity as f64).clamp(1.7, 10.0)
    }

    /// The sky radiance (linear sRGB) along unit `d`; black below the horizon.
    pub fn sky_radiance(&self, d: Vec3) -> [f32; 3] {
        let d = d.as_dvec3();
        if d.y <= 0.0 {
            return [0.0; 3];
        }
        let sun = self.sun_direction().as_dvec3();
        let theta_s = sun
            .y
            .clamp(-1.0, 1.0)
            .acos()
            .min(std::f64::consts::FRAC_PI_2);
        let t = self.turbidity();
        let theta = d.y.clamp(-1.0, 1.0).acos();
        let gamma = d.dot(sun).clamp(-1.0, 1.0).acos();
        let [luminance, x, y] = [PerezChannel::Y, PerezChannel::X, PerezChannel::Y2].map(|c| {
            let coef = c.coefficients(t);
            c.zenith(t, theta_s) * perez(coef, theta, gamma) / perez(coef, 0.0, theta_s)
        });
        if luminance <= 0.0 || y <= 0.0 {
            return [0.0; 3];
        }
        // kcd/m^2 -> cd/m^2 -> W/(m^2 sr).
        let scale = 1000.0 / LUMENS_PER_WATT;
        xyy_to_srgb(x, y, luminance * scale).map(|c| c as f32)
    }

    /// The sky baked into a map (the lattice of [`super::map`]).
    pub fn sky_map(&self) -> EnvironmentMap {
        let (w, h) = (SKY_MAP_WIDTH, SKY_MAP_HEIGHT);
        let texels = (0..h)
            .flat_map(|j| {
                (0..w).map(move |i| {
                    self.sky_radiance(uv_to_direction(
                        (i as f32 + 0.5) / w as f32,
                        j as f32 / (h - 1) as f32,
                    ))
                })
            })
            .collect();
        EnvironmentMap::new(w, h, texels)
    }

    /// The sun's disc, or `None` when it is below the horizon.
    pub fn sun(&self) -> Option<SunDisc> {
        let direction = self.sun_direction();
        if direction.y <= 0.0 {
            return None;
        }
        let zenith_degrees = 90.0 - self.elevation_degrees as f64;
        let air_mass = 1.0
            / ((90.0 - zenith_degrees).to_radians().sin()
                + 0.50572 * (96.07995 - zenith_degrees).powf(-1.6364));
        let t = self.turbidity();
        let beta = 0.04608 * t - 0.04586;
        let transmittance = CHANNEL_WAVELENGTHS.map(|lambda| {
            let rayleigh = (-0.008735 * lambda.powf(-4.08) * air_mass).exp();
            let aerosol = (-beta * lambda.powf(-1.3) * air_mass).exp();
            rayleigh * aerosol
        });
        let sin_r = SUN_ANGULAR_RADIUS.sin();
        // A uniform disc of radiance L gives L pi sin^2(r) at normal incidence.
        let luminance =
            SOLAR_ILLUMINANCE / (std::f64::consts::PI * sin_r * sin_r) / LUMENS_PER_WATT;
        let (x, y) = planckian_xy(SUN_TEMPERATURE);
        let white = xyy_to_srgb(x, y, 1.0);
        let radiance = [0, 1, 2].map(|c| (white[c] * luminance * transmittance[c]) as f32);
        Some(SunDisc {
            direction,
            one_minus_cos: (2.0 * (SUN_ANGULAR_RADIUS * 0.5).sin().powi(2)) as f32,
            radiance,
        })
    }
}

/// Perez et al.'s all-weather sky luminance distribution, F(theta, gamma).
fn perez(c: [f64; 5], theta: f64, gamma: f64) -> f64 {
    let cos_theta = theta.cos().max(1e-3);
    (1.0 + c[0] * (c[1] / cos_theta).exp())
        * (1.0 + c[2] * (c[3] * gamma).exp() + c[4] * gamma.cos().powi(2))
}

/// The three distributions of the model: luminance Y and chromaticities x and y.
#[derive(Clone, Copy)]
enum PerezChannel {
    Y,
    X,
    Y2,
}

impl PerezChannel {
    /// The paper's linear fits of the Perez coefficients A..E in turbidity.
    fn coefficients(self, t: f64) -> [f64; 5] {
        match self {
            Self::Y => [
                0.1787 * t - 1.4630,
                -0.3554 * t + 0.4275,
                -0.0227 * t + 5.3251,
                0.1206 * t - 2.5771,
                -0.0670 * t + 0.3703,
            ],
            Self::X => [
                -0.0193 * t - 0.2592,
                -0.0665 * t + 0.0008,
                -0.0004 * t + 0.2125,
                -0.0641 * t - 0.8989,
                -0.0033 * t + 0.0452,
            ],
            Self::Y2 => [
                -0.0167 * t - 0.2608,
                -0.0950 * t + 0.0092,
                -0.0079 * t + 0.2102,
                -0.0441 * t - 1.6537,
                -0.0109 * t + 0.0529,
            ],
        }
    }

    /// Zenith luminance (kcd/m^2) or chromaticity for the sun at zenith angle `theta_s`.
    fn zenith(self, t: f64, theta_s: f64) -> f64 {
        let s = [theta_s.powi(3), theta_s.powi(2), theta_s, 1.0];
        let poly = |m: [[f64; 4]; 3]| {
            let row = |r: [f64; 4]| r.iter().zip(&s).map(|(a, b)| a * b).sum::<f64>();
            t * t * row(m[0]) + t * row(m[1]) + row(m[2])
        };
        match self {
            Self::Y => {
                let chi = (4.0 / 9.0 - t / 120.0) * (std::f64::consts::PI - 2.0 * theta_s);
                ((4.0453 * t - 4.9710) * chi.tan() - 0.2155 * t + 2.4192).max(0.0)
            }
            Self::X => poly([
                [0.00166, -0.00375, 0.00209, 0.0],
                [-0.02903, 0.06377, -0.03202, 0.00394],
                [0.11693, -0.21196, 0.06052, 0.25886],
            ]),
            Self::Y2 => poly([
                [0.00275, -0.00610, 0.00317, 0.0],
                [-0.04214, 0.08970, -0.04153, 0.00516],
                [0.15346, -0.26756, 0.06670, 0.26688],
            ]),
        }
    }
}

/// CIE xyY to linear sRGB (D65), negative components clipped.
fn xyy_to_srgb(x: f64, y: f64, luminance: f64) -> [f64; 3] {
    let big_x = x / y * luminance;
    let big_z = (1.0 - x - y) / y * luminance;
    [
        3.2404542 * big_x - 1.5371385 * luminance - 0.4985314 * big_z,
        -0.9692660 * big_x + 1.8760108 * luminance + 0.0415560 * big_z,
        0.0556434 * big_x - 0.2040259 * luminance + 1.0572252 * big_z,
    ]
    .map(|c| c.max(0.0))
}

/// Chromaticity of a black body at `kelvin` (Kim et al. 2002 cubic fit, 4000-25000 K).
fn planckian_xy(kelvin: f64) -> (f64, f64) {
    let t = kelvin;
    let x = -3.0258469e9 / t.powi(3) + 2.1070379e6 / t.powi(2) + 0.2226347e3 / t + 0.240390;
    let y = 3.0817580 * x.powi(3) - 5.87338670 * x.powi(2) + 3.75112997 * x - 0.37001483;
    (x, y)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(elevation: f32) -> SunSkyParams {
        SunSkyParams {
            elevation_degrees: elevation,
            azimuth_degrees: 30.0,
            turbidity: 3.0,
        }
    }

    #[test]
    fn sun_chromaticity_is_the_5778k_black_body() {
        let (x, y) = planckian_xy(5778.0);
        assert!(
            (x - 0.3264).abs() < 2e-3 && (y - 0.3357).abs() < 2e-3,
            "{x} {y}"
        );
    }

    #[test]
    fn high_sun_gives_daylight_illuminance() {
        // Direct normal illuminance of a clear high sun is roughly 80-110 klux.
        let sun = params(60.0).sun().expect("above the horizon");
        let lum = 0.2126 * sun.radiance[0] + 0.7152 * sun.radiance[1] + 0.0722 * sun.radiance[2];
        let solid_angle = 2.0 * std::f32::consts::PI * sun.one_minus_cos;
        let lux = lum * solid_angle * LUMENS_PER_WATT as f32;
        assert!((70_000.0..120_000.0).contains(&lux), "{lux} lux");
        // Redder than blue after the atmosphere.
        assert!(sun.radiance[0] > sun.radiance[2]);
        // A low sun is dimmer and redder.
        let low = params(5.0).sun().unwrap();
        assert!(low.radiance[1] < sun.radiance[1]);
        assert!(low.radiance[2] / low.radiance[0] < sun.radiance[2] / sun.radiance[0]);
        assert!(params(-3.0).sun().is_none());
    }

    #[test]
    fn sky_is_blue_at_the_zenith_black_below_and_brighter_near_the_sun() {
        let p = params(40.0);
        let zenith = p.sky_radiance(Vec3::Y);
        assert!(zenith[2] > zenith[0], "{zenith:?}");
        // A clear zenith is a few kcd/m^2.
        let lum = 0.2126 * zenith[0] + 0.7152 * zenith[1] + 0.0722 * zenith[2];
        assert!((1.0..30.0).contains(&lum), "{lum}");
        assert_eq!(p.sky_radiance(Vec3::NEG_Y), [0.0; 3]);
        let sun = p.sun_direction();
        let near = p.sky_radiance((sun + Vec3::new(0.0, 0.05, 0.0)).normalize());
        let away = p.sky_radiance((-sun + Vec3::new(0.0, 1.5, 0.0)).normalize());
        assert!(near[1] > away[1]);
    }
}
