//! A whole engine without a window: the frame schedule run N times, for the CLI, tests, recording and benches.

use crate::camera::{CameraChoice, CameraView, resolve_camera};
use crate::gpu::GpuContext;
use crate::render::{Aovs, RenderPlugin, RenderSettings, Renderer};
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
        let (renderer, notes) = Renderer::new(&ctx, &scene, &settings, binding_limit)?;
        let mut app = App::new();
        crate::configure_frame_schedule(&mut app);
        app.insert_resource(ctx.clone())
            .insert_resource(settings.clone())
            .insert_resource(renderer)
            .add_plugins(ScenePlugin {
                scene: scene.clone(),
            })
            .add_plugins(crate::animation::AnimationPlugin)
            .add_plugins(RenderPlugin)
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
        let world = self.app.world_mut();
        let roots: Vec<bevy_ecs::entity::Entity> = world
            .query_filtered::<bevy_ecs::entity::Entity, bevy_ecs::query::With<crate::scene::SceneRoot>>()
            .iter(world)
            .collect();
        for root in roots {
            world
                .entity_mut(root)
                .insert(crate::animation::AnimationPlayer::paused_at(clip, seconds));
        }
        Ok(())
    }

    /// BVH refit quality and rebuild counters.
    pub fn bvh_stats(&self) -> &crate::bvh::refit::BvhStats {
        self.app.world().resource::<crate::bvh::refit::BvhStats>()
    }

    pub fn settings_mut(&mut self) -> bevy_ecs::world::Mut<'_, RenderSettings> {
        self.app.world_mut().resource_mut::<RenderSettings>()
    }

    /// Drops the accumulated samples: the next frame starts from sample 0 (tests compare fresh
    /// accumulations of the same geometry).
    pub fn restart_accumulation(&mut self) {
        let ctx = self.ctx.clone();
        self.app
            .world_mut()
            .resource_mut::<Renderer>()
            .tracer
            .reset(&ctx);
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
        let mut done = 0;
        while done < spp {
            let n = chunk.clamp(1, spp - done);
            self.settings_mut().spp_per_frame = n;
            self.step();
            done += n;
            // Waiting per chunk keeps the GPU queue short (and lavapipe's memory flat).
            self.ctx.wait_idle();
            progress(done);
        }
    }

    /// The shading-free ray-casting pass (camera rays, plus one diffuse bounce per hit when asked) on the
    /// current pose and camera; `None` where the adapter has no timestamp queries.
    pub fn cast_rays(&mut self, diffuse_bounce: bool) -> Option<crate::render::RayCastTiming> {
        if self.renderer().frames == 0 {
            // Instances and the top-level BVH are uploaded by the first frame.
            self.step();
        }
        let world = self.app.world_mut();
        let settings = world.resource::<RenderSettings>().clone();
        let camera = *world.resource::<CameraView>();
        let mut renderer = world.resource_mut::<Renderer>();
        let renderer = &mut *renderer;
        renderer
            .tracer
            .resize(&self.ctx, settings.width, settings.height);
        renderer.tracer.cast_rays(
            &self.ctx,
            &renderer.scene,
            &settings,
            &camera,
            diffuse_bounce,
        )
    }

    pub fn renderer(&self) -> &Renderer {
        self.app.world().resource::<Renderer>()
    }

    pub fn samples(&self) -> u32 {
        self.renderer().tracer.samples
    }

    pub fn radiance(&self) -> Vec<[f32; 3]> {
        self.renderer().tracer.read_radiance(&self.ctx)
    }

    /// The current accumulation denoised with the settings' `denoise_params` (whether or not
    /// `RenderSettings::denoise` is on): linear RGB per pixel, row-major from the top-left.
    pub fn denoised_radiance(&self) -> Vec<[f32; 3]> {
        let params = self.app.world().resource::<RenderSettings>().denoise_params;
        self.renderer().tracer.denoised_radiance(&self.ctx, &params)
    }

    pub fn aovs(&self) -> Aovs {
        self.renderer().tracer.read_aovs(&self.ctx)
    }

    /// Tone-mapped sRGB RGBA8 of the current accumulation (denoised when `RenderSettings::denoise` is on).
    pub fn display_rgba8(&self) -> Vec<u8> {
        let settings = self.app.world().resource::<RenderSettings>().clone();
        let r = self.renderer();
        r.tracer.tonemap(&self.ctx, &settings);
        r.tracer.read_rgba8(&self.ctx)
    }
}
