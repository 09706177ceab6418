//! White furnace: a sphere with baseColor 1 under a constant environment of 1, max depth 1. Each pixel must
//! equal the glTF BRDF's directional albedo for its view angle, computed here by independent deterministic
//! quadrature of the specification's formulas (not by the renderer's code). The glTF BRDF does not conserve
//! energy, so the expected values are not 1. The gradient furnace does the same under the sky gradient, whose
//! radiance is linear in the direction's height, so each pixel is the BRDF's albedo and first moment.

use crate::common::*;
use raykin::camera::CameraChoice;
use raykin::render::{Environment, RenderSettings};
use raykin::scene::{Material, NodeTransform, procedural};
use std::f64::consts::PI;
use std::sync::Arc;

/// The specification's BRDF times cos(l), for unit vectors in a frame where the normal is +z.
fn brdf_cos(v: [f64; 3], l: [f64; 3], metallic: f64, alpha: f64) -> f64 {
    if l[2] <= 0.0 || v[2] <= 0.0 {
        return 0.0;
    }
    let h = normalize([v[0] + l[0], v[1] + l[1], v[2] + l[2]]);
    let a2 = alpha * alpha;
    let k = h[0] * h[0] + h[1] * h[1] + a2 * h[2] * h[2];
    let d = a2 / (PI * k * k);
    let (nl, nv) = (l[2], v[2]);
    let vis =
        0.5 / (nl * (nv * nv * (1.0 - a2) + a2).sqrt() + nv * (nl * nl * (1.0 - a2) + a2).sqrt());
    let vh = dot(v, h).abs();
    let fw = (1.0 - vh).powi(5);
    let f_dielectric = 0.04 + 0.96 * fw;
    let f_metal = 1.0; // baseColor 1: Schlick with f0 = 1
    let spec = vis * d;
    let dielectric = (1.0 - f_dielectric) / PI + f_dielectric * spec;
    ((1.0 - metallic) * dielectric + metallic * f_metal * spec) * nl
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn normalize(a: [f64; 3]) -> [f64; 3] {
    let l = dot(a, a).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}

/// Directional albedo by the midpoint rule on two substitutions that flatten the integrand: half-vectors
/// distributed as D(h) cos(h) (resolves narrow lobes), and cosine-distributed directions (the diffuse part).
/// Each integrates the whole BRDF with the weight of its own substitution; a partition by a smooth balance
/// heuristic combines them, so neither needs to resolve what the other covers.
pub(crate) fn albedo(mu: f64, metallic: f64, roughness: f64) -> f64 {
    albedo_weighted(mu, metallic, roughness, &|_| 1.0)
}

/// [`albedo`] of the BRDF multiplied by `weight(l)`, l in the frame where the normal is +z and the view
/// direction (sin, 0, mu) (a layer above that dims it per direction, or the light arriving from l).
pub(crate) fn albedo_weighted(
    mu: f64,
    metallic: f64,
    roughness: f64,
    weight: &dyn Fn([f64; 3]) -> f64,
) -> f64 {
    let alpha = (roughness * roughness).max(1e-4);
    let a2 = alpha * alpha;
    let v = [(1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu];
    let (n_theta, n_phi) = (1536usize, 192usize);
    let ndf_pdf_l = |l: [f64; 3]| {
        let h = normalize([v[0] + l[0], v[1] + l[1], v[2] + l[2]]);
        let k = h[0] * h[0] + h[1] * h[1] + a2 * h[2] * h[2];
        let d = a2 / (PI * k * k);
        d * h[2] / (4.0 * dot(v, h).abs())
    };
    let cos_pdf = |l: [f64; 3]| l[2].max(0.0) / PI;
    let mut total = 0.0;
    for i in 0..n_theta {
        let xi = (i as f64 + 0.5) / n_theta as f64;
        for j in 0..n_phi {
            let phi = 2.0 * PI * (j as f64 + 0.5) / n_phi as f64;
            // Half-vector substitution (GGX inverse CDF).
            let cos2 = (1.0 - xi) / (1.0 + (a2 - 1.0) * xi);
            let (ct, st) = (cos2.sqrt(), (1.0 - cos2).max(0.0).sqrt());
            let h = [st * phi.cos(), st * phi.sin(), ct];
            let vh = dot(v, h);
            if vh > 0.0 {
                let l = [
                    2.0 * vh * h[0] - v[0],
                    2.0 * vh * h[1] - v[1],
                    2.0 * vh * h[2] - v[2],
                ];
                if l[2] > 0.0 {
                    let (p1, p2) = (ndf_pdf_l(l), cos_pdf(l));
                    total += brdf_cos(v, l, metallic, alpha) * weight(l) / (p1 + p2);
                }
            }
            // Cosine substitution.
            let l = [
                xi.sqrt() * phi.cos(),
                xi.sqrt() * phi.sin(),
                (1.0 - xi).sqrt(),
            ];
            let (p1, p2) = (ndf_pdf_l(l), cos_pdf(l));
            total += brdf_cos(v, l, metallic, alpha) * weight(l) / (p1 + p2);
        }
    }
    total / (n_theta * n_phi) as f64
}

#[test]
fn quadrature_reproduces_known_albedos() {
    // Near-normal-incidence values quoted in the issue for the glTF BRDF.
    for (m, r, expected) in [(0.0, 1.0, 0.97), (1.0, 0.5, 0.92), (1.0, 1.0, 0.31)] {
        let a = albedo(0.99, m, r);
        assert!(
            (a - expected).abs() < 0.01,
            "albedo(metallic {m}, roughness {r}) = {a}, expected about {expected}"
        );
    }
    // A smooth dielectric gains energy at grazing angles (Schlick Fresnel plus the undiminished diffuse).
    assert!(albedo(0.15, 0.0, 0.05) > 1.0);
}

const SIZE: u32 = 16;
const EYE_Z: f64 = 4.0;
const YFOV_DEG: f64 = 32.0;

/// Expected pixel value: the mean of `radiance(normal, towards the eye)` over a 4x4 grid of sub-pixel rays (the
/// renderer's box filter), or `None` where some ray misses the sphere or meets it at a grazing angle (the
/// tessellation's silhouette).
fn expected_pixel(x: u32, y: u32, radiance: &dyn Fn([f64; 3], [f64; 3]) -> f64) -> Option<f64> {
    let tan = (YFOV_DEG.to_radians() * 0.5).tan();
    let mut sum = 0.0;
    for sy in 0..4 {
        for sx in 0..4 {
            let px = (x as f64 + (sx as f64 + 0.5) / 4.0) / SIZE as f64 * 2.0 - 1.0;
            let py = 1.0 - (y as f64 + (sy as f64 + 0.5) / 4.0) / SIZE as f64 * 2.0;
            let d = normalize([px * tan, py * tan, -1.0]);
            let o = [0.0, 0.0, EYE_Z];
            let b = dot(o, d);
            let disc = b * b - (dot(o, o) - 1.0);
            if disc <= 0.0 {
                return None;
            }
            let t = -b - disc.sqrt();
            let n = [o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]];
            if -dot(n, d) < 0.3 {
                return None;
            }
            sum += radiance(n, [-d[0], -d[1], -d[2]]);
        }
    }
    Some(sum / 16.0)
}

/// `f` on 57 cosines from 0.2 to 1, linear in between.
fn table_of_cosines(f: impl Fn(f64) -> f64) -> impl Fn(f64) -> f64 {
    let table: Vec<(f64, f64)> = (0..=56)
        .map(|i| {
            let mu = 0.2 + 0.8 * i as f64 / 56.0;
            (mu, f(mu))
        })
        .collect();
    move |mu| {
        let i = table
            .partition_point(|(m, _)| *m < mu)
            .clamp(1, table.len() - 1);
        let ((m0, a0), (m1, a1)) = (table[i - 1], table[i]);
        a0 + (a1 - a0) * (mu - m0) / (m1 - m0)
    }
}

fn furnace_case(metallic: f32, roughness: f32) {
    let material = Material {
        name: "white".into(),
        metallic,
        roughness,
        ..Default::default()
    };
    furnace_check(
        &format!("metallic {metallic} roughness {roughness}"),
        material,
        |mu| albedo(mu, metallic as f64, roughness as f64),
        16384,
    );
}

/// Renders a unit sphere of `material` in the white furnace (max depth 1) and checks every interior pixel
/// against `albedo(cos(view))` (computed by the caller from the specification), within 1% where the noise allows
/// (at most `max_spp` samples per half; the per-pixel bound widens to 4 sigma of what noise remains).
pub(crate) fn furnace_check(
    what: &str,
    material: Material,
    albedo: impl Fn(f64) -> f64,
    max_spp: u32,
) {
    let albedo = table_of_cosines(albedo);
    let radiance = |n: [f64; 3], v: [f64; 3]| albedo(dot(n, v));
    sphere_check(
        what,
        material,
        Environment::Constant([1.0; 3]),
        1,
        &radiance,
        max_spp,
    );
}

/// Renders a unit sphere of `material` lit by `environment` alone (max depth 1) and checks channel `channel` of
/// every interior pixel against `radiance(normal, towards the eye)`, as [`furnace_check`] describes.
fn sphere_check(
    what: &str,
    material: Material,
    environment: Environment,
    channel: usize,
    radiance: &dyn Fn([f64; 3], [f64; 3]) -> f64,
    max_spp: u32,
) {
    let (ctx, _gpu) = gpu();
    let sphere = procedural::uv_sphere(1.0, 128, 64, 0);
    let scene = Arc::new(procedural::scene_from_meshes(
        "furnace",
        vec![(sphere, NodeTransform::default())],
        vec![material],
    ));
    let settings = |seed| RenderSettings {
        width: SIZE,
        height: SIZE,
        max_depth: 1,
        environment: environment.clone(),
        russian_roulette: false,
        seed,
        ..Default::default()
    };
    let camera = CameraChoice::LookAt {
        eye: glam::Vec3::new(0.0, 0.0, EYE_Z as f32),
        target: glam::Vec3::ZERO,
        yfov: (YFOV_DEG as f32).to_radians(),
    };

    // Two independent halves; more samples until the estimated per-pixel noise is a quarter of the tolerance.
    // Each round adds as many samples as the halves hold (new seeds), so the total doubles without re-rendering.
    let pixels = (SIZE * SIZE) as usize;
    let (mut a, mut b) = (vec![[0.0f32; 3]; pixels], vec![[0.0f32; 3]; pixels]);
    let mut spp = 0;
    for round in 0u32.. {
        let add = spp.max(2048);
        let fold = |sum: &mut Vec<[f32; 3]>, seed: u32| {
            let more = render(&ctx, &scene, settings(seed), &camera, add);
            assert_all_finite(&more, "furnace");
            let w = add as f32 / (spp + add) as f32;
            for (s, m) in sum.iter_mut().zip(&more) {
                for c in 0..3 {
                    s[c] += (m[c] - s[c]) * w;
                }
            }
        };
        fold(&mut a, 11 + 100 * round);
        fold(&mut b, 22 + 100 * round);
        spp += add;
        let mut worst = (0.0f64, 0u32, 0u32, 0.0, 0.0);
        let mut ratio_sum = 0.0f64;
        let mut sigma2_sum = 0.0f64;
        let mut checked = 0;
        for y in 0..SIZE {
            for x in 0..SIZE {
                let Some(expected) = expected_pixel(x, y, radiance) else {
                    continue;
                };
                let i = (y * SIZE + x) as usize;
                let (va, vb) = (a[i][channel] as f64, b[i][channel] as f64);
                let value = 0.5 * (va + vb);
                // Var(mean of two halves) = E[(a - b)^2] / 4, relative to the expected value.
                sigma2_sum += ((va - vb) / 2.0 / expected).powi(2);
                ratio_sum += value / expected;
                let err = (value / expected - 1.0).abs();
                if err > worst.0 {
                    worst = (err, x, y, value, expected);
                }
                checked += 1;
            }
        }
        assert!(checked > 90, "only {checked} interior pixels");
        // Per-pixel noise (RMS over pixels) must be a quarter of the tolerance, so a 1% miss is a bias.
        let sigma = (sigma2_sum / checked as f64).sqrt();
        eprintln!("{what}: {} spp, relative noise {sigma:.4}", 2 * spp);
        if sigma > 0.0025 && spp < max_spp {
            continue;
        }
        // Per pixel: 1% wherever the noise target was met. Metal at roughness 1 reflects most visible-normal
        // samples below the horizon (albedo 0.31, per-sample sigma ~1.1x the mean): 0.25% noise would need ~200k
        // spp, beyond CI on a CPU, so its per-pixel bound is 4 sigma and the mean ratio below carries the 1% claim.
        let tolerance = 0.01f64.max(4.0 * sigma);
        let mean_ratio = ratio_sum / checked as f64;
        eprintln!(
            "{what}: {checked} pixels at {} spp, worst error {:.4} at ({}, {}) value {:.4} expected {:.4}; mean ratio {mean_ratio:.5}; tolerance {tolerance:.4}",
            2 * spp,
            worst.0,
            worst.1,
            worst.2,
            worst.3,
            worst.4
        );
        assert!(
            worst.0 < tolerance,
            "{what}: pixel ({}, {}) is {:.4}, expected {:.4} ({:.2}% off)",
            worst.1,
            worst.2,
            worst.3,
            worst.4,
            worst.0 * 100.0
        );
        let mean_tolerance = 0.002 + 4.0 * sigma / (checked as f64).sqrt();
        assert!(
            (mean_ratio - 1.0).abs() < mean_tolerance,
            "{what}: mean rendered/expected {mean_ratio:.5} (tolerance {mean_tolerance:.4})"
        );
        return;
    }
}

#[test]
fn furnace_dielectric_rough() {
    furnace_case(0.0, 1.0);
}
#[test]
fn furnace_dielectric_medium() {
    furnace_case(0.0, 0.5);
}
#[test]
fn furnace_dielectric_smooth() {
    furnace_case(0.0, 0.05);
}
#[test]
fn furnace_metal_rough() {
    furnace_case(1.0, 1.0);
}
#[test]
fn furnace_metal_medium() {
    furnace_case(1.0, 0.5);
}
#[test]
fn furnace_metal_smooth() {
    furnace_case(1.0, 0.05);
}

/// The sphere under the sky gradient (`Environment::Sky`: radiance (0.75, 0.85, 1) - (0.25, 0.15, 0) y along a
/// direction of height y, written here from its definition), which next-event estimation leaves to BSDF
/// sampling. For radiance linear in the direction, a pixel is A albedo(mu) + B (m_x(mu) e_x.y + m_z(mu) n.y):
/// the BRDF's first moment (the integral of f cos(l) l) lies in the plane of the normal n and the view, along
/// e_x (the view's part across n) and n. Red, whose gradient is a third of its mean.
#[test]
fn gradient_furnace_dielectric_medium() {
    let (metallic, roughness) = (0.0, 0.5);
    let (a, b) = (0.75, -0.25);
    let moment = |axis: usize| {
        table_of_cosines(move |mu| albedo_weighted(mu, metallic, roughness, &|l| l[axis]))
    };
    let (albedo, m_x, m_z) = (
        table_of_cosines(|mu| albedo(mu, metallic, roughness)),
        moment(0),
        moment(2),
    );
    let radiance = |n: [f64; 3], v: [f64; 3]| {
        let mu = dot(n, v);
        let across = [v[0] - mu * n[0], v[1] - mu * n[1], v[2] - mu * n[2]];
        let e_x_y = if dot(across, across) > 1e-12 {
            normalize(across)[1]
        } else {
            0.0
        };
        a * albedo(mu) + b * (m_x(mu) * e_x_y + m_z(mu) * n[1])
    };
    let material = Material {
        name: "white".into(),
        metallic: metallic as f32,
        roughness: roughness as f32,
        ..Default::default()
    };
    sphere_check(
        "gradient sky, metallic 0 roughness 0.5",
        material,
        Environment::Sky,
        0,
        &radiance,
        16384,
    );
}
