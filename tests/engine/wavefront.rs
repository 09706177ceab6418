//! The wavefront form of the path integrator (`render::passes::wavefront`) traces the megakernel's paths: every
//! decision draws the same sampler dimension and the radiance is summed in the same order, so with one sample
//! per dispatch (both add each sample to the accumulation as it ends) the image is the same bit for bit, and
//! with several (a small view's waves hold several samples of each pixel) it differs only by the order the
//! accumulation adds them. Its image against Mitsuba's is checked
//! in `cornell_box_in_waves_matches_mitsuba_within_noise`.

use crate::common::cornell::{self, SIZE, camera};
use crate::common::*;
use raykin::camera::CameraChoice;
use raykin::headless::HeadlessApp;
use raykin::render::integrator_choice::IntegratorChoice;
use raykin::render::{Environment, Integrator, RenderSettings};
use std::sync::Arc;

/// A 24x20 view of `scene` under the sky, tracing with `integrator`, radiance only.
fn small_app(
    ctx: &raykin::gpu::GpuContext,
    scene: &Arc<raykin::scene::SceneAsset>,
    integrator: Integrator,
) -> HeadlessApp {
    let settings = RenderSettings {
        width: 24,
        height: 20,
        environment: Environment::Sky,
        integrator,
        ..Default::default()
    };
    let mut app = HeadlessApp::new(ctx.clone(), scene.clone(), settings, &CameraChoice::Auto)
        .expect("scene uploads");
    app.set_keep_denoiser_inputs(false);
    app
}

/// The waves' wide top level (`raykin::bvh::tlas`, built beside the BVH2 while they trace): the interior scene's
/// three top-level leaves (the box's merged tree, CesiumMan and the Fox) traced through it give the megakernel's
/// image bit for bit, with the scene read from storage buffers and from textures; the megakernel keeps the BVH2.
#[test]
fn waves_through_the_wide_top_level_trace_the_megakernels_paths() {
    use raykin::render::gpu_scene::GpuScene;
    let (ctx, _gpu) = gpu();
    let interior = raykin::animation::interior_scene(shared_assets()).expect("the interior scene");
    let scene = Arc::new(interior.scene);
    for textures in [true, false] {
        let mut ctx = ctx.clone();
        ctx.scene_in_textures = textures;
        ctx.wide_top_level = true;
        let render = |integrator: Integrator| {
            let mut app = small_app(&ctx, &scene, integrator);
            app.accumulate(4, 1, |_| {});
            let wide = app.app.world().resource::<GpuScene>().wide_top_level();
            (app.radiance(), wide)
        };
        let what = format!("the interior, textures {textures}");
        let (waves, wide) = render(Integrator::Wavefront);
        assert!(wide.is_some(), "{what}: the waves traced no wide top level");
        let (mega, mega_wide) = render(Integrator::Megakernel);
        assert_eq!(
            mega_wide, None,
            "{what}: the megakernel asked for the wide top level"
        );
        assert_forms_render_the_same_image(&waves, &mega, &what);
    }
}

/// Extend with refill (`shaders/traversal/refill.wgsl`): with one or two workgroups each invocation traces
/// dozens of rays, each started inside the traversal loop where the last ended, and the hits are those of the
/// one-ray-an-invocation extend, so the image is the same bit for bit: through the wide top level (the interior's
/// box, CesiumMan and the Fox; closest hits and shadow rays' any hits), through one merged tree (the Cornell box,
/// and alpha-blended surfaces passed through, each next segment started in the loop), sorted and not, from
/// storage buffers and from textures. A step that visited a node out of order, skipped an instance or ended a
/// shadow ray late would change some pixel.
#[test]
fn waves_with_refill_trace_the_same_hits() {
    use raykin::render::passes::wavefront::WavefrontSlot;
    let (ctx, _gpu) = gpu();
    let interior = raykin::animation::interior_scene(shared_assets()).expect("the interior scene");
    let scenes = [
        ("the interior", Arc::new(interior.scene)),
        ("the Cornell box", shared_scene("CornellBox/CornellBox.glb")),
        (
            "alpha blending",
            shared_scene("AlphaBlendModeTest/glTF-Binary/AlphaBlendModeTest.glb"),
        ),
    ];
    for (name, scene) in &scenes {
        for textures in [false, true] {
            let render = |refill: Option<u32>, sorted: bool| {
                let mut ctx = ctx.clone();
                ctx.scene_in_textures = textures;
                ctx.wide_top_level = true;
                ctx.wave_refill = refill;
                let mut app = small_app(&ctx, scene, Integrator::Wavefront);
                app.app
                    .world_mut()
                    .resource_mut::<IntegratorChoice>()
                    .force_ray_sort(Some(sorted));
                app.accumulate(4, 1, |_| {});
                let refilling = app
                    .app
                    .world()
                    .resource::<WavefrontSlot>()
                    .0
                    .as_ref()
                    .is_some_and(|pass| pass.refilling());
                assert_eq!(refilling, refill.is_some(), "{name}: extend with refill");
                let rays = app.view().read_ray_count(&app.ctx);
                (app.radiance(), rays)
            };
            for (groups, sorted) in [(1, false), (2, true)] {
                let what = format!("{name}, textures {textures}, {groups} groups, sorted {sorted}");
                let (plain, plain_rays) = render(None, sorted);
                let (refilled, refilled_rays) = render(Some(groups), sorted);
                assert_eq!(refilled_rays, plain_rays, "{what}: rays traced");
                assert!(
                    plain.iter().flatten().any(|&v| v > 0.0),
                    "{what}: the image is black"
                );
                assert_eq!(refilled, plain, "{what}: the refilled waves' image");
            }
        }
    }
}

