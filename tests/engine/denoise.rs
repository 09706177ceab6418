//! The denoiser (docs/ACCURACY.md, "Denoiser"): error against an independent reference at low spp, energy
//! kept on flat and textured surfaces, texture and geometric edges kept, converged input passed through,
//! extreme inputs kept finite, and a display-side switch that never touches accumulation.

use crate::common::cornell::{self, EPS};
use crate::common::denoising::*;
use crate::common::*;
use raykin::camera::CameraChoice;
use raykin::headless::HeadlessApp;
use raykin::render::{Denoiser, DenoiserKind, Environment, RenderSettings};
use raykin::scene::{Material, NodeTransform, procedural};
use std::sync::Arc;

/// At 1 and 4 spp the denoised Cornell box is several times closer to Mitsuba's converged image than the
/// noisy one (relMSE; measured factors in docs/ACCURACY.md). 1 spp exercises the spatial variance estimate,
/// 4 spp the per-pixel one.
#[test]
fn denoising_cuts_the_error_against_mitsuba_at_low_spp() {
    let (ctx, _gpu) = gpu();
    let reference = cornell::reference();
    let mut app = cornell::app(ctx, true, cornell::SIZE, 11);
    let mut done = 0;
    for (spp, min_factor) in [(1, 3.0), (4, 2.0)] {
        app.accumulate(spp - done, 64, |_| {});
        done = spp;
        let noisy = app.radiance();
        let denoised = app.denoised_radiance();
        assert_all_finite(&denoised, "denoised Cornell box");
        let (before, after) = (
            rel_mse(&noisy, &reference, EPS),
            rel_mse(&denoised, &reference, EPS),
        );
        eprintln!(
            "{spp} spp: relMSE noisy {before:.3e}, denoised {after:.3e}: {:.2}x lower",
            before / after
        );
        assert!(
            before > min_factor * after,
            "{spp} spp: denoising lowered relMSE only {:.2}x ({before:.3e} -> {after:.3e}), expected > {min_factor}x",
            before / after
        );
    }
}

