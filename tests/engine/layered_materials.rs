//! KHR_materials_clearcoat and KHR_materials_sheen, the layers of the glTF BSDF (`shaders/bsdf/gltf.wgsl`), against
//! the specifications' formulas written here (their implementation sections), not the renderer's code:
//! - white furnace: a coated and a sheened sphere reflect per pixel the directional albedo of the layered BRDF,
//!   integrated here by quadrature (`furnace::albedo` for the GGX lobes, the Charlie lobe below);
//! - the shader's fit of the sheen albedo E against fresh quadrature of the sheen BRDF;
//! - sampling: through a probe kernel over the BSDF library, the density a sample reports is the one `bsdf_pdf`
//!   gives its direction, the density integrates to the share of samples that succeed, a histogram of the sampled
//!   directions follows it, and the mean sample weight is the albedo quadrature gives;
//! - sample models with both layers load without an "ignored" warning and render finite pixels.

use crate::common::*;
use crate::furnace::{albedo, albedo_weighted, furnace_check};
use glam::Vec3;
use raykin::camera::CameraChoice;
use raykin::gpu::bind::{Binding, bind_group, compute_layout, params_buffer, storage_buffer};
use raykin::render::RenderSettings;
use raykin::render::shaders::{ShaderModule, compose};
use raykin::scene::material_extensions::{Clearcoat, Sheen};
use raykin::scene::{Material, MaterialExtensions};
use std::f64::consts::PI;

/// The sheen's "Charlie" visibility: the fit of ln(Lambda) the extension quotes (Estevez & Kulla 2017).
fn charlie_lambda(cos_theta: f64, alpha: f64) -> f64 {
    let l = |x: f64| {
        let t = (1.0 - alpha) * (1.0 - alpha);
        let mix = |a: f64, b: f64| a + (b - a) * t;
        mix(21.5473, 25.3245) / (1.0 + mix(3.82987, 3.32435) * x.powf(mix(0.19823, 0.16801)))
            + mix(-1.97760, -1.27393) * x
            + mix(-4.32054, -4.85967)
    };
    let c = cos_theta.abs();
    if c < 0.5 {
        l(c).exp()
    } else {
        (2.0 * l(0.5) - l(1.0 - c)).exp()
    }
}

/// alpha of a sheen roughness: its square, at least 0.01 (raykin's documented clamp of the degenerate 0).
fn sheen_alpha(roughness: f64) -> f64 {
    (roughness * roughness).max(0.01)
}

