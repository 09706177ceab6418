//! Keyframe sampling of glTF animation channels (STEP, LINEAR with slerp, CUBICSPLINE).

use crate::scene::{AnimationChannel, ChannelValues, Interpolation};
use glam::{Quat, Vec3};

/// A sampled channel value.
#[derive(Clone, Debug, PartialEq)]
pub enum Sampled {
    Translation(Vec3),
    Rotation(Quat),
    Scale(Vec3),
    Weights(Vec<f32>),
}

/// Rejects channels that would sample to NaN or index out of range: empty or non-finite times,
/// times not strictly increasing, value counts that do not match the keyframes, non-finite values.
pub fn validate_channel(c: &AnimationChannel) -> Result<(), String> {
    if c.times.is_empty() {
        return Err("no keyframes".into());
    }
    if c.times.iter().any(|t| !t.is_finite()) {
        return Err("non-finite keyframe time".into());
    }
    if c.times.windows(2).any(|w| w[1] <= w[0]) {
        return Err("keyframe times are not strictly increasing".into());
    }
    let per_key = if c.interpolation == Interpolation::CubicSpline { 3 } else { 1 };
    let keys = c.times.len() * per_key;
    let (len, finite) = match &c.values {
        ChannelValues::Translation(v) | ChannelValues::Scale(v) => (v.len(), v.iter().all(|x| x.is_finite())),
        ChannelValues::Rotation(v) => (v.len(), v.iter().all(|x| x.is_finite())),
        ChannelValues::Weights { values, count } => {
            if *count == 0 || values.len() != keys * count {
                return Err(format!("{} weight values do not fill {} keyframes", values.len(), keys));
            }
            (keys, values.iter().all(|x| x.is_finite()))
        }
    };
    if len != keys {
        return Err(format!("{len} values for {} keyframes (sampler/accessor count mismatch)", c.times.len()));
    }
    if !finite {
        return Err("NaN or infinite keyframe value".into());
    }
    Ok(())
}

/// Where `t` falls: keyframe index `i` and the fraction towards `i + 1` (clamped to the first/last key).
fn locate(times: &[f32], t: f32) -> (usize, f32, f32) {
    let last = times.len() - 1;
    if t <= times[0] || last == 0 {
        return (0, 0.0, 0.0);
    }
    if t >= times[last] {
        return (last, 0.0, 0.0);
    }
    let i = times.partition_point(|&k| k <= t) - 1;
    let dt = times[i + 1] - times[i];
    (i, (t - times[i]) / dt, dt)
}

/// Cubic Hermite spline between keys i and i+1; `get(k)` gives (in-tangent, value, out-tangent) of key k.
fn hermite<T>(s: f32, dt: f32, p0: T, m0: T, p1: T, m1: T) -> T
where
    T: std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
{
    let (s2, s3) = (s * s, s * s * s);
    p0 * (2.0 * s3 - 3.0 * s2 + 1.0) + m0 * ((s3 - 2.0 * s2 + s) * dt) + p1 * (-2.0 * s3 + 3.0 * s2) + m1 * ((s3 - s2) * dt)
}

fn sample_vec3(interp: Interpolation, times: &[f32], v: &[Vec3], t: f32) -> Vec3 {
    let (i, s, dt) = locate(times, t);
    match interp {
        Interpolation::CubicSpline => {
            if s == 0.0 {
                return v[3 * i + 1];
            }
            hermite(s, dt, v[3 * i + 1], v[3 * i + 2], v[3 * (i + 1) + 1], v[3 * (i + 1)])
        }
        Interpolation::Step => v[i],
        Interpolation::Linear => {
            if s == 0.0 { v[i] } else { v[i].lerp(v[i + 1], s) }
        }
    }
}

fn sample_quat(interp: Interpolation, times: &[f32], v: &[Quat], t: f32) -> Quat {
    let (i, s, dt) = locate(times, t);
    let q = match interp {
        Interpolation::CubicSpline => {
            if s == 0.0 {
                v[3 * i + 1]
            } else {
                let [a, b, c, d] = [v[3 * i + 1], v[3 * i + 2], v[3 * (i + 1) + 1], v[3 * (i + 1)]].map(glam::Vec4::from);
                Quat::from_vec4(hermite(s, dt, a, b, c, d))
            }
        }
        Interpolation::Step => v[i],
        Interpolation::Linear => {
            if s == 0.0 { v[i] } else { slerp_shortest(v[i], v[i + 1], s) }
        }
    };
    let len = q.length();
    if len > 0.0 && len.is_finite() { q / len } else { Quat::IDENTITY }
}

/// Spherical interpolation along the shorter arc (glTF: "slerp"), exact for nearly parallel keys too.
pub fn slerp_shortest(a: Quat, b: Quat, s: f32) -> Quat {
    let mut b = b;
    let mut d = a.dot(b);
    if d < 0.0 {
        b = -b;
        d = -d;
    }
    if d > 0.9995 {
        return a.lerp(b, s).normalize();
    }
    let theta = d.clamp(-1.0, 1.0).acos();
    let sin = theta.sin();
    a * (((1.0 - s) * theta).sin() / sin) + b * ((s * theta).sin() / sin)
}

fn sample_weights(interp: Interpolation, times: &[f32], v: &[f32], count: usize, t: f32) -> Vec<f32> {
    let (i, s, dt) = locate(times, t);
    let key = |k: usize, part: usize| -> &[f32] {
        let stride = if interp == Interpolation::CubicSpline { 3 } else { 1 };
        let start = (k * stride + part) * count;
        &v[start..start + count]
    };
    match interp {
        Interpolation::Step => key(i, 0).to_vec(),
        Interpolation::Linear => {
            if s == 0.0 {
                return key(i, 0).to_vec();
            }
            key(i, 0).iter().zip(key(i + 1, 0)).map(|(a, b)| a + (b - a) * s).collect()
        }
        Interpolation::CubicSpline => {
            if s == 0.0 {
                return key(i, 1).to_vec();
            }
            (0..count)
                .map(|w| hermite(s, dt, key(i, 1)[w], key(i, 2)[w], key(i + 1, 1)[w], key(i + 1, 0)[w]))
                .collect()
        }
    }
}

/// The channel's value at `t` seconds; `t` is clamped to the channel's keyframe range.
pub fn sample_channel(c: &AnimationChannel, t: f32) -> Sampled {
    match &c.values {
        ChannelValues::Translation(v) => Sampled::Translation(sample_vec3(c.interpolation, &c.times, v, t)),
        ChannelValues::Scale(v) => Sampled::Scale(sample_vec3(c.interpolation, &c.times, v, t)),
        ChannelValues::Rotation(v) => Sampled::Rotation(sample_quat(c.interpolation, &c.times, v, t)),
        ChannelValues::Weights { values, count } => {
            Sampled::Weights(sample_weights(c.interpolation, &c.times, values, *count, t))
        }
    }
}

/// Animation players (issue 3 fills this in).
pub struct AnimationPlugin;

impl bevy_app::Plugin for AnimationPlugin {
    fn build(&self, _app: &mut bevy_app::App) {}
}
