//! Equirectangular (latitude-longitude) radiance maps: loading `.hdr` / `.exr`, and the direction <-> texel
//! convention, which is exactly Mitsuba 3's `envmap` emitter with an identity `to_world` (+Y up):
//!
//! - a local direction `d` has `u = atan2(d.x, -d.z) / 2pi` (wrapped into [0, 1)) and `v = acos(d.y) / pi`;
//!   so `u = 0` looks down -Z, `u = 1/4` down +X, `u = 1/2` down +Z, `u = 3/4` down -X, and `v = 0` is +Y;
//! - texel column `i` sits at `u = (i + 1/2) / W` (the map wraps around in u), texel row `j` at
//!   `v = j / (H - 1)`: the first row is the +Y pole and the last the -Y pole;
//! - radiance between texels is bilinear (the lattice of texel positions above).
//!
//! A rotation of `a` degrees about +Y (`--env-rotation`) is Mitsuba's `to_world = rotate([0, 1, 0], a)`.

use glam::Vec3;
use std::path::{Path, PathBuf};

/// A radiance map: linear RGB texels, row-major from the +Y pole down, never fewer than 2 rows.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentMap {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<[f32; 3]>,
}

#[derive(Debug, thiserror::Error)]
pub enum EnvironmentError {
    #[error("{path}: cannot read the environment map: {reason}")]
    Read { path: PathBuf, reason: String },
    #[error(
        "{path}: not an equirectangular radiance map raykin can read ({reason}); use a .hdr (Radiance RGBE) or .exr file"
    )]
    Decode { path: PathBuf, reason: String },
}

impl EnvironmentMap {
    /// A map from texels; a single row is repeated (the lattice needs two rows, one per pole).
    ///
    /// # Panics
    /// When `texels` does not hold `width * height` values or a size is zero.
    pub fn new(width: u32, height: u32, texels: Vec<[f32; 3]>) -> Self {
        assert!(width > 0 && height > 0, "an environment map needs texels");
        assert_eq!(texels.len(), (width * height) as usize);
        if height == 1 {
            let mut rows = texels.clone();
            rows.extend_from_slice(&texels);
            return Self {
                width,
                height: 2,
                texels: rows,
            };
        }
        Self {
            width,
            height,
            texels,
        }
    }

    /// The same radiance from every direction.
    pub fn constant(rgb: [f32; 3]) -> Self {
        Self::new(1, 2, vec![rgb; 2])
    }