/// E(mu): the sheen BRDF's directional albedo (colour 1), D V cos(l) integrated over the hemisphere by the
/// midpoint rule in (theta_l, phi), phi over half the circle (the integrand is even in phi).
fn sheen_albedo_quadrature(mu: f64, roughness: f64) -> f64 {
    let alpha = sheen_alpha(roughness);
    let v = [(1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu];
    let (n_theta, n_phi) = (384usize, 96usize);
    let mut total = 0.0;
    for i in 0..n_theta {
        let theta = (i as f64 + 0.5) / n_theta as f64 * PI / 2.0;
        let (sl, cl) = theta.sin_cos();
        let lambda = 1.0 + charlie_lambda(mu, alpha) + charlie_lambda(cl, alpha);
        for j in 0..n_phi {
            let phi = (j as f64 + 0.5) / n_phi as f64 * PI;
            let l = [sl * phi.cos(), sl * phi.sin(), cl];
            let h = [v[0] + l[0], v[1] + l[1], v[2] + l[2]];
            let cos_h2 = h[2] * h[2] / (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
            let d = (2.0 + 1.0 / alpha) * (1.0 - cos_h2).max(0.0).powf(0.5 / alpha) / (2.0 * PI);
            let visibility = 1.0 / (lambda * 4.0 * mu * cl);
            // dl = sin(theta) dtheta dphi; twice for the other half of phi.
            total += d * visibility * cl * sl;
        }
    }
    total * 2.0 * (PI / 2.0 / n_theta as f64) * (PI / n_phi as f64)
}

#[test]
fn sheen_albedo_quadrature_is_bounded_and_falls_with_the_view_cosine() {
    // Rough sheens reflect a fraction of the light; E decreases towards normal incidence (a grazing lobe).
    let at = |mu| sheen_albedo_quadrature(mu, 1.0);
    let (grazing, mid, normal) = (at(0.2), at(0.5), at(1.0));
    assert!(grazing > mid && mid > normal && normal > 0.05 && grazing < 1.0);
    // A smooth sheen's lobe lies near the horizon: nothing at normal incidence.
    assert!(sheen_albedo_quadrature(1.0, 0.1) < 1e-3);
}

const PROBE: &str = r#"
struct Probe {
    v: vec3<f32>, count: u32,
    base_color: vec3<f32>, metallic: f32,
    coat_normal: vec3<f32>, roughness: f32,
    sheen_color: vec3<f32>, sheen_roughness: f32,
    coat: f32, coat_roughness: f32, transmission: f32, ior: f32,
    grid_w: u32, grid_h: u32, seed: u32, _pad: u32,
}
@group(0) @binding(0) var<uniform> probe: Probe;
@group(0) @binding(1) var<storage, read_write> out: array<vec4<f32>>;

fn probe_bsdf() -> BsdfParams {
    var p = core_bsdf(probe.base_color, probe.metallic, max(probe.roughness * probe.roughness, MIN_ALPHA));
    p.lobes = pack_lobes(vec3<f32>(0.04), 1.0, probe.transmission, probe.ior, false);
    p.layers = pack_layers(probe.coat, probe.coat_roughness, normalize(probe.coat_normal), probe.sheen_color, probe.sheen_roughness);
    return p;
}

fn probe_hash(x: u32) -> u32 {
    var h = x * 747796405u + 2891336453u;
    h = ((h >> ((h >> 28u) + 4u)) ^ h) * 277803737u;
    return (h >> 22u) ^ h;
}

fn probe_random(i: u32, k: u32) -> f32 {
    return f32(probe_hash(probe_hash(i * 3u + k) ^ probe.seed) >> 8u) / 16777216.0;
}

fn invocation(gid: vec3<u32>) -> u32 {
    return gid.x + gid.y * 65535u * 64u;
}

// Sample i: (wi, pdf), (weight, flags), (f cos at wi, bsdf_pdf at wi).
@compute @workgroup_size(64)
fn sample_bsdf(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = invocation(gid);
    if i >= probe.count { return; }
    let p = probe_bsdf();
    let s = bsdf_sample(probe.v, p, probe_random(i, 0u), vec2<f32>(probe_random(i, 1u), probe_random(i, 2u)));
    out[3u * i] = vec4<f32>(s.wi, s.pdf);
    out[3u * i + 1u] = vec4<f32>(s.weight, f32(s.flags));
    out[3u * i + 2u] = vec4<f32>(bsdf_eval(probe.v, s.wi, p) * abs(s.wi.z), bsdf_pdf(probe.v, s.wi, p));
}

// Cell i of a theta-phi grid over the whole sphere (midpoints): (bsdf_pdf, f cos).
@compute @workgroup_size(64)
fn pdf_grid(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = invocation(gid);
    if i >= probe.grid_w * probe.grid_h { return; }
    let theta = (f32(i / probe.grid_w) + 0.5) / f32(probe.grid_h) * PI;
    let phi = (f32(i % probe.grid_w) + 0.5) / f32(probe.grid_w) * 2.0 * PI;
    let l = vec3<f32>(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));
    let p = probe_bsdf();
    out[i] = vec4<f32>(bsdf_pdf(probe.v, l, p), bsdf_eval(probe.v, l, p) * abs(l.z));
}

// Point i of a grid: the shader's sheen albedo at cos_view (x + 0.5) / grid_w, roughness y / (grid_h - 1).
@compute @workgroup_size(64)
fn sheen_albedo_grid(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = invocation(gid);
    if i >= probe.grid_w * probe.grid_h { return; }
    let mu = (f32(i % probe.grid_w) + 0.5) / f32(probe.grid_w);
    let roughness = f32(i / probe.grid_w) / f32(probe.grid_h - 1u);
    out[i] = vec4<f32>(sheen_albedo(mu, roughness), 0.0, 0.0, 0.0);
}
"#;

const KERNEL: ShaderModule = ShaderModule {
    name: "bsdf_probe",
    source: PROBE,
    requires: &["constants", "math", "bsdf/gltf"],
};

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct Probe {
    v: [f32; 3],
    count: u32,
    base_color: [f32; 3],
    metallic: f32,
    coat_normal: [f32; 3],
    roughness: f32,
    sheen_color: [f32; 3],
    sheen_roughness: f32,
    coat: f32,
    coat_roughness: f32,
    transmission: f32,
    ior: f32,
    grid_w: u32,
    grid_h: u32,
    seed: u32,
    _pad: u32,
}

/// The probe's pipelines, compiled once for every case.
struct Prober {
    ctx: raykin::gpu::GpuContext,
    layout: wgpu::BindGroupLayout,
    pipelines: Vec<(&'static str, wgpu::ComputePipeline)>,
}

impl Prober {
    fn new(ctx: raykin::gpu::GpuContext) -> Self {
        let layout = compute_layout(&ctx, "bsdf probe", &[Binding::Params, Binding::ReadWrite]);
        let pipelines = ["sample_bsdf", "pdf_grid", "sheen_albedo_grid"]
            .into_iter()
            .map(|entry| {
                let pipeline = raykin::gpu::compute_pipeline(
                    &ctx,
                    "bsdf probe",
                    compose(&KERNEL),
                    &[Some(&layout)],
                    entry,
                );
                (entry, pipeline)
            })
            .collect();
        Self {
            ctx,
            layout,
            pipelines,
        }
    }

    fn run(&self, probe: Probe, entry: &str, invocations: u32, out_len: usize) -> Vec<[f32; 4]> {
        let ctx = &self.ctx;
        let pipeline = &self.pipelines.iter().find(|(e, _)| *e == entry).unwrap().1;
        let uniform = params_buffer(ctx, "probe", std::mem::size_of::<Probe>());
        ctx.queue
            .write_buffer(&uniform, 0, bytemuck::bytes_of(&probe));
        let out = storage_buffer(ctx, "probe out", (out_len * 16) as u64);
        let group = bind_group(ctx, "probe", &self.layout, &[&uniform, &out]);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &group, &[]);
            let groups = invocations.div_ceil(64);
            pass.dispatch_workgroups(groups.min(65535), groups.div_ceil(65535), 1);
        }
        ctx.queue.submit([encoder.finish()]);
        bytemuck::cast_slice::<u8, [f32; 4]>(&ctx.read_buffer(&out, (out_len * 16) as u64)).to_vec()
    }
}