#[test]
fn waves_trace_the_megakernels_paths() {
    let (ctx, _gpu) = gpu();
    // The Cornell box: emitters (next-event estimation, MIS on emissive hits), Russian roulette, paths leaving
    // through its open side. Alpha blending: paths that pass through surfaces without a bounce. Attenuation:
    // transmission and volumes (the medium carried between bounces).
    for file in [
        "CornellBox/CornellBox.glb",
        "AlphaBlendModeTest/glTF-Binary/AlphaBlendModeTest.glb",
        "AttenuationTest/glTF/AttenuationTest.gltf",
    ] {
        let scene = shared_scene(file);
        let render_sorted = |integrator: Integrator, spp: u32, chunk: u32, sorted: bool| {
            let mut app = small_app(&ctx, &scene, integrator);
            app.app
                .world_mut()
                .resource_mut::<IntegratorChoice>()
                .force_ray_sort(Some(sorted));
            app.accumulate(spp, chunk, |_| {});
            assert_eq!(
                app.integrator_choice().rays_sorted(),
                sorted && integrator == Integrator::Wavefront
            );
            let rays = app.view().read_ray_count(&app.ctx);
            (app.radiance(), rays)
        };
        let render = |integrator, spp, chunk| render_sorted(integrator, spp, chunk, false);
        let (waves, wave_rays) = render(Integrator::Wavefront, 6, 1);
        let (mega, mega_rays) = render(Integrator::Megakernel, 6, 1);
        assert_forms_render_the_same_image(&waves, &mega, file);
        assert_eq!(
            wave_rays, mega_rays,
            "{file}: rays traced by the last dispatch"
        );
        // Each bounce's rays sorted before extend traces them: the same paths in another order.
        let (sorted, sorted_rays) = render_sorted(Integrator::Wavefront, 6, 1, true);
        assert_forms_render_the_same_image(&sorted, &mega, file);
        assert_eq!(sorted_rays, mega_rays, "{file}: rays traced, sorted");
        // The sort switched on and off between one accumulation's dispatches, as auto's trial does: the queues
        // are made again with and without the sort's entries each time, and the paths stay the same.
        let mut app = small_app(&ctx, &scene, Integrator::Wavefront);
        for frame in 0..6 {
            app.app
                .world_mut()
                .resource_mut::<IntegratorChoice>()
                .force_ray_sort(Some(frame % 2 == 1));
            app.accumulate(1, 1, |_| {});
        }
        assert_eq!(app.radiance(), waves, "{file}: sorted every other dispatch");
        // Several samples per dispatch: the megakernel sums a pixel's samples before adding them, the waves
        // (here 3 samples of each pixel in one wave) add a wave's at its end.
        let worst = worst_relative_difference;
        let (waves3, _) = render(Integrator::Wavefront, 6, 3);
        let differ = worst(&waves3, &mega);
        assert!(
            differ < 1e-4,
            "{file}: 3-sample waves differ by {differ} (relative)"
        );
        // 20 samples in one dispatch: a wave of 16 samples of each pixel (the most), then one of 4.
        let (waves20, _) = render(Integrator::Wavefront, 20, 20);
        let (mega20, _) = render(Integrator::Megakernel, 20, 1);
        let differ = worst(&waves20, &mega20);
        assert!(
            differ < 1e-4,
            "{file}: 20 samples in waves of 16 and 4 differ by {differ} (relative)"
        );
        let (sorted20, _) = render_sorted(Integrator::Wavefront, 20, 20, true);
        assert_eq!(sorted20, waves20, "{file}: 20 samples in sorted waves");
    }
    // The adapter check at start-up asks for the storage buffers the engine's kernels bind: the waves' kernels
    // bind no more (tests/engine/realtime.rs, `the_adapter_check_asks_for_what_the_kernels_bind`).
    let most = ctx.pipelines.most_storage_buffers_per_stage();
    assert!(most <= raykin::gpu::MIN_STORAGE_BUFFERS_PER_STAGE, "{most}");
}

