//! A whole engine without a window: the frame schedule run N times, for the CLI, tests, recording and benches.

use crate::camera::{CameraChoice, CameraView, resolve_camera};
use crate::gpu::GpuContext;
use crate::render::{
    Accumulation, Aovs, DenoiserKind, FrameStats, GpuScene, HostDenoised, RenderPlugin,
    RenderSettings, ViewTargets,
};
use crate::scene::{SceneAsset, ScenePlugin};
use bevy_app::App;
use std::sync::Arc;

pub struct HeadlessApp {
    pub app: App,
    pub ctx: GpuContext,
    pub notes: Vec<String>,
}

#[derive(Debug, thiserror::Error)]
pub enum HeadlessError {
    #[error(transparent)]
    Upload(#[from] crate::render::UploadError),
    #[error(transparent)]
    Camera(#[from] crate::camera::NoSuchCamera),
}

impl HeadlessApp {
    /// Spawns the scene, uploads it, and places the camera (after one transform propagation).
    pub fn new(
        ctx: GpuContext,
        scene: Arc<SceneAsset>,
        settings: RenderSettings,
        camera: &CameraChoice,
    ) -> Result<Self, HeadlessError> {
        Self::with_binding_limit(ctx, scene, settings, camera, None)
    }

    pub fn with_binding_limit(
        ctx: GpuContext,
        scene: Arc<SceneAsset>,
        settings: RenderSettings,
        camera: &CameraChoice,
        binding_limit: Option<u64>,
    ) -> Result<Self, HeadlessError> {
        let mut app = App::new();
        let world = app.world_mut();
        let mut notes =
            crate::render::insert_resources(world, &ctx, &scene, &settings, binding_limit)?;
        notes.extend(crate::gpu_deform::insert_resources(
            world, &ctx, &scene, &settings,
        ));
        crate::configure_frame_schedule(&mut app);
        app.insert_resource(ctx.clone())
            .insert_resource(settings.clone())
            .init_resource::<crate::oidn::HeadlessOidn>()
            // OIDN per real-time frame, where the settings ask for it.
            .insert_resource(crate::render::frame_denoiser::FrameDenoiser::install(
                Box::<crate::oidn::OidnPerFrame>::default(),
            ))
            .add_plugins(ScenePlugin {
                scene: scene.clone(),
            })
            .add_plugins(crate::animation::AnimationPlugin)
            .add_plugins(RenderPlugin)
            .add_plugins(crate::gpu_deform::DeformPlugin)
            .add_plugins(crate::frame_timing::FrameTimingPlugin);
        // Transforms must be current before a camera node can be resolved.
        use bevy_ecs::system::RunSystemOnce;
        let _ = app
            .world_mut()
            .run_system_once(crate::scene::propagate_transforms);
        let aspect = settings.width as f32 / settings.height.max(1) as f32;
        let view = resolve_camera(app.world_mut(), &scene, camera, aspect)?;
        app.insert_resource(view);
        Ok(Self { app, ctx, notes })
    }

    /// Poses the scene at `seconds` into `clip` (held, not playing): the next [`Self::step`] renders exactly
    /// that pose, whatever frames ran before. Errors name the clips when `clip` does not exist.
    pub fn set_time(&mut self, clip: usize, seconds: f32) -> Result<(), String> {
        let scene = self
            .app
            .world()
            .resource::<crate::scene::SceneAssets>()
            .0
            .clone();
        if clip >= scene.animations.len() {
            return Err(match scene.animations.len() {
                0 => format!(
                    "{} has no animations, so it cannot be posed at a time",
                    scene.source
                ),
                n => format!(
                    "{}: no animation {clip}; the scene has {n} clip(s), 0..{}",
                    scene.source,
                    n - 1
                ),
            });
        }
        if !seconds.is_finite() {
            return Err(format!("time {seconds} is not a finite number of seconds"));
        }
        crate::animation::hold_at(self.app.world_mut(), clip, seconds);
        Ok(())
    }

    /// Poses the scene at `seconds` into `clip` (`None`: the file's rest pose) and places the camera as
    /// `camera` sees it in that pose (an animated glTF camera moves with its node). Unlike
    /// [`Self::set_time`] alone, node transforms are current when this returns.
    pub fn pose(
        &mut self,
        clip: Option<usize>,
        seconds: f32,
        camera: &CameraChoice,
    ) -> Result<(), String> {
        if let Some(clip) = clip {
            self.set_time(clip, seconds)?;
        }
        use bevy_ecs::system::RunSystemOnce;
        let world = self.app.world_mut();
        let _ = world.run_system_once(crate::animation::animate);
        let _ = world.run_system_once(crate::scene::propagate_transforms);
        let settings = world.resource::<RenderSettings>();
        let aspect = settings.width as f32 / settings.height.max(1) as f32;
        let scene = world.resource::<crate::scene::SceneAssets>().0.clone();
        let view = resolve_camera(world, &scene, camera, aspect).map_err(|e| e.to_string())?;
        self.set_camera(view);
        Ok(())
    }

    /// How deformed meshes' BVHs are rebuilt ([`RebuildPolicy::PoseDetermined`] for reproducible frames).
    pub fn set_rebuild_policy(&mut self, policy: crate::bvh::refit::RebuildPolicy) {
        self.app
            .world_mut()
            .resource_mut::<crate::bvh::refit::BvhStats>()
            .policy = policy;
    }

    /// Drops the accumulated samples: the next [`Self::step`] starts a new image (sample index 0).
    pub fn restart_accumulation(&mut self) {
        let world = self.app.world_mut();
        world.resource::<ViewTargets>().clear(&self.ctx);
        let mut accumulation = world.resource_mut::<Accumulation>();
        accumulation.samples = 0;
        accumulation.restart();
    }

    /// Whether the denoiser's inputs accumulate while the denoiser is off ([`Accumulation`]'s
    /// `keep_denoiser_inputs`): renders whose settings never switch it on turn this off to save the cost.
    pub fn set_keep_denoiser_inputs(&mut self, keep: bool) {
        self.accumulation_mut().keep_denoiser_inputs = keep;
    }

    /// Records the primary hit through each pixel centre from the next accumulation on ([`Self::primary_hits`]).
    pub fn set_hit_aov(&mut self, enabled: bool) {
        let ctx = self.ctx.clone();
        self.app
            .world_mut()
            .resource_mut::<ViewTargets>()
            .set_hit_aov(&ctx, enabled);
    }

    /// The primary hit through each pixel centre (empty unless [`Self::set_hit_aov`] is on).
    pub fn primary_hits(&self) -> Vec<crate::render::PrimaryHit> {
        self.view().read_hits(&self.ctx)
    }

    pub fn camera(&self) -> CameraView {
        *self.app.world().resource::<CameraView>()
    }

    pub fn scene(&self) -> Arc<SceneAsset> {
        self.app
            .world()
            .resource::<crate::scene::SceneAssets>()
            .0
            .clone()
    }

    /// BVH refit quality and rebuild counters.
    pub fn bvh_stats(&self) -> &crate::bvh::refit::BvhStats {
        self.app.world().resource::<crate::bvh::refit::BvhStats>()
    }

    pub fn settings_mut(&mut self) -> bevy_ecs::world::Mut<'_, RenderSettings> {
        self.app.world_mut().resource_mut::<RenderSettings>()
    }

    pub fn set_camera(&mut self, view: CameraView) {
        self.app.insert_resource(view);
    }

    /// Runs the frame schedule once (animation, transforms, deformation, BVH, upload, `spp_per_frame` samples).
    pub fn step(&mut self) {
        self.app.update();
    }

    /// Accumulates `spp` samples per pixel in frames of at most `chunk` samples; `progress(done)` after each.
    pub fn accumulate(&mut self, spp: u32, chunk: u32, mut progress: impl FnMut(u32)) {
        self.accumulate_while(spp, chunk, |done| {
            progress(done);
            true
        });
    }

    /// Like [`Self::accumulate`], but stops early after a chunk for which `progress(done)` returns false;
    /// returns the samples per pixel traced.
    pub fn accumulate_while(
        &mut self,
        spp: u32,
        chunk: u32,
        mut progress: impl FnMut(u32) -> bool,
    ) -> u32 {
        let mut done = 0;
        while done < spp {
            let n = chunk.clamp(1, spp - done);
            self.settings_mut().spp_per_frame = n;
            self.step();
            done += n;
            // Waiting per chunk keeps the GPU queue short (and lavapipe's memory flat).
            self.ctx.wait_idle();
            if !progress(done) {
                break;
            }
        }
        done
    }

    /// The shading-free ray-casting pass (camera rays, plus one diffuse bounce per hit when asked) on the
    /// current pose and camera; `None` where the adapter has no timestamp queries.
    pub fn cast_rays(&mut self, diffuse_bounce: bool) -> Option<crate::render::RayCastTiming> {
        self.prepare_ray_casting();
        crate::render::queries::cast_rays(self.app.world(), diffuse_bounce)
    }

    /// The scene uploaded (by a first frame) and the view at the settings' size.
    fn prepare_ray_casting(&mut self) {
        if self.frame_stats().frames == 0 {
            // Instances and the top-level BVH are uploaded by the first frame.
            self.step();
        }
        let world = self.app.world_mut();
        let (width, height) = {
            let s = world.resource::<RenderSettings>();
            (s.width, s.height)
        };
        world
            .resource_mut::<ViewTargets>()
            .resize(&self.ctx, width, height);
    }

    /// The rays of [`Self::cast_rays`] once more, counting their traversal work (nodes fetched by kind,
    /// triangles tested) instead of timing it; with the number of rays cast.
    pub fn count_traversal_work(
        &mut self,
        diffuse_bounce: bool,
    ) -> (crate::render::passes::raycast::TraversalWork, u64) {
        self.prepare_ray_casting();
        crate::render::queries::count_traversal_work(self.app.world(), diffuse_bounce)
    }

    /// The scene's GPU buffers (mesh slots, materials, emitters, memory).
    pub fn gpu_scene(&self) -> &GpuScene {
        self.app.world().resource::<GpuScene>()
    }

    /// The view's render targets.
    pub fn view(&self) -> &ViewTargets {
        self.app.world().resource::<ViewTargets>()
    }

    pub fn accumulation_mut(&mut self) -> bevy_ecs::world::Mut<'_, Accumulation> {
        self.app.world_mut().resource_mut::<Accumulation>()
    }