fn view_at(degrees: f32) -> [f32; 3] {
    let t = degrees.to_radians();
    [t.sin(), 0.0, t.cos()]
}

/// A BSDF with both layers over a rough dielectric; the cases below change it.
fn layered_probe() -> Probe {
    Probe {
        v: view_at(40.0),
        count: 0,
        base_color: [0.5, 0.4, 0.3],
        metallic: 0.0,
        coat_normal: Vec3::new(0.3, 0.1, 0.95).normalize().to_array(),
        roughness: 0.6,
        sheen_color: [0.8, 0.6, 0.4],
        sheen_roughness: 0.5,
        coat: 1.0,
        coat_roughness: 0.3,
        transmission: 0.0,
        ior: 1.5,
        grid_w: 0,
        grid_h: 0,
        seed: 17,
        _pad: 0,
    }
}

/// Checks `bsdf_sample` against `bsdf_pdf` and `bsdf_eval` for one parameter set (see the module comment).
fn check_sampling(prober: &Prober, what: &str, probe: Probe) {
    let n: u32 = 1 << 20;
    let samples = prober.run(
        Probe { count: n, ..probe },
        "sample_bsdf",
        n,
        3 * n as usize,
    );
    let (w, h) = (1024u32, 512u32);
    let cells = prober.run(
        Probe {
            grid_w: w,
            grid_h: h,
            ..probe
        },
        "pdf_grid",
        w * h,
        (w * h) as usize,
    );
    // Quadrature over the sphere: the density's integral and the albedo.
    let cell_area = |row: u32| {
        let t0 = row as f64 / h as f64 * PI;
        let t1 = (row + 1) as f64 / h as f64 * PI;
        (t0.cos() - t1.cos()) * 2.0 * PI / w as f64
    };
    let (bins_theta, bins_phi) = (16u32, 32u32);
    let mut expected_bins = vec![0.0f64; (bins_theta * bins_phi) as usize];
    let mut pdf_integral = 0.0f64;
    let mut albedo_grid = [0.0f64; 3];
    for (i, c) in cells.iter().enumerate() {
        let (row, col) = (i as u32 / w, i as u32 % w);
        let area = cell_area(row);
        pdf_integral += c[0] as f64 * area;
        for k in 0..3 {
            albedo_grid[k] += c[k + 1] as f64 * area;
        }
        let bin = (row * bins_theta / h) * bins_phi + col * bins_phi / w;
        expected_bins[bin as usize] += c[0] as f64 * area * n as f64;
    }
    // Every sample: its density is bsdf_pdf's and its weight f cos / pdf.
    let mut succeeded = 0usize;
    let mut weight_sum = [0.0f64; 3];
    let mut observed_bins = vec![0.0f64; expected_bins.len()];
    let mut worst = 0.0f32;
    for s in samples.chunks_exact(3) {
        let ([x, y, z, pdf], [wr, wg, wb, flags], [fr, fg, fb, pdf_eval]) = (s[0], s[1], s[2]);
        if flags == 0.0 {
            assert_eq!(
                [wr, wg, wb],
                [0.0; 3],
                "{what}: a failed sample has a weight"
            );
            continue;
        }
        assert!(pdf > 0.0 && pdf.is_finite(), "{what}: pdf {pdf}");
        worst = worst.max((pdf - pdf_eval).abs() / pdf);
        for (weight, f) in [(wr, fr), (wg, fg), (wb, fb)] {
            worst = worst.max((weight - f / pdf).abs() / (f / pdf).max(1e-3));
        }
        succeeded += 1;
        for (k, v) in [wr, wg, wb].into_iter().enumerate() {
            weight_sum[k] += v as f64;
        }
        let theta = (z as f64).clamp(-1.0, 1.0).acos();
        let phi = (y as f64).atan2(x as f64).rem_euclid(2.0 * PI);
        let row = ((theta / PI * bins_theta as f64) as u32).min(bins_theta - 1);
        let col = ((phi / (2.0 * PI) * bins_phi as f64) as u32).min(bins_phi - 1);
        observed_bins[(row * bins_phi + col) as usize] += 1.0;
    }
    assert!(
        worst < 1e-3,
        "{what}: a sample's pdf or weight differs from bsdf_pdf / bsdf_eval by {worst}"
    );
    let success = succeeded as f64 / n as f64;
    eprintln!(
        "{what}: {:.4} of samples succeed, the density integrates to {pdf_integral:.4}; mean weight {:?} vs albedo {:?}",
        success,
        weight_sum.map(|s| s / n as f64),
        albedo_grid
    );
    // The density integrates to the share of samples that succeed (the rest, e.g. reflections below the
    // horizon, have no density anywhere).
    let sigma = (success * (1.0 - success) / n as f64).sqrt();
    assert!(
        (pdf_integral - success).abs() < 4.0 * sigma + 3e-3,
        "{what}: the density integrates to {pdf_integral}, but {success} of samples succeed"
    );
    assert!(success > 0.5, "{what}: only {success} of samples succeed");
    // The directions follow the density: every well-filled bin within 5 sigma (and 1% for the grid's error).
    for (i, (&expected, &observed)) in expected_bins.iter().zip(&observed_bins).enumerate() {
        if expected < 50.0 {
            continue;
        }
        assert!(
            (observed - expected).abs() < 5.0 * expected.sqrt() + 0.01 * expected,
            "{what}: bin {i} (theta row {}, phi column {}) holds {observed} samples, the density says {expected:.1}",
            i as u32 / bins_phi,
            i as u32 % bins_phi
        );
    }
    // E[f cos / pdf] is the albedo: the sampler covers everything the BSDF reflects or transmits.
    for k in 0..3 {
        let mean = weight_sum[k] / n as f64;
        assert!(
            (mean - albedo_grid[k]).abs() < 0.01 * albedo_grid[k] + 2e-3,
            "{what}: channel {k}: mean weight {mean} but the albedo is {}",
            albedo_grid[k]
        );
    }
}

