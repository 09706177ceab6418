//! The light library's sampling on the GPU, through a probe kernel composed from the same WGSL modules the
//! path tracer uses (`lights/dispatch`, `lights/light_sampler`): every sample's density equals what
//! `emitter_pdf_li` or `infinite_light_li` gives its direction (the MIS weights depend on it), the densities
//! integrate to 1, and sample means of known integrands converge to the integrals computed independently
//! (quadrature, Lambert's polygon formula), which checks that each sampler draws from the density it claims.

use crate::common::*;
use glam::Vec3;
use raykin::camera::CameraChoice;
use raykin::gpu::GpuContext;
use raykin::gpu::bind::{Binding, bind_group, compute_layout, params_buffer, storage_buffer};
use raykin::headless::HeadlessApp;
use raykin::render::shaders::{ShaderModule, compose};
use raykin::render::{Environment, GpuScene, RenderSettings, ViewTargets};
use std::sync::Arc;

const PROBE: &str = r#"
struct Probe { p: vec3<f32>, light: u32, n: vec3<f32>, count: u32, grid_w: u32, grid_h: u32, seed: u32, incomplete: u32 }
@group(1) @binding(1) var<uniform> probe: Probe;
@group(1) @binding(2) var<storage, read_write> out: array<vec4<f32>>;

// The density of `wi` as the path tracer's MIS weights get it where a BSDF-sampled ray meets the light: an
// emissive triangle's at `distance`, a light at infinity's along `wi` (0 for delta lights).
fn met_light_pdf(light: u32, ctx: LightSampleContext, wi: vec3<f32>, distance: f32, incomplete: bool) -> f32 {
    if read_light(light).kind == LIGHT_TRIANGLE { return emitter_pdf_li(light, ctx, wi, distance); }
    return infinite_light_li(light, wi, incomplete).pdf;
}

// Sample i: (wi, pdf), (luminance of li, pdf of wi again, distance, 0).
@compute @workgroup_size(64)
fn sample_light(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= probe.count { return; }
    let u = get_2d(sampler_start(i, 0u, probe.seed), 0u);
    let ctx = LightSampleContext(probe.p, probe.n);
    let s = light_sample_li(probe.light, ctx, u, probe.incomplete != 0u);
    out[2u * i] = vec4<f32>(s.wi, s.pdf);
    out[2u * i + 1u] = vec4<f32>(luminance(s.li), met_light_pdf(probe.light, ctx, s.wi, s.distance, probe.incomplete != 0u), s.distance, 0.0);
}

// Grid cell i (theta rows, phi columns, midpoints): (pdf, luminance of what a ray leaving along it sees, 0, 0).
@compute @workgroup_size(64)
fn pdf_grid(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= probe.grid_w * probe.grid_h { return; }
    let theta = (f32(i / probe.grid_w) + 0.5) / f32(probe.grid_h) * PI;
    let phi = (f32(i % probe.grid_w) + 0.5) / f32(probe.grid_w) * 2.0 * PI;
    let dir = vec3<f32>(sin(theta) * cos(phi), cos(theta), sin(theta) * sin(phi));
    let li = infinite_light_li(probe.light, dir, probe.incomplete != 0u);
    out[i] = vec4<f32>(li.pdf, luminance(li.le), 0.0, 0.0);
}

// Light i's probability from (probe.p, probe.n): the light sampler NEE uses, by power alone, and for a light
// at infinity the shortcut escaped rays' MIS weights take (-1 for the others).
@compute @workgroup_size(64)
fn pmf_all(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= frame.light_count { return; }
    let ctx = LightSampleContext(probe.p, probe.n);
    let at_infinity = select(-1.0, infinite_light_pmf_at(i), i >= frame.infinite_light_first);
    out[i] = vec4<f32>(light_sampler_pmf_at(ctx, i), light_sampler_pmf(i), at_infinity, 0.0);
}