    /// GPU pass times and frame counts.
    pub fn frame_stats(&self) -> &FrameStats {
        self.app.world().resource::<FrameStats>()
    }

    /// Which form of the path integrator traced the last frame, and `Integrator::Auto`'s trial outcome.
    pub fn integrator_choice(&self) -> &crate::render::integrator_choice::IntegratorChoice {
        self.app
            .world()
            .resource::<crate::render::integrator_choice::IntegratorChoice>()
    }

    /// GPU times of the last frame's passes (set while `FrameStats::time_passes` is on).
    pub fn pass_times(&self) -> Option<crate::render::PassTimes> {
        self.frame_stats().last_pass_times
    }

    /// Times every frame's passes on the GPU from now on (blocks the CPU each frame; benches).
    pub fn set_time_passes(&mut self, on: bool) {
        self.app
            .world_mut()
            .resource_mut::<FrameStats>()
            .time_passes = on;
    }

    /// The GPU deformation state (backend in use, the deformer when the GPU deforms).
    pub fn deformation(&self) -> &crate::gpu_deform::GpuDeformation {
        self.app
            .world()
            .resource::<crate::gpu_deform::GpuDeformation>()
    }

    pub fn samples(&self) -> u32 {
        self.app.world().resource::<Accumulation>().samples
    }

