//! The GPU time of the material's passes, cached or as Bevy draws it, from
//! Bevy's render diagnostics.
//!
//! One camera draws the scene along the path. Bevy's
//! `RenderDiagnosticsPlugin` times its passes with timestamp queries: the
//! main opaque pass (`render/main_opaque_pass_3d/elapsed_gpu`), which
//! draws the lava meshes when the cache is off and only clears when it is
//! on, and the plugin's passes (`render/shadecache/elapsed_gpu`). The
//! material's time is their sum, per frame, over the frames after Bevy's
//! pipelines are ready.

use std::sync::{Arc, Mutex};

use bevy::app::AppExit;
use bevy::diagnostic::{DiagnosticPath, DiagnosticsStore};
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use shadecache_bevy::ReprojectionCache;

use crate::scene::{self, FrameCount};
use crate::{drawn_pixels, headless_app, run_to_exit, target_image, Deadline};

/// What a timing run does.
#[derive(Clone, Debug)]
pub struct Measure {
    /// The image's side, in pixels.
    pub size: u32,
    /// Frames timed, after the pipelines are ready.
    pub frames: u32,
    /// Whether the camera draws through the cache.
    pub cached: bool,
    /// Degrees the camera moves a frame.
    pub step_degrees: f32,
}

/// GPU milliseconds of the material's passes, one value a frame.
#[derive(Clone, Debug, Default)]
pub struct Measured {
    /// The opaque pass plus the plugin's passes, per frame timed.
    pub material_ms: Vec<f64>,
    /// Frames the plugin drew through the cache.
    pub frames_drawn: u64,
    /// Errors the plugin logged.
    pub errors: Vec<String>,
}

impl Measured {
    /// The median and the 2.5th and 97.5th percentiles of the per-frame
    /// times.
    pub fn median_and_interval(&self) -> Option<(f64, f64, f64)> {
        use shadecache_bevy::shadecache_host::plan::speed::{median, quantile};
        let times = &self.material_ms;
        (!times.is_empty()).then(|| {
            (
                median(times),
                quantile(times, 0.025),
                quantile(times, 0.975),
            )
        })
    }
}

const OPAQUE: &str = "render/main_opaque_pass_3d/elapsed_gpu";
const CACHE: &str = "render/shadecache/elapsed_gpu";

#[derive(Resource, Clone)]
struct Run(Measure, Arc<Mutex<Vec<f64>>>);

/// Frames since Bevy first drew lava, and the times taken so far.
#[derive(Resource, Default)]
struct Timing {
    ready_at: Option<u32>,
    times: Vec<f64>,
}

/// Runs the scene headless with one camera, cached or not, and returns the
/// material's GPU time per frame.
pub fn measure(settings: Measure) -> Measured {
    let results = Arc::new(Mutex::new(Vec::new()));
    let mut app = headless_app(
        true,
        settings.step_degrees,
        false,
        crate::scene::MaterialsPlugin::default(),
    );
    app.insert_resource(Run(settings.clone(), results.clone()))
        .init_resource::<Timing>()
        .add_systems(Startup, setup)
        .add_systems(Update, (scene::move_cameras, take_times).chain());
    let (material_ms, stats) = run_to_exit(app, &results);
    Measured {
        material_ms,
        frames_drawn: stats.frames_drawn(),
        errors: stats.errors(),
    }
}

fn setup(
    mut commands: Commands,
    run: Res<Run>,
    mut images: ResMut<Assets<Image>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<scene::LavaMaterial>>,
) {
    scene::spawn_meshes(&mut commands, &mut meshes, &mut materials, true);
    let settings = &run.0;
    let target = target_image(&mut images, settings.size, false);
    commands.spawn((
        scene::camera(target.clone(), settings.step_degrees),
        ReprojectionCache {
            enabled: settings.cached,
            ..default()
        },
    ));
    // Bevy's pipelines compile asynchronously: timing starts with the
    // first image with lava in it.
    commands.spawn(Readback::texture(target)).observe(
        |event: On<ReadbackComplete>, mut timing: ResMut<Timing>, frame: Res<FrameCount>| {
            if timing.ready_at.is_none()
                && drawn_pixels(&crate::compare::channels(&event.data, false)) > 0
            {
                timing.ready_at = Some(frame.0);
            }
        },
    );
}

/// Takes each frame's newest measurements, once the pipelines are ready.
fn take_times(
    run: Res<Run>,
    store: Res<DiagnosticsStore>,
    frame: Res<FrameCount>,
    mut timing: ResMut<Timing>,
    deadline: Res<Deadline>,
    mut exit: MessageWriter<AppExit>,
) {
    let settings = &run.0;
    // A few frames more: the timestamps of the first ready frame come
    // back a few frames later.
    let Some(ready) = timing.ready_at.filter(|&at| frame.0 > at + 8) else {
        if deadline.passed() {
            exit.write(AppExit::Success);
        }
        return;
    };
    let newest = |path: &'static str| {
        store
            .get(&DiagnosticPath::const_new(path))
            .and_then(|d| d.measurement())
            .map(|m| m.value)
    };
    let opaque = newest(OPAQUE);
    let cache = newest(CACHE);
    let total = match (opaque, cache, settings.cached) {
        (Some(opaque), Some(cache), true) => Some(opaque + cache),
        (Some(opaque), _, false) => Some(opaque),
        _ => None,
    };
    if let Some(total) = total {
        timing.times.push(total);
    }
    // Without timestamp queries nothing comes: a bounded number of frames.
    let without_times = frame.0 > ready + 10 * settings.frames + 100;
    if timing.times.len() as u32 >= settings.frames || without_times || deadline.passed() {
        *run.1.lock().unwrap_or_else(|p| p.into_inner()) = timing.times.clone();
        exit.write(AppExit::Success);
    }
}
