//! KHR_materials_transmission, _ior, _volume and _specular against closed forms of the glTF model (the
//! extensions' layering: `fresnel_mix` with Schlick's Fresnel, f0 = ((ior - 1) / (ior + 1))^2 x specular
//! colour, the base weighted by 1 - specular x max(F)), written here from the specifications:
//! - a smooth slab seen at normal incidence in front of an emitter transmits the series of its internal
//!   reflections, t^2 a / (1 - R^2 a^2), with t = 1 - max(F), R = F per channel and a = attenuationColor^(L / d)
//!   (Beer-Lambert over the slab's thickness L);
//! - a thin-walled surface transmits 1 - max(F) once, without bending;
//! - in a white furnace a smooth glass sphere (and one inside another) is invisible: every interface splits
//!   light into R + T = 1, total internal reflection included, so nothing is lost or gained; a rough one may
//!   only lose (single-scattering microfacets);
//! - degenerate parameters (IOR 0, IOR 1 with a volume, black attenuation, roughness 1) render finite pixels.

use crate::common::*;
use glam::{Vec3, Vec4};
use raykin::camera::CameraChoice;
use raykin::render::{Environment, RenderSettings};
use raykin::scene::material_extensions::{Specular, Transmission, Volume};
use raykin::scene::{Material, MaterialExtensions, MeshData, NodeTransform, procedural};
use std::sync::Arc;

const SIZE: u32 = 16;

/// A transmissive dielectric: white, smooth unless `roughness` says otherwise.
fn glass(ior: f32, roughness: f32) -> Material {
    Material {
        name: "glass".into(),
        metallic: 0.0,
        roughness,
        extensions: MaterialExtensions {
            ior,
            transmission: Some(Transmission {
                factor: 1.0,
                texture: None,
            }),
            ..Default::default()
        },
        ..Default::default()
    }
}

/// `glass` with a volume behind its surface (refraction), attenuating to `color` over `distance`.
fn glass_volume(ior: f32, roughness: f32, color: Vec3, distance: f32) -> Material {
    let mut m = glass(ior, roughness);
    m.extensions.volume = Some(Volume {
        thickness: 1.0,
        thickness_texture: None,
        attenuation_distance: distance,
        attenuation_color: color,
    });
    m
}

fn emitter() -> Material {
    Material {
        name: "emitter".into(),
        base_color: Vec4::new(0.0, 0.0, 0.0, 1.0),
        emissive: Vec3::ONE,
        ..Default::default()
    }
}

/// A square face centred at `c` spanning +-u and +-v, facing u x v (counter-clockwise seen from there).
fn face(c: Vec3, u: Vec3, v: Vec3, material: u32) -> MeshData {
    quad_mesh([c - u - v, c + u - v, c + u + v, c - u + v], material)
}

/// A closed box of half extents `h` around the origin, faces outward.
fn closed_box(h: Vec3, material: u32) -> Vec<MeshData> {
    let (x, y, z) = (Vec3::X * h.x, Vec3::Y * h.y, Vec3::Z * h.z);
    vec![
        face(z, x, y, material),
        face(-z, y, x, material),
        face(x, y, z, material),
        face(-x, z, y, material),
        face(y, z, x, material),
        face(-y, x, z, material),
    ]
}

/// How a test scene is rendered: 16x16, no Russian roulette, a constant environment, a camera looking at the
/// origin.
struct Shot {
    max_depth: u32,
    environment: f32,
    seed: u32,
    eye: Vec3,
    yfov_deg: f32,
}

/// `meshes` (untransformed) with `materials`, rendered at `spp` as `shot` says; every pixel must be finite.
fn shoot(
    what: &str,
    meshes: Vec<MeshData>,
    materials: Vec<Material>,
    shot: Shot,
    spp: u32,
) -> Vec<[f32; 3]> {
    let (ctx, _gpu) = gpu();
    let meshes = meshes
        .into_iter()
        .map(|m| (m, NodeTransform::default()))
        .collect();
    let scene = Arc::new(procedural::scene_from_meshes(what, meshes, materials));
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        max_depth: shot.max_depth,
        environment: Environment::Constant([shot.environment; 3]),
        russian_roulette: false,
        seed: shot.seed,
        ..Default::default()
    };
    let camera = CameraChoice::LookAt {
        eye: shot.eye,
        target: Vec3::ZERO,
        yfov: shot.yfov_deg.to_radians(),
    };
    let image = render(&ctx, &scene, settings, &camera, spp);
    assert_all_finite(&image, what);
    image
}