    /// Reads a `.hdr` or `.exr` file (any format the `image` crate decodes, converted to linear f32 RGB;
    /// 8-bit formats are taken as sRGB-encoded). Negative and non-finite texels become 0, with a note.
    pub fn load(path: &Path) -> Result<(Self, Vec<String>), EnvironmentError> {
        let bytes = std::fs::read(path).map_err(|e| EnvironmentError::Read {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        let decode_err = |reason: String| EnvironmentError::Decode {
            path: path.to_path_buf(),
            reason,
        };
        let format = image::guess_format(&bytes)
            .or_else(|_| image::ImageFormat::from_path(path))
            .map_err(|e| decode_err(e.to_string()))?;
        let image = image::load_from_memory_with_format(&bytes, format)
            .map_err(|e| decode_err(e.to_string()))?;
        let float_source = matches!(
            image.color(),
            image::ColorType::Rgb32F | image::ColorType::Rgba32F
        );
        let rgb = image.to_rgb32f();
        let (width, height) = rgb.dimensions();
        if width == 0 || height == 0 {
            return Err(decode_err("the image has no pixels".into()));
        }
        let mut notes = Vec::new();
        let mut repaired = 0usize;
        let texels = rgb
            .pixels()
            .map(|p| {
                p.0.map(|c| {
                    let c = if float_source { c } else { srgb_decode(c) };
                    if c.is_finite() && c >= 0.0 {
                        c
                    } else {
                        repaired += 1;
                        0.0
                    }
                })
            })
            .collect();
        if repaired > 0 {
            notes.push(format!(
                "{}: {repaired} negative or non-finite texel values set to 0",
                path.display()
            ));
        }
        if !float_source {
            notes.push(format!(
                "{}: an 8-bit image holds no high dynamic range; decoded as sRGB, radiance at most 1",
                path.display()
            ));
        }
        Ok((Self::new(width, height, texels), notes))
    }

    /// Halves the resolution (2x2 box filter; odd sizes keep their last row or column) until the GPU copy
    /// (`bytes_per_texel` each) fits `limit` bytes; returns how many times it halved.
    pub fn fit_to(&mut self, bytes_per_texel: u64, limit: u64) -> u32 {
        let mut halvings = 0;
        while (self.width as u64 * self.height as u64) * bytes_per_texel > limit
            && (self.width > 1 || self.height > 2)
        {
            let (w, h) = (self.width.div_ceil(2), self.height.div_ceil(2).max(2));
            let mut out = Vec::with_capacity((w * h) as usize);
            for y in 0..h {
                for x in 0..w {
                    let mut sum = [0.0f32; 3];
                    let mut n = 0.0;
                    for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        let (sx, sy) = (2 * x + dx, 2 * y + dy);
                        if sx < self.width && sy < self.height {
                            let t = self.texel(sx, sy);
                            (0..3).for_each(|c| sum[c] += t[c]);
                            n += 1.0;
                        }
                    }
                    out.push(sum.map(|s| s / n));
                }
            }
            *self = Self::new(w, h, out);
            halvings += 1;
        }
        halvings
    }

    pub fn texel(&self, x: u32, y: u32) -> [f32; 3] {
        self.texels[(y * self.width + x) as usize]
    }

    /// Bilinear radiance along the map-local direction `d` (the GPU lookup's reference).
    pub fn lookup(&self, d: Vec3) -> [f32; 3] {
        let (u, v) = direction_to_uv(d);
        let (w, h) = (self.width as f32, self.height as f32);
        let x = u * w - 0.5;
        let y = (v * (h - 1.0)).clamp(0.0, h - 1.0);
        let x0 = x.floor();
        let fx = x - x0;
        let j0 = (y.floor() as u32).min(self.height - 2);
        let fy = y - j0 as f32;
        let i0 = (x0 as i64).rem_euclid(self.width as i64) as u32;
        let i1 = (i0 + 1) % self.width;
        let t = |i, j| self.texel(i, j);
        let mut out = [0.0; 3];
        for (c, o) in out.iter_mut().enumerate() {
            let top = t(i0, j0)[c] * (1.0 - fx) + t(i1, j0)[c] * fx;
            let bottom = t(i0, j0 + 1)[c] * (1.0 - fx) + t(i1, j0 + 1)[c] * fx;
            *o = top * (1.0 - fy) + bottom * fy;
        }
        out
    }
}

/// Mitsuba's latitude-longitude coordinates of a unit map-local direction: u in [0, 1), v in [0, 1].
pub fn direction_to_uv(d: Vec3) -> (f32, f32) {
    let u = d.x.atan2(-d.z) * (0.5 / std::f32::consts::PI);
    (
        u - u.floor(),
        d.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI,
    )
}

/// Inverse of [`direction_to_uv`].
pub fn uv_to_direction(u: f32, v: f32) -> Vec3 {
    let (sin_t, cos_t) = (v * std::f32::consts::PI).sin_cos();
    let (sin_p, cos_p) = (u * 2.0 * std::f32::consts::PI).sin_cos();
    Vec3::new(sin_p * sin_t, cos_t, -cos_p * sin_t)
}

/// A world direction in the frame of a map rotated by `degrees` about +Y (Mitsuba's `to_world` inverse).
pub fn world_to_map(d: Vec3, degrees: f32) -> Vec3 {
    let (s, c) = degrees.to_radians().sin_cos();
    Vec3::new(c * d.x - s * d.z, d.y, s * d.x + c * d.z)
}

/// The world direction of a map-local direction (Mitsuba's `to_world = rotate([0, 1, 0], degrees)`).
pub fn map_to_world(d: Vec3, degrees: f32) -> Vec3 {
    world_to_map(d, -degrees)
}

fn srgb_decode(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uv_convention_is_mitsubas() {
        let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
        assert!(close(uv_to_direction(0.0, 0.5), Vec3::NEG_Z));
        assert!(close(uv_to_direction(0.25, 0.5), Vec3::X));
        assert!(close(uv_to_direction(0.5, 0.5), Vec3::Z));
        assert!(close(uv_to_direction(0.75, 0.5), Vec3::NEG_X));
        assert!(close(uv_to_direction(0.3, 0.0), Vec3::Y));
        for (u, v) in [(0.1, 0.2), (0.6, 0.9), (0.9, 0.5)] {
            let (u2, v2) = direction_to_uv(uv_to_direction(u, v));
            assert!((u - u2).abs() < 1e-5 && (v - v2).abs() < 1e-5);
        }
    }

    #[test]
    fn rotation_turns_about_y_like_mitsubas_to_world() {
        // rotate([0,1,0], 90) maps local -Z to world -X (a right-handed turn about +Y).
        let w = map_to_world(Vec3::NEG_Z, 90.0);
        assert!((w - Vec3::NEG_X).length() < 1e-6, "{w}");
        let back = world_to_map(w, 90.0);
        assert!((back - Vec3::NEG_Z).length() < 1e-6);
    }

    #[test]
    fn lookup_hits_texels_at_their_lattice_points() {
        let mut texels = vec![[0.0; 3]; 8 * 5];
        texels[2 * 8 + 3] = [1.0, 2.0, 3.0];
        let map = EnvironmentMap::new(8, 5, texels);
        // Column 3 sits at u = 3.5 / 8, row 2 at v = 2 / 4.
        let d = uv_to_direction(3.5 / 8.0, 0.5);
        let got = map.lookup(d);
        assert!(
            (got[0] - 1.0).abs() < 1e-4 && (got[2] - 3.0).abs() < 1e-4,
            "{got:?}"
        );
        // Half-way to the next column: half the value.
        let half = map.lookup(uv_to_direction(4.0 / 8.0, 0.5));
        assert!((half[1] - 1.0).abs() < 1e-4, "{half:?}");
    }

    #[test]
    fn halving_keeps_the_mean() {
        let texels: Vec<[f32; 3]> = (0..16 * 8).map(|i| [i as f32, 1.0, 0.0]).collect();
        let mut map = EnvironmentMap::new(16, 8, texels);
        let mean = |m: &EnvironmentMap| {
            m.texels.iter().map(|t| t[0] as f64).sum::<f64>() / m.texels.len() as f64
        };
        let before = mean(&map);
        assert_eq!(map.fit_to(16, 16 * 16), 2);
        assert_eq!((map.width, map.height), (4, 2));
        assert!((mean(&map) - before).abs() < 1e-3);
    }
}