/// A flat region keeps its mean: a grey plane under a sunny map fills the view, so its radiance is flat over
/// the filter's whole footprint (and noisy: under the sky gradient, which BSDF sampling alone covers, a 1-spp
/// image of the plane is nearly converged). Over eight 1-spp images (seeds 1-8, each denoised on its own), every 8x8
/// block's mean of the denoised images must match a 64-spp reference within 1.5% (and better than the noisy
/// blocks do), and the denoised images' mean must match the noisy ones' (which is unbiased) within 0.75%. One
/// image's worst block was too unsteady a statistic: 1.9-3.5% over seeds 1-8 with the same sampler
/// (docs/BENCHMARKS.md, "Owen-scrambled Sobol' points"); a filter that shifts a flat block's mean by 2% fails.
#[test]
fn flat_region_keeps_its_mean() {
    let (ctx, _gpu) = gpu();
    let grey = Material {
        name: "grey".into(),
        base_color: glam::Vec4::new(0.5, 0.5, 0.5, 1.0),
        metallic: 0.0,
        roughness: 0.3,
        ..Default::default()
    };
    let scene = Arc::new(procedural::scene_from_meshes(
        "flat plane",
        vec![(procedural::ground_quad(40.0, 0), NodeTransform::default())],
        vec![grey],
    ));
    let size = 32;
    let settings = |seed| RenderSettings {
        width: size,
        height: size,
        max_depth: 2,
        environment: Environment::Map(raykin::environment::MapSettings {
            path: repo_root().join("tests/reference/lights/sunny_64x33.exr"),
            rotation_degrees: 30.0,
            strength: 1.0,
        }),
        seed,
        ..Default::default()
    };
    let camera = CameraChoice::LookAt {
        eye: glam::Vec3::new(0.0, 3.0, 1.0),
        target: glam::Vec3::ZERO,
        yfov: 30f32.to_radians(),
    };
    let reference = render(&ctx, &scene, settings(100), &camera, 64);
    let mut app = HeadlessApp::new(ctx, scene, settings(1), &camera).expect("uploads");
    let pixels = (size * size) as usize;
    let seeds = 1..=8u32;
    let weight = 1.0 / seeds.clone().count() as f32;
    let (mut noisy, mut denoised) = (vec![[0.0f32; 3]; pixels], vec![[0.0f32; 3]; pixels]);
    for seed in seeds {
        app.settings_mut().seed = seed;
        app.accumulate(1, 64, |_| {});
        let add = |sum: &mut Vec<[f32; 3]>, img: Vec<[f32; 3]>| {
            for (s, p) in sum.iter_mut().zip(img) {
                for c in 0..3 {
                    s[c] += p[c] * weight;
                }
            }
        };
        add(&mut noisy, app.radiance());
        add(&mut denoised, app.denoised_radiance());
    }
    let all: Vec<usize> = (0..pixels).collect();
    let sum = |img: &[[f32; 3]], pixels: &[usize]| -> f64 {
        pixels.iter().map(|&i| luminance(img[i])).sum()
    };
    let (mut worst_noisy, mut worst_denoised) = (0.0f64, 0.0f64);
    for by in 0..size as usize / 8 {
        for bx in 0..size as usize / 8 {
            let block: Vec<usize> = (0..64)
                .map(|k| (by * 8 + k / 8) * size as usize + bx * 8 + k % 8)
                .collect();
            let expected = sum(&reference, &block);
            worst_noisy = worst_noisy.max((sum(&noisy, &block) / expected - 1.0).abs());
            worst_denoised = worst_denoised.max((sum(&denoised, &block) / expected - 1.0).abs());
        }
    }
    let kept = sum(&denoised, &all) / sum(&noisy, &all);
    eprintln!(
        "flat plane, 8x8 blocks of 8 images' mean vs reference: worst noisy {:.2}%, worst denoised {:.2}%; \
         image denoised/noisy {kept:.4}",
        worst_noisy * 100.0,
        worst_denoised * 100.0
    );
    assert!(
        worst_denoised < 0.015 && worst_denoised < 0.8 * worst_noisy,
        "a flat 8x8 block is {:.2}% off the reference after denoising ({:.2}% before)",
        worst_denoised * 100.0,
        worst_noisy * 100.0
    );
    // 0.75%: one image measured -0.55% since the sky is sampled as a light (+0.3% before).
    assert!(
        (kept - 1.0).abs() < 0.0075,
        "denoising changed the flat image's mean by {:+.2}%",
        (kept - 1.0) * 100.0
    );
}

/// No net energy is gained or lost over a whole scene with finite variance (the Cornell box with a
/// single-sided light) at 16 spp. With the shipped double-sided light (heavy-tailed: light leaking from the
/// cavity above it) the filter, like SVGF, drops part of the fireflies' energy: measured and loosely bounded
/// (docs/ACCURACY.md).
#[test]
fn scene_energy_is_kept() {
    let (ctx, _gpu) = gpu();
    for (double_sided, bound) in [(false, 0.01), (true, 0.03)] {
        let mut app = cornell::app(ctx.clone(), double_sided, cornell::SIZE, 5);
        app.accumulate(16, 64, |_| {});
        let (noisy, denoised) = (app.radiance(), app.denoised_radiance());
        let total = |img: &[[f32; 3]]| img.iter().map(|p| luminance(*p)).sum::<f64>();
        let kept = total(&denoised) / total(&noisy);
        eprintln!("double-sided light {double_sided}: image denoised/noisy {kept:.4}");
        assert!(
            (kept - 1.0).abs() < bound,
            "double-sided light {double_sided}: denoising changed the image's energy by {:+.2}%",
            (kept - 1.0) * 100.0
        );
    }
}

