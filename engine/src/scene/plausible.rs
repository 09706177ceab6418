//! Material factors a path tracer can render. glTF bounds the colour factors to [0, 1] and emission must be
//! finite: a negative base colour would give negative radiance, and an emitter of 3.4e38 overflows the
//! emitter sampling sums to infinity (a black or NaN image). Such values are clamped, each with a warning,
//! never silently.

use super::Material;
use glam::{Vec3, Vec4};

/// Brightest emitted radiance per channel (emissiveFactor x emissiveStrength). Sums of squared sample
/// luminances (the denoiser's variance) stay far inside f32 below it, even through importance-sampling
/// weights of 1e6; it is brighter than any display-referred scene needs.
pub const MAX_EMITTED_RADIANCE: f32 = 1e8;

/// Clamps `m`'s factors into their valid ranges; returns one note per change.
pub(super) fn clamp_factors(m: &mut Material) -> Vec<String> {
    let mut notes = Vec::new();
    let base = m.base_color;
    if !base.is_finite() {
        m.base_color = Vec4::ONE;
        notes.push(format!("baseColorFactor {base} is not finite; 1 used"));
    } else if base.min_element() < 0.0 || base.max_element() > 1.0 {
        m.base_color = base.clamp(Vec4::ZERO, Vec4::ONE);
        notes.push(format!(
            "baseColorFactor {base} is outside [0, 1]; clamped to {}",
            m.base_color
        ));
    }
    for (what, value) in [
        ("metallicFactor", &mut m.metallic),
        ("roughnessFactor", &mut m.roughness),
    ] {
        let v = *value;
        if !v.is_finite() {
            *value = 1.0;
            notes.push(format!("{what} {v} is not finite; 1 used"));
        } else if !(0.0..=1.0).contains(&v) {
            *value = v.clamp(0.0, 1.0);
            notes.push(format!(
                "{what} {v} is outside [0, 1]; clamped to {}",
                *value
            ));
        }
    }
    let factor = m.emissive;
    if factor.is_nan() {
        m.emissive = Vec3::ZERO;
        notes.push(format!(
            "emissiveFactor {factor} is not a number; no emission"
        ));
    } else if factor.min_element() < 0.0 {
        m.emissive = factor.max(Vec3::ZERO);
        notes.push(format!(
            "emissiveFactor {factor} is negative; clamped to {}",
            m.emissive
        ));
    }
    let strength = m.emissive_strength;
    if strength.is_nan() || strength < 0.0 {
        m.emissive_strength = if strength.is_nan() { 1.0 } else { 0.0 };
        notes.push(format!(
            "emissiveStrength {strength} is {}; {} used",
            if strength.is_nan() {
                "not a number"
            } else {
                "negative"
            },
            m.emissive_strength
        ));
    }
    // Infinite factors and strengths land here too (0 x infinity is NaN: no emission in that channel).
    let radiance = m.emissive * m.emissive_strength;
    if !radiance.is_finite() || radiance.max_element() > MAX_EMITTED_RADIANCE {
        let capped = if radiance.is_finite() {
            radiance * (MAX_EMITTED_RADIANCE / radiance.max_element())
        } else {
            radiance.map(|c| match c {
                c if c.is_nan() => 0.0,
                c => c.min(MAX_EMITTED_RADIANCE),
            })
        };
        m.emissive = capped / MAX_EMITTED_RADIANCE;
        m.emissive_strength = MAX_EMITTED_RADIANCE;
        notes.push(format!(
            "emitted radiance {radiance} (emissiveFactor x emissiveStrength) is over the {MAX_EMITTED_RADIANCE:e} \
             limit; capped to {capped}"
        ));
    }
    notes
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clamped(m: Material) -> (Material, Vec<String>) {
        let mut m = m;
        let notes = clamp_factors(&mut m);
        (m, notes)
    }

    #[test]
    fn valid_factors_pass_unchanged_and_silently() {
        let m = Material {
            base_color: Vec4::new(0.2, 0.4, 1.0, 0.5),
            emissive: Vec3::new(1.0, 0.5, 0.0),
            emissive_strength: 1000.0,
            ..Default::default()
        };
        let (out, notes) = clamped(m.clone());
        assert_eq!(out, m);
        assert!(notes.is_empty(), "{notes:?}");
    }

    #[test]
    fn negative_and_infinite_factors_are_clamped_with_a_note_each() {
        let (m, notes) = clamped(Material {
            base_color: Vec4::new(-1.0, 0.5, 2.0, 1.0),
            emissive: Vec3::new(3.4e38, -1.0, 0.0),
            emissive_strength: f32::INFINITY,
            ..Default::default()
        });
        assert_eq!(m.base_color, Vec4::new(0.0, 0.5, 1.0, 1.0));
        let radiance = m.emitted_radiance();
        assert!(radiance.is_finite(), "{radiance}");
        assert_eq!(radiance, Vec3::new(MAX_EMITTED_RADIANCE, 0.0, 0.0));
        assert_eq!(notes.len(), 3, "{notes:?}");
    }

    #[test]
    fn a_huge_finite_product_keeps_its_hue() {
        let (m, notes) = clamped(Material {
            emissive: Vec3::new(1.0, 0.5, 0.25),
            emissive_strength: 1e38,
            ..Default::default()
        });
        let r = m.emitted_radiance();
        assert!(
            (r.x - MAX_EMITTED_RADIANCE).abs() / MAX_EMITTED_RADIANCE < 1e-6,
            "{r}"
        );
        assert!((r.y / r.x - 0.5).abs() < 1e-6 && (r.z / r.x - 0.25).abs() < 1e-6);
        assert_eq!(notes.len(), 1);
    }
}