#[test]
fn layered_sampling_draws_from_the_density_it_reports() {
    let (ctx, _gpu) = gpu();
    let prober = Prober::new(ctx);
    check_sampling(&prober, "coat and sheen over a dielectric", layered_probe());
    check_sampling(
        &prober,
        "coat and sheen over thin-walled transmission",
        Probe {
            v: view_at(60.0),
            coat: 0.7,
            coat_roughness: 0.4,
            coat_normal: [0.0, 0.0, 1.0],
            sheen_color: [0.5; 3],
            sheen_roughness: 0.8,
            transmission: 1.0,
            ior: 1.0,
            roughness: 0.5,
            ..layered_probe()
        },
    );
    check_sampling(
        &prober,
        "coat over refraction",
        Probe {
            v: view_at(30.0),
            coat_roughness: 0.3,
            sheen_color: [0.0; 3],
            transmission: 1.0,
            ior: 1.5,
            roughness: 0.5,
            ..layered_probe()
        },
    );
    check_sampling(
        &prober,
        "sheen over a metal at a grazing view",
        Probe {
            v: view_at(75.0),
            coat: 0.0,
            base_color: [0.9, 0.7, 0.5],
            metallic: 1.0,
            roughness: 0.3,
            sheen_color: [1.0; 3],
            sheen_roughness: 0.3,
            ..layered_probe()
        },
    );
}