/// Texture edges stay sharp (albedo is divided out before filtering and multiplied back), and the textured
/// plane keeps its energy. The contrast across checker edges must match a 128-spp reference; a plain blur of
/// the same input fails that bound, so the metric can tell.
#[test]
fn texture_edges_stay_sharp() {
    let (ctx, _gpu) = gpu();
    let scene = checker_scene();
    let mut converged = checker_app(ctx.clone(), &scene, 100);
    converged.accumulate(128, 64, |_| {});
    // Pixels are classified on the converged AOVs: a 4-spp albedo can call a mixed pixel pure.
    let (reference, aovs) = (converged.radiance(), converged.aovs());
    let mut app = checker_app(ctx, &scene, 1);
    app.accumulate(4, 64, |_| {});
    let (noisy, denoised) = (app.radiance(), app.denoised_radiance());
    // Both pixels on the plane (normal up), one on a light and one on a dark check (albedo 0.72 vs 0.10).
    let on_plane = |i: usize| aovs.normal[i][1] > 0.999;
    let pairs = adjacent_pairs(CHECKER_SIZE, |a, b| {
        let (la, lb) = (aovs.albedo[a][0], aovs.albedo[b][0]);
        on_plane(a) && on_plane(b) && la.max(lb) > 0.6 && la.min(lb) < 0.15
    });
    assert!(pairs.len() >= 40, "only {} checker-edge pairs", pairs.len());
    let images = EdgeImages {
        reference: &reference,
        noisy: &noisy,
        denoised: &denoised,
        size: CHECKER_SIZE,
    };
    assert_edges_kept("checker-edge", &pairs, &images, 0.1);
    let plane: Vec<usize> = (0..noisy.len()).filter(|&i| on_plane(i)).collect();
    let energy = |img: &[[f32; 3]]| plane.iter().map(|&i| luminance(img[i])).sum::<f64>();
    let kept = energy(&denoised) / energy(&noisy);
    eprintln!("textured plane: denoised/noisy energy {kept:.4}");
    // 2%: measured -1.66% since the sky is a light that next-event estimation samples (issue 15; within 1.5%
    // before): the a-trous weights favour darker neighbours a little more with that noise.
    assert!(
        (kept - 1.0).abs() < 0.02,
        "the textured plane's mean changed by {:+.2}%",
        (kept - 1.0) * 100.0
    );
}

/// Geometric edges (same albedo on both sides: creases and silhouettes between white surfaces of the
/// Cornell box) keep their contrast at 4 spp, thanks to the normal and depth guides.
#[test]
fn geometric_edges_stay_sharp() {
    let (ctx, _gpu) = gpu();
    let reference = cornell::reference();
    let mut app = cornell::app(ctx, true, cornell::SIZE, 21);
    app.accumulate(4, 64, |_| {});
    let (noisy, denoised, aovs) = (app.radiance(), app.denoised_radiance(), app.aovs());
    // The light's own outline is no geometric edge of the filter's (its emission is added back unfiltered),
    // and a blind blur would smear its radiance of 100 over every pair near it.
    let s = cornell::SIZE as i32;
    let near_light = |i: usize| {
        let (x, y) = ((i as i32) % s, (i as i32) / s);
        (-3..=3).any(|dy| {
            (-3..=3).any(|dx| {
                let (qx, qy) = (x + dx, y + dy);
                qx >= 0
                    && qy >= 0
                    && qx < s
                    && qy < s
                    && luminance(reference[(qy * s + qx) as usize]) > 2.0
            })
        })
    };
    let pairs = adjacent_pairs(cornell::SIZE, |a, b| {
        let (na, nb) = (
            glam::Vec3::from(aovs.normal[a]),
            glam::Vec3::from(aovs.normal[b]),
        );
        let same_albedo = (0..3).all(|c| (aovs.albedo[a][c] - aovs.albedo[b][c]).abs() < 0.02);
        let crease = na.dot(nb) < 0.9;
        let silhouette = (aovs.depth[a] / aovs.depth[b]).ln().abs() > 0.03;
        let hit = na != glam::Vec3::ZERO && nb != glam::Vec3::ZERO;
        let visible = (luminance(reference[a]) - luminance(reference[b])).abs() > 0.02;
        hit && same_albedo && (crease || silhouette) && visible && !near_light(a) && !near_light(b)
    });
    assert!(
        pairs.len() >= 30,
        "only {} geometric-edge pairs",
        pairs.len()
    );
    let images = EdgeImages {
        reference: &reference,
        noisy: &noisy,
        denoised: &denoised,
        size: cornell::SIZE,
    };
    assert_edges_kept("geometric-edge", &pairs, &images, 0.25);
}