    pub fn radiance(&self) -> Vec<[f32; 3]> {
        self.view().read_radiance(&self.ctx)
    }

    /// The current accumulation denoised with the settings' `denoise_params` (whether or not
    /// `RenderSettings::denoise` is on): linear RGB per pixel, row-major from the top-left.
    pub fn denoised_radiance(&self) -> Vec<[f32; 3]> {
        crate::render::queries::denoised_radiance(self.app.world())
    }

    /// The current accumulation through Open Image Denoise with the settings' `oidn` options (whether or not
    /// `RenderSettings::denoise` is on), with its timings; blocks. Errors say why OIDN cannot run.
    pub fn oidn_denoised(&self) -> Result<crate::oidn::OidnImage, crate::oidn::OidnError> {
        let options = self.app.world().resource::<RenderSettings>().oidn;
        self.app
            .world()
            .resource::<crate::oidn::HeadlessOidn>()
            .denoise(
                &self.ctx,
                self.view(),
                self.app.world().resource::<Accumulation>(),
                options,
            )
    }

    /// Opens OIDN's device now (it is otherwise opened at the first OIDN denoise): its description, or why
    /// OIDN cannot run (then the svgf denoiser stands in).
    pub fn open_oidn(&self) -> Result<String, crate::oidn::OidnError> {
        self.app
            .world()
            .resource::<crate::oidn::HeadlessOidn>()
            .open(&self.ctx)
    }

    /// With `denoise` on and OIDN chosen, opens OIDN's device now: `Some(Ok(device))`; when OIDN cannot run,
    /// switches this app's settings to svgf and returns `Some(Err(why))` for the caller to report. `None`
    /// when the settings do not ask for OIDN.
    pub fn resolve_denoiser(&mut self) -> Option<Result<String, crate::oidn::OidnError>> {
        let s = self.app.world().resource::<RenderSettings>();
        if !(s.denoise && s.denoiser == DenoiserKind::Oidn) {
            return None;
        }
        let opened = self.open_oidn();
        if opened.is_err() {
            self.settings_mut().denoiser = DenoiserKind::Svgf;
        }
        Some(opened)
    }