#[test]
fn sheen_albedo_fit_matches_quadrature() {
    let (ctx, _gpu) = gpu();
    let prober = Prober::new(ctx);
    let (w, h) = (20u32, 11u32);
    let fit = prober.run(
        Probe {
            grid_w: w,
            grid_h: h,
            ..layered_probe()
        },
        "sheen_albedo_grid",
        w * h,
        (w * h) as usize,
    );
    let mut worst = (0.0f64, 0.0, 0.0, 0.0);
    for (i, f) in fit.iter().enumerate() {
        let mu = ((i as u32 % w) as f64 + 0.5) / w as f64;
        let roughness = (i as u32 / w) as f64 / (h - 1) as f64;
        if mu < 0.1 {
            continue;
        }
        let e = sheen_albedo_quadrature(mu, roughness);
        let err = (f[0] as f64 - e).abs();
        if err > worst.0 {
            worst = (err, mu, roughness, e);
        }
    }
    eprintln!(
        "sheen albedo fit: worst error {:.4} at cos {:.3}, roughness {:.2} (E = {:.4})",
        worst.0, worst.1, worst.2, worst.3
    );
    assert!(worst.0 < 0.01, "sheen albedo fit off by {worst:?}");
}

/// Samples per half of a layered furnace: 0.4% noise per pixel, so the per-pixel bound is about 1.6% and the
/// mean ratio's 0.4% (CI time: the core lobes' furnaces already hold each pixel to 1%).
const LAYER_FURNACE_SPP: u32 = 4096;

/// A white sphere material with `extensions`.
fn white(extensions: MaterialExtensions, metallic: f32, roughness: f32) -> Material {
    Material {
        name: "layered".into(),
        metallic,
        roughness,
        extensions,
        ..Default::default()
    }
}

