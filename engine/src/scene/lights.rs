//! KHR_lights_punctual: point, spot and directional lights on nodes, as the loader reads them, the ECS
//! component that carries one on its node, and their JSON form for Save as.
//!
//! Units follow the glTF Sample Viewer: the intensity is used directly as the radiometric scale, so a point or
//! spot light has radiant intensity `colour x intensity` (per steradian) and a directional light gives
//! irradiance `colour x intensity` on a surface facing it. A light shines along its node's local -Z; scale is
//! ignored.

use bevy_ecs::prelude::Component;
use glam::Vec3;
use gltf::json::extensions::scene::khr_lights_punctual as json_light;

/// The three punctual light types, with the spot's cone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PunctualKind {
    Point,
    /// Full intensity inside `inner_cone_angle`, none outside `outer_cone_angle` (radians from the axis).
    Spot {
        inner_cone_angle: f32,
        outer_cone_angle: f32,
    },
    Directional,
}

#[derive(Clone, Debug, PartialEq)]
pub struct PunctualLight {
    pub name: String,
    pub kind: PunctualKind,
    /// Linear RGB.
    pub color: Vec3,
    pub intensity: f32,
    /// Distance at which a point or spot light's influence ends (the spec's smooth window); `None`: unbounded.
    pub range: Option<f32>,
}

impl PunctualLight {
    /// Radiant intensity (point, spot: per steradian) or irradiance (directional).
    pub fn scaled_color(&self) -> Vec3 {
        self.color * self.intensity
    }

    /// The spec's recommended range window times inverse-square falloff: `clamp(1 - (d/range)^4, 0, 1) / d^2`
    /// (just `1 / d^2` without a range).
    pub fn distance_falloff(&self, distance: f32) -> f32 {
        let window = match self.range {
            Some(r) if r > 0.0 => (1.0 - (distance / r).powi(4)).clamp(0.0, 1.0),
            _ => 1.0,
        };
        window / (distance * distance)
    }

    /// The spec's smooth angular attenuation of a spot at `cos_angle` from its axis (1 for other kinds):
    /// `saturate(cos_angle * scale + offset)^2` with scale = 1 / max(0.001, cos inner - cos outer) and
    /// offset = -cos outer x scale.
    pub fn angular_falloff(&self, cos_angle: f32) -> f32 {
        let PunctualKind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } = self.kind
        else {
            return 1.0;
        };
        let (cos_inner, cos_outer) = (inner_cone_angle.cos(), outer_cone_angle.cos());
        let scale = 1.0 / (cos_inner - cos_outer).max(0.001);
        let t = (cos_angle * scale - cos_outer * scale).clamp(0.0, 1.0);
        t * t
    }

    /// The light in the KHR_lights_punctual JSON form.
    pub fn to_json(&self) -> json_light::Light {
        let (type_, spot) = match self.kind {
            PunctualKind::Point => (json_light::Type::Point, None),
            PunctualKind::Directional => (json_light::Type::Directional, None),
            PunctualKind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => (
                json_light::Type::Spot,
                Some(json_light::Spot {
                    inner_cone_angle,
                    outer_cone_angle,
                }),
            ),
        };
        json_light::Light {
            color: self.color.to_array(),
            extensions: None,
            extras: Default::default(),
            intensity: self.intensity,
            name: (!self.name.is_empty()).then(|| self.name.clone()),
            range: self.range,
            spot,
            type_: gltf::json::validation::Checked::Valid(type_),
        }
    }
}

/// A node's punctual light (a copy the editor may change; the renderer reads it with the node's
/// `GlobalTransform` every frame and re-uploads the light list only when something differs).
#[derive(Component, Clone, Debug, PartialEq)]
pub struct LightSource(pub PunctualLight);