// Choice i of the light sampler NEE uses: (light index as f32 bits, pmf).
@compute @workgroup_size(64)
fn choose(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= probe.count { return; }
    let u = get_1d(sampler_start(i, 1u, probe.seed), 0u);
    let c = light_sampler_sample_at(LightSampleContext(probe.p, probe.n), u);
    out[i] = vec4<f32>(bitcast<f32>(c.light), c.pmf, 0.0, 0.0);
}

// The light's triangle in world space (for the CPU's closed forms).
@compute @workgroup_size(1)
fn light_triangle() {
    let light = read_light(probe.light);
    let p = world_triangle(light.index_a, light.index_b);
    out[0] = vec4<f32>(p[0], 0.0);
    out[1] = vec4<f32>(p[1], 0.0);
    out[2] = vec4<f32>(p[2], 0.0);
}
"#;

const KERNEL: ShaderModule = ShaderModule {
    name: "light_probe",
    source: PROBE,
    requires: &[
        "constants",
        "view",
        "sampler",
        "color",
        "math",
        "lights/dispatch",
        "lights/light_sampler",
    ],
};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Probe {
    p: [f32; 3],
    light: u32,
    n: [f32; 3],
    count: u32,
    grid_w: u32,
    grid_h: u32,
    seed: u32,
    /// The density next-event estimation samples (`allow_incomplete_pdf`), else the full one.
    incomplete: u32,
}

/// Runs one probe entry point over `invocations` against `app`'s scene and view; returns the output.
fn run_probe(
    app: &HeadlessApp,
    probe: Probe,
    entry: &str,
    invocations: u32,
    out_len: usize,
) -> Vec<[f32; 4]> {
    let ctx: &GpuContext = &app.ctx;
    let world = app.app.world();
    let scene = world.resource::<GpuScene>();
    let bindings = world.resource::<raykin::render::scene_bindings::SceneBindings>();
    let view = world.resource::<ViewTargets>();
    let layout = compute_layout(
        ctx,
        "probe",
        &[Binding::Params, Binding::Params, Binding::ReadWrite],
    );
    let pipeline = raykin::gpu::compute_pipeline(
        ctx,
        "light probe",
        compose(&KERNEL),
        &[Some(&bindings.layout), Some(&layout)],
        entry,
    );
    let uniform = params_buffer(ctx, "probe", std::mem::size_of::<Probe>());
    ctx.queue
        .write_buffer(&uniform, 0, bytemuck::bytes_of(&probe));
    let out = storage_buffer(ctx, "probe out", (out_len * 16) as u64);
    let group = bind_group(ctx, "probe", &layout, &[&view.frame, &uniform, &out]);
    let scene_group = bindings.fresh(ctx, scene);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &scene_group, &[]);
        pass.set_bind_group(1, &group, &[]);
        let groups = invocations.div_ceil(64);
        pass.dispatch_workgroups(groups.min(65535), groups.div_ceil(65535), 1);
    }
    ctx.queue.submit([encoder.finish()]);
    bytemuck::cast_slice::<u8, [f32; 4]>(&ctx.read_buffer(&out, (out_len * 16) as u64)).to_vec()
}

fn app_with(
    ctx: &GpuContext,
    scene: Arc<raykin::scene::SceneAsset>,
    environment: Environment,
) -> HeadlessApp {
    let settings = RenderSettings {
        width: 8,
        height: 8,
        environment,
        light_sampler: raykin::render::LightSampler::Tree,
        ..Default::default()
    };
    let mut app =
        HeadlessApp::new(ctx.clone(), scene, settings, &CameraChoice::Auto).expect("uploads");
    // The first frame uploads instances and the light list and writes the frame constants.
    app.step();
    ctx.wait_idle();
    app
}

fn reference_file(name: &str) -> std::path::PathBuf {
    repo_root().join("tests/reference/lights").join(name)
}

fn sunny_environment() -> Environment {
    Environment::Map(raykin::environment::MapSettings {
        path: reference_file("sunny_64x33.exr"),
        rotation_degrees: 30.0,
        strength: 1.0,
    })
}

