//! KHR_texture_transform: an affine map applied to a texture slot's UVs before sampling.

use glam::{Mat3, Vec2};

/// Offset, rotation and scale of one texture slot's UVs (identity without the extension).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureTransform {
    pub offset: Vec2,
    /// Radians, counter-clockwise in UV space (the image turns clockwise).
    pub rotation: f32,
    pub scale: Vec2,
    /// The extension's `texCoord`, if it overrides the slot's set (already applied to
    /// [`super::TextureRef::tex_coord`]; kept so a saved file says the same).
    pub tex_coord: Option<u32>,
}

impl Default for TextureTransform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl TextureTransform {
    pub const IDENTITY: Self = Self {
        offset: Vec2::ZERO,
        rotation: 0.0,
        scale: Vec2::ONE,
        tex_coord: None,
    };

    /// True when UVs pass through unchanged.
    pub fn is_identity(&self) -> bool {
        self.offset == Vec2::ZERO && self.rotation == 0.0 && self.scale == Vec2::ONE
    }

    /// The spec's `translation * rotation * scale`, for column vectors `(u, v, 1)`. The spec's rotation is
    /// the GLSL `mat3(cos, sin, 0, -sin, cos, 0, 0, 0, 1)` written row by row, i.e. rows `(cos, sin)` and
    /// `(-sin, cos)`: with v pointing down the image, a positive angle turns the image clockwise.
    pub fn matrix(&self) -> Mat3 {
        let (s, c) = self.rotation.sin_cos();
        let translation = Mat3::from_translation(self.offset);
        // glam takes columns: column 0 = (cos, -sin), column 1 = (sin, cos).
        let rotation = Mat3::from_cols_array(&[c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0]);
        let scale = Mat3::from_scale(self.scale);
        translation * rotation * scale
    }

    /// The transformed UV.
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        self.matrix().transform_point2(uv)
    }

    /// The 2x3 affine rows `[a, b, c, d, e, f]` with `u' = a u + b v + c`, `v' = d u + e v + f` (the layout
    /// proposed for the GPU).
    pub fn affine_rows(&self) -> [f32; 6] {
        let m = self.matrix();
        [
            m.x_axis.x, m.y_axis.x, m.z_axis.x, m.x_axis.y, m.y_axis.y, m.z_axis.y,
        ]
    }

    /// Reads the extension object of a textureInfo; non-finite numbers fall back to the identity's values.
    /// Returns the transform and a note when a value was replaced.
    pub fn from_json(value: &serde_json::Value) -> (Self, Option<String>) {
        let mut replaced = Vec::new();
        let mut pair = |name: &str, default: Vec2| -> Vec2 {
            let Some(v) = value.get(name) else {
                return default;
            };
            match v.as_array().map(|a| {
                a.iter()
                    .map(|x| x.as_f64().map(|x| x as f32))
                    .collect::<Option<Vec<f32>>>()
            }) {
                Some(Some(a)) if a.len() == 2 && a.iter().all(|x| x.is_finite()) => {
                    Vec2::new(a[0], a[1])
                }
                _ => {
                    replaced.push(name.to_string());
                    default
                }
            }
        };
        let offset = pair("offset", Vec2::ZERO);
        let scale = pair("scale", Vec2::ONE);
        let rotation = match value.get("rotation").map(|r| r.as_f64().map(|r| r as f32)) {
            None => 0.0,
            Some(Some(r)) if r.is_finite() => r,
            Some(_) => {
                replaced.push("rotation".into());
                0.0
            }
        };
        let tex_coord = value
            .get("texCoord")
            .and_then(serde_json::Value::as_u64)
            .map(|t| t as u32);
        let note = (!replaced.is_empty()).then(|| {
            format!(
                "KHR_texture_transform {}: not finite numbers of the right count; the identity's value used",
                replaced.join(", ")
            )
        });
        (
            Self {
                offset,
                rotation,
                scale,
                tex_coord,
            },
            note,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::FRAC_PI_2;

    fn close(a: Vec2, b: Vec2) -> bool {
        (a - b).abs().max_element() < 1e-6
    }

    #[test]
    fn identity_passes_uvs_through() {
        let t = TextureTransform::IDENTITY;
        assert!(t.is_identity());
        assert_eq!(t.apply(Vec2::new(0.3, 0.7)), Vec2::new(0.3, 0.7));
    }

    #[test]
    fn scale_then_rotate_then_offset() {
        // Order check: with offset (1, 0), rotation 90 degrees and scale (2, 1), the point (1, 0) scales to
        // (2, 0), rotates to (0, -2) (rows (cos, sin), (-sin, cos)), then moves to (1, -2).
        let t = TextureTransform {
            offset: Vec2::new(1.0, 0.0),
            rotation: FRAC_PI_2,
            scale: Vec2::new(2.0, 1.0),
            tex_coord: None,
        };
        assert!(close(t.apply(Vec2::new(1.0, 0.0)), Vec2::new(1.0, -2.0)));
        assert!(close(t.apply(Vec2::new(0.0, 1.0)), Vec2::new(2.0, 0.0)));
        let [a, b, c, d, e, f] = t.affine_rows();
        let uv = Vec2::new(0.25, 0.5);
        let by_rows = Vec2::new(a * uv.x + b * uv.y + c, d * uv.x + e * uv.y + f);
        assert!(close(by_rows, t.apply(uv)));
    }

    #[test]
    fn spec_example_picks_the_lower_left_quadrant() {
        // The spec's example: offset (0, 1), rotation pi/2, scale 0.5 shows the lower-left quadrant of the
        // image turned clockwise: every UV of the unit square lands in u in [0, 0.5], v in [0.5, 1].
        let (t, note) = TextureTransform::from_json(&serde_json::json!({
            "offset": [0, 1], "rotation": FRAC_PI_2, "scale": [0.5, 0.5]
        }));
        assert!(note.is_none());
        for (u, v) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.5, 0.5)] {
            let p = t.apply(Vec2::new(u, v));
            assert!((-1e-6..=0.5 + 1e-6).contains(&p.x), "{p}");
            assert!((0.5 - 1e-6..=1.0 + 1e-6).contains(&p.y), "{p}");
        }
        // Clockwise: the image's top-left corner (uv 0,0) is shown at the top-right of the surface (uv 1,0).
        assert!(close(t.apply(Vec2::new(1.0, 0.0)), Vec2::new(0.0, 0.5)));
    }

    #[test]
    fn spec_example_flips_t() {
        let (t, _) =
            TextureTransform::from_json(&serde_json::json!({"offset": [0, 1], "scale": [1, -1]}));
        assert!(close(t.apply(Vec2::new(0.2, 0.0)), Vec2::new(0.2, 1.0)));
        assert!(close(t.apply(Vec2::new(0.2, 0.75)), Vec2::new(0.2, 0.25)));
    }

    #[test]
    fn bad_numbers_fall_back_with_a_note() {
        let (t, note) = TextureTransform::from_json(
            &serde_json::json!({"offset": [1, "x"], "rotation": "a", "scale": [2, 3], "texCoord": 1}),
        );
        assert_eq!(t.offset, Vec2::ZERO);
        assert_eq!(t.rotation, 0.0);
        assert_eq!(t.scale, Vec2::new(2.0, 3.0));
        assert_eq!(t.tex_coord, Some(1));
        let note = note.unwrap();
        assert!(
            note.contains("offset") && note.contains("rotation"),
            "{note}"
        );
    }
}