    /// The denoised image the settings ask for: OIDN's, or svgf's when the settings pick svgf or OIDN fails
    /// (with a warning).
    fn chosen_denoised(&self) -> Vec<[f32; 3]> {
        if self.app.world().resource::<RenderSettings>().denoiser == DenoiserKind::Oidn {
            match self.oidn_denoised() {
                Ok(image) => return image.color.to_vec(),
                Err(e) => tracing::warn!("{e}; denoising with svgf instead"),
            }
        }
        self.denoised_radiance()
    }

    /// The image an output file takes: denoised by the settings' denoiser when `RenderSettings::denoise` is
    /// on, else [`Self::radiance`] (as the display pass follows the same settings).
    pub fn output_radiance(&self) -> Vec<[f32; 3]> {
        if self.app.world().resource::<RenderSettings>().denoise {
            self.chosen_denoised()
        } else {
            self.radiance()
        }
    }

    /// The linear radiance the display shows (the real-time image, the hand-over's mix or the accumulation).
    pub fn displayed_radiance(&self) -> Vec<[f32; 3]> {
        crate::render::queries::displayed_radiance(self.app.world())
    }

    /// The real-time path's colour history: mean radiance and history length per pixel.
    pub fn realtime_history(&self) -> Vec<([f32; 3], f32)> {
        crate::render::queries::realtime_history(self.app.world())
    }

    /// What OIDN per frame did since the last call (taken: `None` when no real-time frame went to it), or why
    /// it failed (then the real-time path uses its a-trous filter).
    pub fn take_frame_denoise_report(
        &mut self,
    ) -> Result<Option<crate::render::frame_denoiser::FrameDenoiseReport>, String> {
        let mut d = self
            .app
            .world_mut()
            .resource_mut::<crate::render::frame_denoiser::FrameDenoiser>();
        match &d.failed {
            Some(why) => Err(why.clone()),
            None => Ok(d.last.take()),
        }
    }

    /// The real-time G-buffer of the last real-time frame.
    pub fn realtime_gbuffer(&self) -> Vec<crate::render::layout::GpuSurface> {
        crate::render::queries::realtime_gbuffer(self.app.world())
    }

    /// This frame's GPU instance (top-level BVH leaf order, as `PrimaryHit::instance`) of a real-time stable
    /// object id (`GpuSurface::object`).
    pub fn instance_of_object(&self, object: u32) -> Option<u32> {
        let world = self.app.world();
        let entity = world
            .resource::<crate::render::realtime::scene_motion::MotionObjects>()
            .entity(object)?;
        world
            .resource::<crate::render::gpu_scene::InstanceMap>()
            .entities
            .iter()
            .position(|e| *e == entity)
            .map(|i| i as u32)
    }

    /// The entity behind a real-time stable object id.
    pub fn entity_of_object(&self, object: u32) -> Option<bevy_ecs::entity::Entity> {
        self.app
            .world()
            .resource::<crate::render::realtime::scene_motion::MotionObjects>()
            .entity(object)
    }

    /// Drops every real-time history at the next frame (a camera cut the renderer cannot see).
    pub fn reset_realtime_history(&mut self) {
        self.app
            .world_mut()
            .resource_mut::<crate::render::realtime::Realtime>()
            .state
            .reset_requested = true;
    }

    /// The first-hit AOVs of the accumulation: recorded while the denoiser's inputs are kept
    /// ([`Self::set_keep_denoiser_inputs`], the default) or a denoiser is on; otherwise what the targets held.
    pub fn aovs(&self) -> Aovs {
        self.view().read_aovs(&self.ctx, self.samples())
    }

    /// Tone-mapped sRGB RGBA8 of the current accumulation (denoised when `RenderSettings::denoise` is on).
    pub fn display_rgba8(&self) -> Vec<u8> {
        let settings = self.app.world().resource::<RenderSettings>();
        if settings.denoise && settings.denoiser == DenoiserKind::Oidn {
            // The display shows OIDN's image once it holds it for this accumulation, svgf's otherwise.
            if let Ok(image) = self.oidn_denoised() {
                let world = self.app.world();
                world.resource::<HostDenoised>().show(
                    &self.ctx,
                    world.resource::<ViewTargets>(),
                    world.resource::<Accumulation>(),
                    &image.color,
                );
            }
        }
        crate::render::queries::display_rgba8(self.app.world())
    }
}
