//! The GPU time of the material's passes, cached or as Bevy draws it, from
//! Bevy's render diagnostics.
//!
//! One camera draws the game's scene along the path: the lava, and the
//! props in Bevy's `StandardMaterial` (a floor, a pillar, a crate, a glass
//! pane, a point light). Bevy's `RenderDiagnosticsPlugin` times its passes
//! with timestamp queries: the main opaque pass
//! (`render/main_opaque_pass_3d/elapsed_gpu`), which draws every opaque
//! mesh the cache does not, and the plugin's passes
//! (`render/shadecache/elapsed_gpu`), which draw the cached ones. Their
//! sum per frame, over the frames after Bevy's pipelines are ready, is the
//! time of the opaque meshes, with each material cached or not
//! ([`Cached`]): a material's cost and saving is the difference it makes.

use std::sync::{Arc, Mutex};

use bevy::app::AppExit;
use bevy::diagnostic::{DiagnosticPath, DiagnosticsStore};
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use shadecache_bevy::ReprojectionCache;

use crate::scene::{self, FrameCount};
use crate::{headless_app, run_to_exit, target_image, Deadline};

/// What a timing run does.
#[derive(Clone, Debug)]
pub struct Measure {
    /// The image's side, in pixels.
    pub size: u32,
    /// Frames timed, after the pipelines are ready.
    pub frames: u32,
    /// Which materials the camera draws through the cache.
    pub cached: Cached,
    /// Degrees the camera moves a frame.
    pub step_degrees: f32,
}

/// Which of the game's materials a timing run draws through the cache.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cached {
    /// None: every mesh as Bevy draws it.
    Nothing,
    /// The lava (one-pass, a custom material).
    Lava,
    /// The props (two-pass, Bevy's `StandardMaterial`).
    StandardMaterial,
    /// Both.
    Both,
}

impl Cached {
    /// Every configuration, in the order the measure runs them.
    pub const ALL: [Cached; 4] = [
        Cached::Nothing,
        Cached::Lava,
        Cached::StandardMaterial,
        Cached::Both,
    ];

    fn lava(self) -> bool {
        matches!(self, Cached::Lava | Cached::Both)
    }

    fn standard_material(self) -> bool {
        matches!(self, Cached::StandardMaterial | Cached::Both)
    }

    /// In words, for a table.
    pub fn name(self) -> &'static str {
        match self {
            Cached::Nothing => "nothing cached",
            Cached::Lava => "lava cached",
            Cached::StandardMaterial => "StandardMaterial cached",
            Cached::Both => "both cached",
        }
    }
}

/// GPU milliseconds of the opaque meshes' passes, one value a frame.
#[derive(Clone, Debug, Default)]
pub struct Measured {
    /// The opaque pass plus the plugin's passes, per frame timed.
    pub material_ms: Vec<f64>,
    /// Frames the plugin drew through the cache.
    pub frames_drawn: u64,
    /// Errors the plugin logged.
    pub errors: Vec<String>,
    /// The bytes of GPU memory the caches owned as the run ended.
    pub target_bytes: u64,
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
        target_bytes: stats.target_bytes(),
    }
}

fn setup(
    mut commands: Commands,
    run: Res<Run>,
    mut images: ResMut<Assets<Image>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<scene::LavaMaterial>>,
    mut standard: ResMut<Assets<StandardMaterial>>,
) {
    let settings = &run.0;
    let cached = settings.cached;
    scene::spawn_meshes(&mut commands, &mut meshes, &mut materials, cached.lava());
    scene::spawn_props(
        &mut commands,
        &mut meshes,
        &mut standard,
        cached.standard_material(),
    );
    let target = target_image(&mut images, settings.size, false);
    commands.spawn((
        scene::camera(target.clone(), settings.step_degrees),
        ReprojectionCache {
            enabled: cached != Cached::Nothing,
            ..default()
        },
    ));
    // Bevy's pipelines compile asynchronously: timing starts with the
    // first image with lava in it.
    commands.spawn(Readback::texture(target)).observe(
        |event: On<ReadbackComplete>, mut timing: ResMut<Timing>, frame: Res<FrameCount>| {
            if timing.ready_at.is_none()
                && crate::compare::lava_pixels(&crate::compare::channels(&event.data, false)) > 0
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
    // Frames more: the timestamps of the first ready frame come back a
    // few frames later, and the props' pipelines may be made after the
    // lava's (Bevy compiles each material's when it first meets it).
    let Some(ready) = timing.ready_at.filter(|&at| frame.0 > at + 30) else {
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
        (Some(opaque), _, Cached::Nothing) => Some(opaque),
        (Some(opaque), Some(cache), _) => Some(opaque + cache),
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