/// What the camera sees straight through `meshes` (material 0) onto an emitter of radiance 1 behind them,
/// in the dark: the mean over a 16x16 image whose rays all cross the glass within 5 degrees of its normal.
fn seen_through(mut meshes: Vec<MeshData>, material: Material, spp: u32) -> [f64; 3] {
    meshes.push(face(
        Vec3::new(0.0, 0.0, -3.0),
        Vec3::X * 10.0,
        Vec3::Y * 10.0,
        1,
    ));
    let shot = Shot {
        max_depth: 12,
        environment: 0.0,
        seed: 5,
        eye: Vec3::new(0.0, 0.0, 6.0),
        yfov_deg: 10.0,
    };
    mean_rgb(&shoot(
        "glass seen through",
        meshes,
        vec![material, emitter()],
        shot,
        spp,
    ))
}

fn slab() -> Vec<MeshData> {
    closed_box(Vec3::new(3.0, 3.0, 0.5), 0)
}

/// Schlick's f0 of an interface to air, per channel with the specular colour.
fn f0(ior: f64, color: [f64; 3]) -> [f64; 3] {
    let r = ((ior - 1.0) / (ior + 1.0)).powi(2);
    color.map(|c| (r * c).min(1.0))
}

/// Transmittance of a slab at normal incidence: t^2 a / (1 - R^2 a^2) per channel (all internal reflections).
fn slab_series(f0: [f64; 3], absorbed: [f64; 3]) -> [f64; 3] {
    let t = 1.0 - f0.iter().cloned().fold(0.0, f64::max);
    [0, 1, 2].map(|c| {
        let (r, a) = (f0[c], absorbed[c]);
        t * t * a / (1.0 - r * r * a * a)
    })
}

#[test]
fn slab_transmits_the_fresnel_series() {
    // IOR 1.5 (f0 = 0.04) and 2 (f0 = 1/9): 0.923 and 0.8 of the light behind.
    for ior in [1.5f32, 2.0] {
        let got = seen_through(slab(), glass_volume(ior, 0.0, Vec3::ONE, f32::INFINITY), 64);
        let want = slab_series(f0(ior as f64, [1.0; 3]), [1.0; 3]);
        assert_channel_means_within(&format!("slab of IOR {ior}"), got, want, 0.015);
    }
    // The specular colour tints what is reflected, not what is transmitted (1 - max(F) for every channel).
    let mut coloured = glass_volume(2.0, 0.0, Vec3::ONE, f32::INFINITY);
    coloured.extensions.specular = Some(Specular {
        factor: 1.0,
        texture: None,
        color: Vec3::new(1.0, 0.5, 0.0),
        color_texture: None,
    });
    let got = seen_through(slab(), coloured, 64);
    let want = slab_series(f0(2.0, [1.0, 0.5, 0.0]), [1.0; 3]);
    assert_channel_means_within("slab with a specular colour", got, want, 0.015);
}

#[test]
fn slab_absorbs_by_beer_lambert() {
    // 1 unit of glass attenuating to (0.8, 0.5, 0.2) over 0.5 units: a = colour^2 per pass.
    let color = Vec3::new(0.8, 0.5, 0.2);
    let absorbed = color.to_array().map(|c| (c as f64).powi(2));
    let got = seen_through(slab(), glass_volume(1.5, 0.0, color, 0.5), 64);
    let want = slab_series(f0(1.5, [1.0; 3]), absorbed);
    assert_channel_means_within("absorbing slab", got, want, 0.02);
    // IOR 1 bends nothing and reflects nothing at normal incidence: only the absorption remains.
    let got = seen_through(slab(), glass_volume(1.0, 0.0, color, 0.5), 32);
    assert_channel_means_within("absorbing slab of IOR 1", got, absorbed, 0.02);
}

