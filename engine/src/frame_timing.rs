//! CPU time of each frame-schedule phase, stamped by marker systems between the chained `FrameSet`s, so the
//! systems themselves carry no timing code. The GPU passes are timed by timestamp queries (render module).

use crate::FrameSet;
use bevy_app::{App, Plugin, Update};
use bevy_ecs::prelude::*;
use std::time::Instant;

/// Milliseconds spent in each phase of the last frame (CPU side).
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct PhaseTimes {
    pub animate_ms: f64,
    pub transform_ms: f64,
    /// Skinning and morphing.
    pub deform_ms: f64,
    /// BLAS refit/rebuild, vertex upload of deformed meshes, top-level build and instance upload.
    pub bvh_ms: f64,
    pub upload_ms: f64,
    /// Encoding and submitting the GPU passes (and, when pass timing is on, waiting for them).
    pub render_ms: f64,
}

#[derive(Resource, Default)]
pub struct FrameTimings {
    marks: Vec<Instant>,
    pub last: PhaseTimes,
}

fn stamp(mut t: ResMut<FrameTimings>) {
    t.marks.push(Instant::now());
}

fn begin(mut t: ResMut<FrameTimings>) {
    t.marks.clear();
    t.marks.push(Instant::now());
}

fn finish(mut t: ResMut<FrameTimings>) {
    t.marks.push(Instant::now());
    let ms = |i: usize| t.marks[i + 1].duration_since(t.marks[i]).as_secs_f64() * 1e3;
    if t.marks.len() == 7 {
        t.last = PhaseTimes {
            animate_ms: ms(0),
            transform_ms: ms(1),
            deform_ms: ms(2),
            bvh_ms: ms(3),
            upload_ms: ms(4),
            render_ms: ms(5),
        };
    }
}

/// Adds the marker systems around every phase.
pub struct FrameTimingPlugin;

impl Plugin for FrameTimingPlugin {
    fn build(&self, app: &mut App) {
        use FrameSet::*;
        app.init_resource::<FrameTimings>().add_systems(
            Update,
            (
                begin.before(Animate),
                stamp.after(Animate).before(Transform),
                stamp.after(Transform).before(Deform),
                stamp.after(Deform).before(Bvh),
                stamp.after(Bvh).before(Upload),
                stamp.after(Upload).before(Render),
                finish.after(Render),
            )
                .chain(),
        );
    }
}