/// The path tracer's raw accumulation per pixel: radiance + count, albedo + depth, normal + hits, moments.
type Accumulation = [Vec<[f32; 4]>; 4];

fn read_accumulation(app: &HeadlessApp) -> Accumulation {
    let t = app.view();
    [&t.accum, &t.albedo_depth, &t.normal_hits, &t.moments]
        .map(|b| bytemuck::cast_slice(&app.ctx.read_buffer(b, b.size())).to_vec())
}

fn write_accumulation(app: &HeadlessApp, data: &Accumulation) {
    let t = app.view();
    for (buffer, values) in [&t.accum, &t.albedo_depth, &t.normal_hits, &t.moments]
        .into_iter()
        .zip(data)
    {
        app.ctx
            .queue
            .write_buffer(buffer, 0, bytemuck::cast_slice::<[f32; 4], u8>(values));
    }
}

/// Rewrites the accumulation as if `samples` samples per pixel had been traced, with mean radiance `radiance`
/// (all of it scattered, so all of it is filtered), the app's first-hit AOVs and the given per-sample
/// luminance variance.
fn write_synthetic_accumulation(
    app: &HeadlessApp,
    radiance: &[[f32; 3]],
    samples: f32,
    per_sample_variance: &[f64],
) {
    let [accum, albedo_depth, normal, _] = read_accumulation(app);
    let mut synthetic: Accumulation = Default::default();
    for i in 0..radiance.len() {
        let scale = samples / accum[i][3];
        let r = radiance[i];
        let l = luminance(r);
        synthetic[0].push([r[0] * samples, r[1] * samples, r[2] * samples, samples]);
        synthetic[1].push(albedo_depth[i].map(|v| v * scale));
        synthetic[2].push(normal[i].map(|v| v * scale));
        synthetic[3].push([
            0.0,
            0.0,
            0.0,
            ((l * l + per_sample_variance[i]) * samples as f64) as f32,
        ]);
    }
    write_accumulation(app, &synthetic);
}

/// A converged input passes through nearly unchanged: Mitsuba's image, presented as 131072 spp with raykin's
/// AOVs and a per-sample standard deviation equal to the pixel's mean (at most 1; so the means are uncertain by
/// 0.28%, about the reference's real noise of 0.26%), comes back changed by less than its own noise (relMSE
/// 3.3e-5).
#[test]
fn converged_input_passes_through() {
    let (ctx, _gpu) = gpu();
    let reference = cornell::reference();
    let mut app = cornell::app(ctx, true, cornell::SIZE, 31);
    app.accumulate(4, 64, |_| {});
    // Capped at 1: emitters are exact in a real render (their emission bypasses the filter).
    let variance: Vec<f64> = reference
        .iter()
        .map(|r| luminance(*r).min(1.0).powi(2))
        .collect();
    write_synthetic_accumulation(&app, &reference, 131072.0, &variance);
    assert!(
        rel_mse(&app.radiance(), &reference, EPS) < 1e-10,
        "the synthetic accumulation must read back as the reference"
    );
    let denoised = app.denoised_radiance();
    let change = rel_mse(&denoised, &reference, EPS);
    let mut per_pixel: Vec<f64> = denoised
        .iter()
        .zip(&reference)
        .map(|(d, r)| (luminance(*d) - luminance(*r)).abs() / (luminance(*r) + 0.1))
        .collect();
    per_pixel.sort_by(f64::total_cmp);
    let p99 = per_pixel[per_pixel.len() * 99 / 100];
    eprintln!(
        "converged input: relMSE change {change:.2e}, 99th percentile relative change {p99:.4}, max {:.4}",
        per_pixel.last().unwrap()
    );
    assert!(
        change < 3e-5,
        "a converged image changed by relMSE {change:.2e}"
    );
    assert!(p99 < 0.02, "1% of pixels changed by more than {p99:.4}");
}