#[test]
fn thin_wall_transmits_once_without_bending() {
    // One face, no volume: 1 - 0.04 of the light behind, and the emitter's edge stays where it was.
    let wall = vec![face(Vec3::ZERO, Vec3::X * 3.0, Vec3::Y * 3.0, 0)];
    let got = seen_through(wall, glass(1.5, 0.0), 64);
    assert_channel_means_within("thin wall", got, [0.96; 3], 0.015);
}

/// Mean over the pixels that see the sphere (radius 1, 4 units away, 32-degree field) of a glass sphere in a
/// white furnace; `inner` adds a second glass sphere of half the radius inside it.
fn furnace_mean(material: Material, inner: bool, spp: u32) -> [f64; 3] {
    let mut meshes = vec![procedural::uv_sphere(1.0, 128, 64, 0)];
    if inner {
        meshes.push(procedural::uv_sphere(0.5, 64, 32, 0));
    }
    let shot = Shot {
        max_depth: 32,
        environment: 1.0,
        seed: 9,
        eye: Vec3::new(0.0, 0.0, 4.0),
        yfov_deg: 32.0,
    };
    let image = shoot("glass furnace", meshes, vec![material], shot, spp);
    // Pixels whose centre ray meets the sphere well inside its silhouette.
    let tan = (16f64.to_radians()).tan();
    let inside: Vec<[f32; 3]> = (0..SIZE * SIZE)
        .filter(|i| {
            let px = ((i % SIZE) as f64 + 0.5) / SIZE as f64 * 2.0 - 1.0;
            let py = ((i / SIZE) as f64 + 0.5) / SIZE as f64 * 2.0 - 1.0;
            // Distance of the ray from the centre at 4 units, against radius 1.
            (px * px + py * py).sqrt() * tan * 4.0 < 0.8
        })
        .map(|i| image[i as usize])
        .collect();
    assert!(inside.len() > 20, "{} pixels on the sphere", inside.len());
    mean_rgb(&inside)
}

#[test]
fn smooth_glass_is_invisible_in_a_white_furnace() {
    let clear = glass_volume(1.5, 0.0, Vec3::ONE, f32::INFINITY);
    let got = furnace_mean(clear.clone(), false, 64);
    assert_channel_means_within("smooth glass sphere", got, [1.0; 3], 0.02);
    // Nested: a second sphere inside the first (the inner crossing is taken as air to glass, which bends the
    // light wrongly but still splits it into R + T = 1): no energy leaks or appears.
    let got = furnace_mean(clear, true, 64);
    assert_channel_means_within("nested glass spheres", got, [1.0; 3], 0.02);
    // Thin-walled glass too.
    let got = furnace_mean(glass(1.5, 0.0), false, 32);
    assert_channel_means_within("thin-walled sphere", got, [1.0; 3], 0.02);
}

/// Directional albedo of one rough refracting interface seen from the outside (transmission 1, white), by
/// deterministic quadrature over microfacet normals: the midpoint rule on GGX's inverse CDF, which distributes h
/// as D(h) cos(h). Per normal, reflection and refraction (Walter et al. 2007) with Schlick's Fresnel, the
/// height-correlated Smith term for both, and the 1 / eta^2 radiance scale on refraction. The Jacobians
/// cancel against the BSDFs' own denominators: albedo = integral of D(h) (v.h / v.z) [F G2(v, l_r) + (1 - F)
/// G2(v, l_t) / eta^2] over h.
fn rough_interface_albedo(cos_view: f64, roughness: f64, eta: f64) -> f64 {
    let alpha = (roughness * roughness).max(1e-4);
    let a2 = alpha * alpha;
    let v = [(1.0 - cos_view * cos_view).sqrt(), 0.0, cos_view];
    let f0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
    let lambda = |c: f64| 0.5 * (-1.0 + (1.0 + a2 * (1.0 - c * c) / (c * c)).sqrt());
    let g2 = |l: [f64; 3]| 1.0 / (1.0 + lambda(v[2]) + lambda(l[2].abs()));
    let (n_xi, n_phi) = (4096usize, 256usize);
    let mut total = 0.0;
    for i in 0..n_xi {
        let xi = (i as f64 + 0.5) / n_xi as f64;
        let cos2 = (1.0 - xi) / (1.0 + (a2 - 1.0) * xi);
        let (ct, st) = (cos2.sqrt(), (1.0 - cos2).max(0.0).sqrt());
        for j in 0..n_phi {
            let phi = std::f64::consts::TAU * (j as f64 + 0.5) / n_phi as f64;
            let h = [st * phi.cos(), st * phi.sin(), ct];
            let vh = v[0] * h[0] + v[1] * h[1] + v[2] * h[2];
            if vh <= 0.0 {
                continue;
            }
            let f = f0 + (1.0 - f0) * (1.0 - vh).powi(5);
            let mut g = 0.0;
            let lr = [0, 1, 2].map(|k| 2.0 * vh * h[k] - v[k]);
            if lr[2] > 0.0 {
                g += f * g2(lr);
            }
            // Snell's law about h, entering the denser side (no total internal reflection from outside).
            let k = 1.0 - (1.0 - vh * vh) / (eta * eta);
            let lt = [0, 1, 2].map(|c| -v[c] / eta + (vh / eta - k.sqrt()) * h[c]);
            if lt[2] < 0.0 {
                g += (1.0 - f) * g2(lt) / (eta * eta);
            }
            // Divided by h's density D(h) cos(h) relative to D(h): the 1 / ct.
            total += vh / v[2] * g / ct;
        }
    }
    total / (n_xi * n_phi) as f64
}