/// Reads the file's lights; values the spec forbids are repaired with a warning (`warn`), never dropped, so
/// node references stay valid.
pub(super) fn read_lights(
    document: &gltf::Document,
    mut warn: impl FnMut(String),
) -> Vec<PunctualLight> {
    let Some(lights) = document.lights() else {
        return Vec::new();
    };
    lights
        .map(|light| {
            let index = light.index();
            let name = light.name().unwrap_or("").to_string();
            let label = format!("KHR_lights_punctual light {index} `{name}`");
            let mut color = Vec3::from(light.color());
            if !color.is_finite() || color.min_element() < 0.0 {
                warn(format!("{label}: colour {color} is not a finite non-negative RGB; white used"));
                color = Vec3::ONE;
            }
            let mut intensity = light.intensity();
            if !intensity.is_finite() || intensity < 0.0 {
                warn(format!("{label}: intensity {intensity} is not a finite non-negative number; the light is off"));
                intensity = 0.0;
            }
            let range = match light.range() {
                Some(r) if !(r.is_finite() && r > 0.0) => {
                    warn(format!("{label}: range {r} must be a positive number; ignored (unbounded)"));
                    None
                }
                r => r,
            };
            let kind = match light.kind() {
                gltf::khr_lights_punctual::Kind::Point => PunctualKind::Point,
                gltf::khr_lights_punctual::Kind::Directional => {
                    if range.is_some() {
                        warn(format!("{label}: a directional light has no range; ignored"));
                    }
                    PunctualKind::Directional
                }
                gltf::khr_lights_punctual::Kind::Spot {
                    inner_cone_angle,
                    outer_cone_angle,
                } => {
                    let (inner, outer) = valid_cone(inner_cone_angle, outer_cone_angle);
                    if (inner, outer) != (inner_cone_angle, outer_cone_angle) {
                        warn(format!(
                            "{label}: spot cone angles inner {inner_cone_angle}, outer {outer_cone_angle} break 0 <= inner < outer <= pi/2; using inner {inner}, outer {outer}"
                        ));
                    }
                    PunctualKind::Spot {
                        inner_cone_angle: inner,
                        outer_cone_angle: outer,
                    }
                }
            };
            PunctualLight {
                name,
                kind,
                color,
                intensity,
                range: range.filter(|_| kind != PunctualKind::Directional),
            }
        })
        .collect()
}

/// The spec requires 0 <= inner < outer <= pi/2; anything else is clamped into that range.
fn valid_cone(inner: f32, outer: f32) -> (f32, f32) {
    let half_pi = std::f32::consts::FRAC_PI_2;
    let outer = if outer.is_finite() {
        outer.clamp(1e-4, half_pi)
    } else {
        std::f32::consts::FRAC_PI_4
    };
    let inner = if inner.is_finite() {
        inner.clamp(0.0, outer)
    } else {
        0.0
    };
    // Equal angles would make a hard edge; the spec's formula already guards the division.
    (if inner >= outer { outer * 0.999 } else { inner }, outer)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spot(inner: f32, outer: f32) -> PunctualLight {
        PunctualLight {
            name: String::new(),
            kind: PunctualKind::Spot {
                inner_cone_angle: inner,
                outer_cone_angle: outer,
            },
            color: Vec3::ONE,
            intensity: 1.0,
            range: None,
        }
    }

    #[test]
    fn spot_falloff_is_one_inside_the_inner_cone_and_zero_outside_the_outer() {
        let s = spot(0.2, 0.5);
        assert_eq!(s.angular_falloff(0.1f32.cos()), 1.0);
        assert_eq!(s.angular_falloff(0.6f32.cos()), 0.0);
        let mid = s.angular_falloff(0.35f32.cos());
        assert!(mid > 0.0 && mid < 1.0);
    }

    #[test]
    fn range_window_ends_at_the_range() {
        let mut p = spot(0.0, 0.5);
        p.kind = PunctualKind::Point;
        assert_eq!(p.distance_falloff(2.0), 0.25);
        p.range = Some(4.0);
        assert!((p.distance_falloff(2.0) - (1.0 - 1.0 / 16.0) / 4.0).abs() < 1e-6);
        assert_eq!(p.distance_falloff(4.0), 0.0);
        assert_eq!(p.distance_falloff(5.0), 0.0);
    }

    #[test]
    fn invalid_cones_are_repaired_into_the_spec_range() {
        assert_eq!(valid_cone(0.1, 0.3), (0.1, 0.3));
        let (i, o) = valid_cone(0.5, 0.3);
        assert!(i < o && o == 0.3);
        let (i, o) = valid_cone(-1.0, 3.0);
        assert_eq!((i, o), (0.0, std::f32::consts::FRAC_PI_2));
    }
}