/// Extreme but NaN-free inputs (fireflies up to f32::MAX, infinite sums, zero albedo, zero-length normals)
/// give a finite, non-negative image; so does a real 1-spp render with its fireflies.
#[test]
fn extreme_inputs_stay_finite() {
    let (ctx, _gpu) = gpu();
    let size = 16;
    let mut app = cornell::app(ctx, true, size, 41);
    app.accumulate(1, 1, |_| {});
    let real = app.denoised_radiance();
    assert_all_finite(&real, "denoised 1-spp render");
    app.accumulate(3, 64, |_| {});
    let [mut accum, mut albedo, mut normal, mut moments] = read_accumulation(&app);
    let big = [1e6, 1e20, 1e30, f32::MAX, f32::INFINITY];
    for (k, i) in (0..accum.len()).step_by(7).enumerate() {
        let v = big[k % big.len()];
        accum[i] = [v, v * 0.5, v, accum[i][3]];
        moments[i][3] = if k % 2 == 0 { f32::MAX } else { v };
        if k % 3 == 0 {
            albedo[i] = [0.0, 0.0, 0.0, f32::MAX];
        }
        if k % 5 == 0 {
            normal[i] = [0.0, 0.0, 0.0, normal[i][3]];
        }
    }
    write_accumulation(&app, &[accum, albedo, normal, moments]);
    let denoised = app.denoised_radiance();
    assert_all_finite(&denoised, "denoised fireflies");
    let negative = denoised.iter().flatten().filter(|v| **v < 0.0).count();
    assert_eq!(negative, 0, "{negative} negative values");
}

/// The denoiser is display-side: turning it on and off mid-accumulation keeps every sample (no restart),
/// leaves the accumulated radiance and the plain display bit-identical to a run that never denoised, and
/// allocates nothing while it is off. With it on, the tone-mapped image shows the denoised radiance.
#[test]
fn denoise_switch_never_touches_accumulation() {
    let (ctx, _gpu) = gpu();
    let size = 16;
    let new_app = || {
        let mut app = cornell::app(ctx.clone(), true, size, 51);
        app.settings_mut().spp_per_frame = 2;
        app.settings_mut().denoiser = DenoiserKind::Svgf;
        // The viewer's path: denoise + tone map every frame, GPU timestamps read back.
        app.accumulation_mut().display_each_frame = true;
        app.set_time_passes(true);
        app
    };
    let (mut plain, mut toggled) = (new_app(), new_app());
    for frame in 0..4 {
        plain.step();
        toggled.settings_mut().denoise = frame == 1 || frame == 2;
        toggled.step();
        let times = toggled.pass_times();
        if let Some(t) = times
            && !toggled.app.world().resource::<RenderSettings>().denoise
        {
            assert_eq!(t.denoise_ms, 0.0, "frame {frame}: no denoise pass ran");
        }
    }
    assert_eq!(plain.samples(), 8);
    assert_eq!(
        toggled.samples(),
        8,
        "toggling the denoiser restarted accumulation"
    );
    assert_eq!(
        plain.app.world().resource::<Denoiser>().memory_bytes(),
        0,
        "a run that never denoised allocated denoiser buffers"
    );
    assert!(toggled.app.world().resource::<Denoiser>().memory_bytes() > 0);
    let bits =
        |img: Vec<[f32; 3]>| -> Vec<u32> { img.iter().flatten().map(|v| v.to_bits()).collect() };
    assert!(
        bits(plain.radiance()) == bits(toggled.radiance()),
        "accumulated radiance differs after toggling the denoiser"
    );
    assert_eq!(plain.display_rgba8(), toggled.display_rgba8());

    toggled.settings_mut().denoise = true;
    let shown = toggled.display_rgba8();
    assert_ne!(
        shown,
        plain.display_rgba8(),
        "the display ignores the denoiser"
    );
    // The tone mapper's input is the denoised radiance: a brighter denoised pixel displays brighter.
    let denoised = toggled.denoised_radiance();
    let noisy = toggled.radiance();
    let (mut agree, mut total) = (0, 0);
    for i in 0..denoised.len() {
        let d = luminance(denoised[i]) - luminance(noisy[i]);
        let plain_px = plain.display_rgba8()[4 * i + 1] as i32;
        let shown_px = shown[4 * i + 1] as i32;
        if d.abs() > 0.05 && plain_px < 250 && shown_px < 250 {
            total += 1;
            agree += ((shown_px - plain_px).signum() == d.signum() as i32) as usize;
        }
    }
    assert!(
        total > 10 && agree * 10 >= total * 9,
        "display follows the denoised image in {agree}/{total} pixels"
    );
}