/// Integrates a light's density over the sphere (midpoint rule on a theta-phi grid) and returns it with the
/// integral of the luminance seen along the same directions.
/// The integrals over the sphere of `light`'s density (the full one, or next-event estimation's with
/// `incomplete`) and of its luminance where that density is positive, by the midpoint rule on a w x h grid.
fn integrate_over_sphere(
    app: &HeadlessApp,
    light: u32,
    incomplete: bool,
    w: u32,
    h: u32,
) -> (f64, f64) {
    let cells = run_probe(
        app,
        Probe {
            p: [0.0; 3],
            light,
            n: [0.0; 3],
            count: 0,
            grid_w: w,
            grid_h: h,
            seed: 0,
            incomplete: incomplete as u32,
        },
        "pdf_grid",
        w * h,
        (w * h) as usize,
    );
    let (mut pdf_sum, mut le_sum) = (0.0f64, 0.0f64);
    for (i, c) in cells.iter().enumerate() {
        let theta = ((i as u32 / w) as f64 + 0.5) / h as f64 * std::f64::consts::PI;
        let d_omega = theta.sin()
            * (std::f64::consts::PI / h as f64)
            * (2.0 * std::f64::consts::PI / w as f64);
        pdf_sum += c[0] as f64 * d_omega;
        if c[0] > 0.0 {
            le_sum += c[1] as f64 * d_omega;
        }
    }
    (pdf_sum, le_sum)
}

/// Samples from `ctx` and checks each against `light_pdf_li`; returns the samples.
fn samples_consistent(app: &HeadlessApp, probe: Probe, what: &str) -> Vec<([f32; 4], [f32; 4])> {
    let raw = run_probe(
        app,
        probe,
        "sample_light",
        probe.count,
        2 * probe.count as usize,
    );
    let samples: Vec<([f32; 4], [f32; 4])> = raw.chunks(2).map(|c| (c[0], c[1])).collect();
    let valid: Vec<_> = samples.iter().filter(|s| s.0[3] > 0.0).collect();
    assert!(
        valid.len() as f64 > 0.99 * samples.len() as f64,
        "{what}: only {} of {} samples succeeded",
        valid.len(),
        samples.len()
    );
    let mismatched = valid
        .iter()
        .filter(|(a, b)| ((a[3] - b[1]) / a[3]).abs() > 2e-3)
        .count();
    assert!(
        mismatched * 1000 <= valid.len(),
        "{what}: {mismatched} of {} samples have a density light_pdf_li does not reproduce",
        valid.len()
    );
    samples
}