#[test]
fn furnace_clearcoat() {
    // fresnel_coat: the coat's GGX lobe weighted by w F_coat(n.v), the base by 1 - w F_coat(n.v).
    let (weight, coat_roughness, base_roughness) = (0.8f32, 0.4f32, 0.5f32);
    let material = white(
        MaterialExtensions {
            clearcoat: Some(Clearcoat {
                factor: weight,
                texture: None,
                roughness: coat_roughness,
                roughness_texture: None,
                normal_texture: None,
                normal_scale: 1.0,
            }),
            ..Default::default()
        },
        0.0,
        base_roughness,
    );
    let expected = |mu: f64| {
        let fc = weight as f64 * (0.04 + 0.96 * (1.0 - mu).powi(5));
        // The coat's lobe alone is GGX with F = 1: the albedo of a white metal of its roughness.
        (1.0 - fc) * albedo(mu, 0.0, base_roughness as f64)
            + fc * albedo(mu, 1.0, coat_roughness as f64)
    };
    furnace_check("clearcoat", material, expected, LAYER_FURNACE_SPP);
}

#[test]
fn furnace_sheen() {
    // The Charlie lobe plus the base dimmed by min(1 - c E(n.v), 1 - c E(n.l)), c = max(sheenColor).
    let (color, sheen_roughness, base_roughness) = (0.8f32, 0.6f32, 0.5f32);
    let material = white(
        MaterialExtensions {
            sheen: Some(Sheen {
                color: Vec3::splat(color),
                color_texture: None,
                roughness: sheen_roughness,
                roughness_texture: None,
            }),
            ..Default::default()
        },
        0.0,
        base_roughness,
    );
    // E on a grid of cosines, linear in between (the base's quadrature asks at every direction).
    let nodes: Vec<f64> = (0..=128)
        .map(|i| sheen_albedo_quadrature((i as f64 / 128.0).max(1e-3), sheen_roughness as f64))
        .collect();
    let e = |mu: f64| {
        let x = mu.clamp(0.0, 1.0) * 128.0;
        let i = (x as usize).min(127);
        nodes[i] + (nodes[i + 1] - nodes[i]) * (x - i as f64)
    };
    let c = color as f64;
    let expected = |mu: f64| {
        let scale_v = 1.0 - c * e(mu);
        let base = albedo_weighted(mu, 0.0, base_roughness as f64, &|l| {
            scale_v.min(1.0 - c * e(l[2])).max(0.0)
        });
        c * e(mu) + base
    };
    furnace_check("sheen", material, expected, LAYER_FURNACE_SPP);
}

#[test]
fn sample_models_with_layers_render_without_a_warning() {
    let conformance = repo_root().join("assets/conformance");
    let (ctx, _gpu) = gpu();
    for file in [
        "ClearCoatCarPaint/glTF-Binary/ClearCoatCarPaint.glb",
        "Authored/MaterialExtensions.gltf",
    ] {
        let scene = raykin::scene::load_gltf(conformance.join(file), &Default::default())
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(
            scene.materials.iter().any(|m| {
                m.extensions
                    .clearcoat
                    .as_ref()
                    .is_some_and(|c| c.factor > 0.0)
                    || m.extensions
                        .sheen
                        .as_ref()
                        .is_some_and(|s| s.color.max_element() > 0.0)
            }),
            "{file} has no layer"
        );
        for ext in ["KHR_materials_clearcoat", "KHR_materials_sheen"] {
            assert!(
                !scene.warnings.iter().any(|w| w.contains(ext)),
                "{file}: {ext} warned: {:#?}",
                scene.warnings
            );
        }
        let settings = RenderSettings {
            width: 24,
            height: 24,
            seed: 3,
            ..Default::default()
        };
        let image = render(
            &ctx,
            &std::sync::Arc::new(scene),
            settings,
            &CameraChoice::Auto,
            4,
        );
        assert_all_finite(&image, file);
        let mean = mean_rgb(&image);
        assert!(mean.iter().all(|c| *c > 0.0), "{file}: mean {mean:?}");
    }
}