/// Without the denoisers' inputs the trace pass runs a kernel compiled without them (`PATH_AOVS`), which differs
/// only where it puts the camera ray in the pixel (stratified over the pixel's samples there, independent where
/// the denoisers read the first-hit AOVs: shaders/sampler.wgsl): the radiance agrees with the kernel's with them
/// within the noise of two independent renders, and only the latter records AOVs. The box's light is
/// single-sided here, so that the noise has a finite variance to compare against.
#[test]
fn dropping_the_denoiser_inputs_changes_no_radiance() {
    let (ctx, _gpu) = gpu();
    let render = |keep: bool, seed: u32| {
        let mut app = cornell::app(ctx.clone(), false, 16, seed);
        app.set_keep_denoiser_inputs(keep);
        app.accumulate(1024, 64, |_| {});
        (app.radiance(), app.aovs())
    };
    let (with, aovs) = render(true, 5);
    let (without, no_aovs) = render(false, 5);
    let (other_seed, _) = render(false, 6);
    assert_all_finite(&with, "Cornell box");
    assert_all_finite(&without, "Cornell box without the inputs");
    assert!(
        with.iter().flatten().map(|&v| v as f64).sum::<f64>() > 0.0,
        "the box is lit"
    );
    // Two independent renders' relMSE is twice each one's error (~2e-3 at 1024 spp); a kernel that lost or added
    // light would sit above it (a 5% brightness change alone adds ~2.5e-3).
    let apart = rel_mse(&with, &without, cornell::EPS);
    let noise = rel_mse(&without, &other_seed, cornell::EPS);
    eprintln!("with / without the inputs: relMSE {apart:.3e}; two seeds without them: {noise:.3e}");
    assert!(
        apart < 2.0 * noise,
        "radiance with and without the denoisers' inputs differs by relMSE {apart:.3e}, beyond the noise {noise:.3e}"
    );
    assert_channel_means_within(
        "with / without the inputs",
        mean_rgb(&with),
        mean_rgb(&without),
        0.03,
    );
    let lit = |a: &raykin::render::Aovs| a.albedo.iter().flatten().filter(|&&v| v > 0.0).count();
    assert!(
        lit(&aovs) > 16 * 16,
        "the albedo AOV is recorded when the inputs are kept"
    );
    assert_eq!(lit(&no_aovs), 0, "no albedo AOV without the inputs");
}