/// The Cornell box against Mitsuba 3's reference (tests/reference/cornell), traced in waves of 4 samples.
#[test]
fn cornell_box_in_waves_matches_mitsuba_within_noise() {
    let (ctx, _gpu) = gpu();
    let scene = cornell::scene();
    let settings = |seed| RenderSettings {
        integrator: Integrator::Wavefront,
        spp_per_frame: 4,
        ..cornell::settings(SIZE, seed)
    };
    let render = |seed| {
        let mut app = HeadlessApp::new(ctx.clone(), scene.clone(), settings(seed), &camera())
            .expect("scene uploads");
        app.set_keep_denoiser_inputs(false);
        app.accumulate(128, 4, |_| {});
        app.radiance()
    };
    let (a, b) = (render(1), render(2));
    assert_all_finite(&a, "waves, half a");
    let (ra, rb) = cornell::reference_halves();
    cornell::assert_agree_within_noise("Cornell box in waves vs Mitsuba", (&a, &b), (&ra, &rb));
}

/// `Integrator::Auto` times both forms on its first frames (here on the CPU adapter too, which otherwise keeps
/// the megakernel untimed), interleaved, and then keeps one; the image it accumulates across the switches is
/// the megakernel's bit for bit.
#[test]
fn auto_times_both_forms_and_keeps_the_image() {
    use raykin::render::integrator_choice::IntegratorChoice;
    let (ctx, _gpu) = gpu();
    let scene = shared_scene("CornellBox/CornellBox.glb");
    // A trial whose times spread is run again (at least four, for at least half a second of trace time, at
    // most 100); then the chosen form, here for four frames.
    let most_frames = 1004;
    // `frames`: how many to accumulate; None: until four frames after the decision.
    let render = |integrator: Integrator, trial: bool, frames: Option<usize>| {
        let mut app = small_app(&ctx, &scene, integrator);
        if trial {
            app.app
                .world_mut()
                .insert_resource(IntegratorChoice::new(true));
        }
        let mut forms = Vec::new();
        let mut decided_after = None;
        for frame in 0..most_frames {
            let enough = match frames {
                Some(n) => frame == n,
                None => decided_after.is_some_and(|d| frame >= d + 4),
            };
            if enough {
                break;
            }
            app.accumulate(1, 1, |_| {});
            forms.push(app.integrator_choice().last_form());
            if decided_after.is_none() && app.integrator_choice().decision().is_some() {
                decided_after = Some(frame + 1);
            }
        }
        let decision = app.integrator_choice().decision();
        (app.radiance(), forms, decision.zip(decided_after))
    };
    let (auto, forms, decision) = render(Integrator::Auto, true, None);
    let (decision, decided_after) = decision.expect("both forms timed within 100 trials");
    assert!(
        decision.megakernel_ms.is_finite() && decision.wavefront_ms.is_finite(),
        "{decision:?}"
    );
    let (mega, wave) = (Some(Integrator::Megakernel), Some(Integrator::Wavefront));
    // Each trial: one warm-up frame each, then four timed frames each in an ABBA BAAB order; then the chosen
    // form.
    let order = [mega, wave, mega, wave, wave, mega, wave, mega, mega, wave];
    assert!(
        decided_after % order.len() == 0 && decided_after <= 1000,
        "decided after {decided_after} frames"
    );
    for trial in forms[..decided_after].chunks(order.len()) {
        assert_eq!(trial, order, "{forms:?}");
    }
    assert!(
        forms[decided_after..]
            .iter()
            .all(|f| *f == Some(decision.chosen)),
        "{forms:?} after {decision:?}"
    );
    let (megakernel, mega_forms, _) = render(Integrator::Megakernel, false, Some(forms.len()));
    assert!(mega_forms.iter().all(|f| *f == mega));
    assert_forms_render_the_same_image(&auto, &megakernel, "auto's trial");
    // Without a trial (a CPU adapter, as this one is), Auto is the megakernel, untimed.
    let (_, cpu_forms, cpu_decision) = render(Integrator::Auto, false, Some(44));
    assert!(cpu_forms.iter().all(|f| *f == mega), "{cpu_forms:?}");
    assert_eq!(cpu_decision, None);
}