#[test]
fn quadrature_of_a_smooth_interface_is_fresnel() {
    // Smooth limit: F + (1 - F) / eta^2 with F = 0.04 at normal incidence.
    let a = rough_interface_albedo(1.0, 0.0, 1.5);
    assert!((a - (0.04 + 0.96 / 2.25)).abs() < 2e-3, "{a}");
}

#[test]
fn rough_interface_albedo_matches_quadrature() {
    for (roughness, view_deg) in [(0.3f32, 0.0f32), (0.3, 60.0), (1.0, 0.0), (1.0, 60.0)] {
        let plane = face(Vec3::ZERO, Vec3::X * 1e3, Vec3::Y * 1e3, 0);
        let material = glass_volume(1.5, roughness, Vec3::ONE, f32::INFINITY);
        let view = view_deg.to_radians();
        let shot = Shot {
            max_depth: 4,
            environment: 1.0,
            seed: 3,
            eye: Vec3::new(view.sin(), 0.0, view.cos()) * 5.0,
            yfov_deg: 1.0,
        };
        let image = shoot("rough interface", vec![plane], vec![material], shot, 64);
        let want = rough_interface_albedo((view as f64).cos(), roughness as f64, 1.5);
        eprintln!(
            "roughness {roughness} at {view_deg} deg: {:?} vs quadrature {want:.4}",
            mean_rgb(&image)
        );
        assert_channel_means_within(
            &format!("interface of roughness {roughness} seen at {view_deg} degrees"),
            mean_rgb(&image),
            [want; 3],
            0.015,
        );
    }
}

#[test]
fn rough_glass_loses_energy_but_never_gains() {
    for roughness in [0.3f32, 1.0] {
        let got = furnace_mean(
            glass_volume(1.5, roughness, Vec3::ONE, f32::INFINITY),
            false,
            64,
        );
        eprintln!("rough glass sphere, roughness {roughness}: {got:?}");
        for (c, v) in got.iter().enumerate() {
            assert!(
                *v < 1.02 && *v > 0.2,
                "rough glass (roughness {roughness}) channel {c}: {v}"
            );
        }
    }
}

#[test]
fn degenerate_glass_parameters_render_finite() {
    let black = glass_volume(1.5, 0.2, Vec3::ZERO, 0.01);
    let zero_ior = glass_volume(0.0, 0.0, Vec3::ONE, f32::INFINITY);
    let mut huge = glass_volume(1.5, 1.0, Vec3::splat(0.5), 1e-30);
    if let Some(v) = &mut huge.extensions.volume {
        v.thickness = f32::MAX;
    }
    for (what, material) in [
        ("black attenuation", black),
        ("IOR 0", zero_ior),
        ("huge volume", huge),
    ] {
        let got = furnace_mean(material, false, 8);
        for v in got {
            assert!(
                v.is_finite() && (0.0..=1.05).contains(&v),
                "{what}: mean {v}"
            );
        }
    }
}