/// Mean and standard error.
fn mean_and_error(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

#[test]
fn environment_map_density_integrates_to_one_and_samples_match_it() {
    let (ctx, _gpu) = gpu();
    let scene = Arc::new(
        raykin::scene::load_gltf(reference_file("envmap.gltf"), &Default::default())
            .expect("loads"),
    );
    let app = app_with(&ctx, scene, sunny_environment());
    let lights = &app.gpu_scene().lights;
    assert_eq!(lights.infinite_count, 1, "the map is one light at infinity");
    let env = lights.infinite_first;
    // Both densities: the full one (ReSTIR's candidates) and next-event estimation's MIS-compensated one, which
    // leaves the map's darker half to BSDF sampling (zero there) and so integrates L only where it is positive.
    let mut full = (0.0, 0.0, 0.0);
    for incomplete in [false, true] {
        let what = if incomplete {
            "compensated environment map"
        } else {
            "environment map"
        };
        // The map is 64 x 33 texels: a 2048 x 1024 grid resolves its cells 32 times over.
        let (pdf_integral, le_integral) = integrate_over_sphere(&app, env, incomplete, 2048, 1024);
        eprintln!(
            "{what}: integral of the pdf {pdf_integral:.5}, of luminance where it is positive {le_integral:.4}"
        );
        assert!(
            (pdf_integral - 1.0).abs() < 2e-3,
            "{what}: the density integrates to {pdf_integral}"
        );
        let count = 1 << 18;
        let samples = samples_consistent(
            &app,
            Probe {
                p: [0.0; 3],
                light: env,
                n: [0.0; 3],
                count,
                grid_w: 0,
                grid_h: 0,
                seed: 11,
                incomplete: incomplete as u32,
            },
            what,
        );
        // E[L / pdf] is the integral of L where the density is positive: the sampler draws from the density
        // it reports.
        let estimates: Vec<f64> = samples
            .iter()
            .map(|(a, b)| {
                if a[3] > 0.0 {
                    b[0] as f64 / a[3] as f64
                } else {
                    0.0
                }
            })
            .collect();
        let (mean, error) = mean_and_error(&estimates);
        eprintln!("{what}: E[L/pdf] = {mean:.4} +- {error:.4}, quadrature {le_integral:.4}");
        assert!(
            (mean - le_integral).abs() < 4.0 * error + 3e-3 * le_integral,
            "{what}: importance-sampled integral {mean} vs quadrature {le_integral}"
        );
        if incomplete {
            // The sun and the bright sky are above the mean, the dark sky below: part of the light, not all.
            assert!(
                le_integral < 0.99 * full.1 && le_integral > 0.5 * full.1,
                "{what}: covers {le_integral} of the map's {}",
                full.1
            );
        } else {
            full = (mean, le_integral, error * (count as f64).sqrt());
        }
    }
    let (mean, _, deviation) = full;
    // Importance sampling pays: the estimator's relative spread is far below uniform sphere sampling's.
    let uniform_rel = {
        let cells = run_probe(
            &app,
            Probe {
                p: [0.0; 3],
                light: env,
                n: [0.0; 3],
                count: 0,
                grid_w: 512,
                grid_h: 256,
                seed: 0,
                incomplete: 0,
            },
            "pdf_grid",
            512 * 256,
            512 * 256,
        );
        // Var of 4 pi L under uniform directions, from the grid (weights sin theta).
        let (mut m1, mut m2, mut wsum) = (0.0, 0.0, 0.0);
        for (i, c) in cells.iter().enumerate() {
            let theta = ((i / 512) as f64 + 0.5) / 256.0 * std::f64::consts::PI;
            let w = theta.sin();
            let x = 4.0 * std::f64::consts::PI * c[1] as f64;
            m1 += w * x;
            m2 += w * x * x;
            wsum += w;
        }
        let (m1, m2) = (m1 / wsum, m2 / wsum);
        (m2 - m1 * m1).sqrt() / m1
    };
    let importance_rel = deviation / mean;
    eprintln!(
        "relative standard deviation: importance {importance_rel:.3}, uniform {uniform_rel:.3}"
    );
    assert!(importance_rel * 3.0 < uniform_rel);
}

#[test]
fn sun_and_sky_sample_inside_the_disc_and_the_sky_integrates_to_one() {
    let (ctx, _gpu) = gpu();
    let scene = Arc::new(
        raykin::scene::load_gltf(reference_file("envmap.gltf"), &Default::default())
            .expect("loads"),
    );
    let sky = raykin::environment::SunSkySettings {
        elevation_degrees: 30.0,
        azimuth_degrees: 120.0,
        turbidity: 3.0,
        strength: 1.0,
    };
    let app = app_with(&ctx, scene, Environment::SunSky(sky));
    let lights = &app.gpu_scene().lights;
    assert_eq!(lights.infinite_count, 2, "sky map and sun");
    let (sky_light, sun_light) = (lights.infinite_first, lights.infinite_first + 1);
    let (pdf_integral, _) = integrate_over_sphere(&app, sky_light, false, 2048, 1024);
    assert!(
        (pdf_integral - 1.0).abs() < 2e-3,
        "sky density integrates to {pdf_integral}"
    );
    let sun = sky.params().sun().expect("above the horizon");
    let samples = samples_consistent(
        &app,
        Probe {
            p: [0.0; 3],
            light: sun_light,
            n: [0.0; 3],
            count: 1 << 14,
            grid_w: 0,
            grid_h: 0,
            seed: 5,
            incomplete: 0,
        },
        "sun",
    );
    let expected_pdf = 1.0 / (2.0 * std::f32::consts::PI * sun.one_minus_cos);
    for (a, b) in &samples {
        let wi = Vec3::new(a[0], a[1], a[2]);
        assert!(
            1.0 - wi.dot(sun.direction) <= sun.one_minus_cos * 1.01,
            "sample outside the disc"
        );
        assert!((a[3] / expected_pdf - 1.0).abs() < 1e-3);
        let lum = 0.2126 * sun.radiance[0] + 0.7152 * sun.radiance[1] + 0.0722 * sun.radiance[2];
        assert!((b[0] / lum - 1.0).abs() < 1e-4);
    }
}

/// The integral of cos(theta) (to normal n) over the solid angle of triangle `v` seen from `p`: Lambert's
/// formula for polygons, 1/2 sum over edges of the edge's angle times n . (the edge plane's unit normal).
fn projected_solid_angle(p: Vec3, v: [Vec3; 3], n: Vec3) -> f64 {
    let r: Vec<glam::DVec3> = v.iter().map(|x| (*x - p).as_dvec3().normalize()).collect();
    let n = n.as_dvec3();
    let mut sum = 0.0;
    for k in 0..3 {
        let (a, b) = (r[k], r[(k + 1) % 3]);
        let gamma = a.dot(b).clamp(-1.0, 1.0).acos();
        sum += gamma * n.dot(a.cross(b).normalize());
    }
    (0.5 * sum).abs()
}

/// Whether the ray from `p` along `dir` meets triangle `v` (in f64, with a margin of 1e-3 in barycentrics: at
/// grazing incidence f32 directions land that far off the edges).
fn meets_triangle(p: Vec3, dir: Vec3, v: [Vec3; 3]) -> bool {
    let [a, b, c] = v.map(|x| x.as_dvec3());
    let (p, dir) = (p.as_dvec3(), dir.as_dvec3());
    let (e1, e2) = (b - a, c - a);
    let n = e1.cross(e2);
    let t = n.dot(a - p) / n.dot(dir);
    let q = p + dir * t - a;
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (q1, q2) = (q.dot(e1), q.dot(e2));
    let det = d11 * d22 - d12 * d12;
    let (b1, b2) = ((d22 * q1 - d12 * q2) / det, (d11 * q2 - d12 * q1) / det);
    t > 0.0 && b1 >= -1e-3 && b2 >= -1e-3 && b1 + b2 <= 1.0 + 1e-3
}

#[test]
fn triangle_lights_sample_their_solid_angle_near_and_far() {
    let (ctx, _gpu) = gpu();
    let scene = Arc::new(
        raykin::scene::load_gltf(
            shared_assets().join("CornellBox/CornellBox.glb"),
            &Default::default(),
        )
        .expect("CornellBox loads"),
    );
    let app = app_with(&ctx, scene, Environment::Constant([0.0; 3]));
    assert!(app.gpu_scene().lights.triangle_count >= 2);
    let probe = |p: Vec3, n: Vec3, light: u32, count: u32, seed: u32| Probe {
        p: p.to_array(),
        light,
        n: n.to_array(),
        count,
        grid_w: 0,
        grid_h: 0,
        seed,
        incomplete: 0,
    };
    let tri = run_probe(
        &app,
        probe(Vec3::ZERO, Vec3::ZERO, 0, 0, 0),
        "light_triangle",
        1,
        3,
    );
    let v = [0, 1, 2].map(|k| Vec3::new(tri[k][0], tri[k][1], tri[k][2]));
    let centroid = (v[0] + v[1] + v[2]) / 3.0;
    let normal = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
    // The lamp is double-sided and hangs under the ceiling: points 0.5 above it (spherical sampling, the
    // case area sampling made infinitely variable), at a slant, and far away (area sampling). Between: small
    // solid angles still sampled spherically (0.006 sr head-on; 0.001 sr at 3 degrees, a thin sliver), where
    // Arvo's formulas took the triangle's area from its angle sum minus pi and GPU asin left it a few percent
    // short (the grazing scene's floor was 5% dark on lavapipe).
    let along = (v[1] - v[0]).normalize();
    for (label, p) in [
        ("0.5 above", centroid + normal * 0.5),
        ("0.5 below", centroid - normal * 0.5),
        ("slanted", centroid + normal * 20.0 + (v[1] - v[0]) * 0.8),
        ("small", centroid + normal * 1000.0),
        ("grazing", centroid + normal * 50.0 + along * 950.0),
        ("far", centroid + normal * 4000.0),
    ] {
        let to_light = (centroid - p).normalize();
        let samples = samples_consistent(&app, probe(p, to_light, 0, 1 << 16, 3), label);
        // Every direction must meet the triangle itself (a direction past an edge meets the quad's other
        // triangle, which blocks the shadow ray).
        let outside = samples
            .iter()
            .filter(|(a, _)| a[3] > 0.0 && !meets_triangle(p, Vec3::new(a[0], a[1], a[2]), v))
            .count();
        assert!(
            outside * 10_000 <= samples.len(),
            "{label}: {outside} of {} sampled directions miss the triangle",
            samples.len()
        );
        // The cosine to the direction of the light is nearly constant over a small triangle, so its mean checks
        // only the density; the cosine to a normal tilted 75 degrees away varies across it, so its mean also
        // checks that the directions are spread uniformly.
        let tilted = (to_light * 15f32.to_radians().sin()
            + along.reject_from(to_light).normalize() * 15f32.to_radians().cos())
        .normalize();
        // Each sample's cos(theta) to `n` over its density (0 where the sampling failed).
        let cos_over_pdf = |n: Vec3| -> Vec<f64> {
            samples
                .iter()
                .map(|(a, _)| {
                    if a[3] > 0.0 {
                        (Vec3::new(a[0], a[1], a[2]).dot(n).max(0.0) / a[3]) as f64
                    } else {
                        0.0
                    }
                })
                .collect()
        };
        for (what, n) in [("cos", to_light), ("tilted cos", tilted)] {
            let (mean, error) = mean_and_error(&cos_over_pdf(n));
            let exact = projected_solid_angle(p, v, n);
            eprintln!("{label}: E[{what}/pdf] = {mean:.6} +- {error:.6}, Lambert {exact:.6}");
            // The triangle must lie above the tilted normal's horizon for Lambert's formula to hold.
            if v.iter().all(|x| (*x - p).dot(n) > 0.0) {
                assert!(
                    (mean - exact).abs() < 4.0 * error + 1e-3 * exact,
                    "{label}: sampled projected solid angle ({what}) {mean} vs Lambert's formula {exact}"
                );
            }
        }
        let exact = projected_solid_angle(p, v, to_light);
        let estimates = cos_over_pdf(to_light);
        // Solid-angle sampling keeps the estimator bounded next to the light.
        if label.starts_with("0.5") {
            let max = estimates.iter().cloned().fold(0.0, f64::max);
            assert!(
                max < 20.0 * exact,
                "{label}: a sample of {max} against a mean of {exact}"
            );
        }
    }
}

#[test]
fn light_tree_probabilities_sum_to_one_and_match_its_choices() {
    let (ctx, _gpu) = gpu();
    let mut asset = raykin::scene::procedural::light_field(12);
    // A point and a spot among the emissive quads, on their own nodes.
    for (i, kind) in [
        raykin::scene::PunctualKind::Point,
        raykin::scene::PunctualKind::Spot {
            inner_cone_angle: 0.3,
            outer_cone_angle: 0.7,
        },
    ]
    .into_iter()
    .enumerate()
    {
        asset.lights.push(raykin::scene::PunctualLight {
            name: format!("punctual {i}"),
            kind,
            color: Vec3::ONE,
            intensity: 50.0,
            range: None,
        });
        asset.nodes.push(raykin::scene::NodeData {
            name: format!("punctual {i}"),
            transform: raykin::scene::NodeTransform {
                translation: Vec3::new(3.0 * i as f32 - 2.0, 3.0, 1.0),
                rotation: glam::Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2),
                ..Default::default()
            },
            light: Some(i),
            ..Default::default()
        });
        asset.roots.push(asset.nodes.len() - 1);
    }
    // A sunny map: a light at infinity that next-event estimation samples (a smooth one it leaves to BSDF
    // sampling), so that escaped rays' shortcut to its probability is checked against a non-zero one.
    let app = app_with(&ctx, Arc::new(asset), sunny_environment());
    let lights = &app.gpu_scene().lights;
    assert_eq!(lights.triangle_count, 288);
    assert_eq!(
        lights.count,
        lights.infinite_first + 1,
        "the map after the lamps"
    );
    assert_eq!(
        lights.tree_count, 290,
        "triangles, point and spot in the tree"
    );
    let count = lights.count;
    for (label, p, n) in [
        ("on the floor", Vec3::new(0.5, 0.0, -0.3), Vec3::Y),
        ("under one lamp", Vec3::new(-9.0, 0.0, -9.0), Vec3::Y),
        ("in the air", Vec3::new(2.0, 2.0, 2.0), Vec3::ZERO),
    ] {
        let probe = Probe {
            p: p.to_array(),
            light: 0,
            n: n.to_array(),
            count: 1 << 17,
            grid_w: 0,
            grid_h: 0,
            seed: 9,
            incomplete: 0,
        };
        let pmfs = run_probe(&app, probe, "pmf_all", count, count as usize);
        for (light, p) in pmfs.iter().enumerate().skip(lights.infinite_first as usize) {
            assert!(p[0] > 0.0, "{label}: the map has no probability");
            assert_eq!(
                p[2], p[0],
                "{label}: light {light} at infinity: infinite_light_pmf_at differs from light_sampler_pmf_at"
            );
        }
        let total: f64 = pmfs.iter().map(|p| p[0] as f64).sum();
        assert!(
            (total - 1.0).abs() < 1e-4,
            "{label}: the tree's probabilities sum to {total}"
        );
        let choices = run_probe(&app, probe, "choose", probe.count, probe.count as usize);
        let mut histogram = vec![0u32; count as usize];
        for c in &choices {
            let light = c[0].to_bits() as usize;
            assert!(light < count as usize, "{label}: chose light {light}");
            assert!(
                (c[1] / pmfs[light][0] - 1.0).abs() < 1e-4,
                "{label}: the choice's pmf {} differs from light_sampler_pmf_at {}",
                c[1],
                pmfs[light][0]
            );
            histogram[light] += 1;
        }
        let n_samples = probe.count as f64;
        for (light, &observed) in histogram.iter().enumerate() {
            let expected = pmfs[light][0] as f64 * n_samples;
            let sigma = expected.max(1.0).sqrt();
            assert!(
                (observed as f64 - expected).abs() < 5.0 * sigma + 1.0,
                "{label}: light {light} chosen {observed} times, expected {expected:.1}"
            );
        }
        // Spatially aware: the lamps nearest the point are far likelier than by power alone.
        let gain = pmfs
            .iter()
            .map(|p| p[0] as f64 / p[1].max(1e-12) as f64)
            .fold(0.0, f64::max);
        eprintln!("{label}: sum {total:.6}; largest tree/power probability ratio {gain:.1}");
        assert!(
            gain > 3.0,
            "{label}: the tree favours no light over power sampling"
        );
    }
}
