//! The shadecache Bevy plugin's test harness: a game's scene run
//! headless, through the cache and as Bevy draws it. The plugin's tests
//! (`crates/shadecache-bevy/tests`) and the example game
//! (`examples/bevy`) use it; its build script is a game's build script,
//! rewriting the scene's materials into their variants.
//!
//! - [`scene`]: the materials (Bevy `Material`s with `assets/lava.wesl`
//!   and `assets/stone.wesl`, Bevy's `StandardMaterial`, an
//!   `ExtendedMaterial` with `assets/rim.wesl`), their variants as the
//!   build script wrote them, the meshes marked for the cache, the
//!   camera's path.
//! - [`compare`]: a headless run that draws each frame twice, through the
//!   cache and as Bevy draws the material, and compares the two (the
//!   plugin's tests).
//! - [`measure`]: a headless run of one camera, cached or not, that reads
//!   the GPU time of the material's passes from Bevy's render
//!   diagnostics (the figures in `docs/bevy.md`).

pub mod compare;
pub mod measure;
pub mod scene;

use std::time::{Duration, Instant};

use bevy::prelude::*;
use bevy::render::render_resource::{TextureFormat, TextureUsages};
use shadecache_bevy::CacheStats;

pub use compare::{
    run_headless, Compared, Headless, HeadlessRun, LeftToBevy, Masked, MaterialEdit, OtherMeshes,
};
pub use measure::{measure, Cached, Measure, Measured};

/// The scene's assets (the materials' shaders, the lava's scene for
/// `shadecache profile`): Bevy's `AssetPlugin::file_path` for an app that
/// draws the scene.
pub const ASSETS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets");

/// Bevy with the game's assets, its material and the cache, run headless
/// as fast as frames come, its cameras' path `step_degrees` a frame (the
/// runs move them with [`scene::move_cameras`]); with `diagnostics`, Bevy's
/// render diagnostics (GPU time per pass), which must be added with Bevy's
/// plugins.
/// With `compare`, Bevy compiles its pipelines before the frame that
/// needs them, so that both cameras' images hold every mesh from the first
/// frame compared (asynchronously, a material's pipeline can be ready for
/// one view's frame and not yet the other's).
fn headless_app(
    diagnostics: bool,
    step_degrees: f32,
    compare: bool,
    materials: scene::MaterialsPlugin,
) -> App {
    let mut app = App::new();
    let plugins = DefaultPlugins
        .set(AssetPlugin {
            file_path: ASSETS.into(),
            ..default()
        })
        .set(bevy::render::RenderPlugin {
            synchronous_pipeline_compilation: compare,
            ..default()
        });
    // Built with the window, the headless runs still open none.
    #[cfg(feature = "window")]
    let plugins = plugins
        .set(bevy::window::WindowPlugin {
            primary_window: None,
            exit_condition: bevy::window::ExitCondition::DontExit,
            ..default()
        })
        .disable::<bevy::winit::WinitPlugin>();
    app.add_plugins(plugins);
    if diagnostics {
        app.add_plugins(bevy::render::diagnostic::RenderDiagnosticsPlugin);
    }
    app.add_plugins((
        bevy::app::ScheduleRunnerPlugin::run_loop(std::time::Duration::ZERO),
        materials,
    ))
    // Time steps a 60 Hz frame each frame, whatever the frame took, as
    // `shadecache profile` steps its `time` uniform: the glow flows alike
    // in every run.
    .insert_resource(bevy::time::TimeUpdateStrategy::ManualDuration(
        std::time::Duration::from_secs_f64(1.0 / 60.0),
    ))
    .insert_resource(scene::Step(step_degrees))
    .init_resource::<scene::FrameCount>()
    .insert_resource(Deadline(Instant::now() + GIVE_UP_AFTER));
    app
}

/// How long a headless run waits for what it needs (Bevy's pipelines
/// compile asynchronously, slowly on a loaded CPU rasteriser) before it
/// ends with what it has.
const GIVE_UP_AFTER: Duration = Duration::from_secs(300);

/// When a headless run gives up.
#[derive(Resource, Clone, Copy)]
struct Deadline(Instant);

impl Deadline {
    fn passed(&self) -> bool {
        Instant::now() > self.0
    }
}

/// Runs `app` until a system exits it (its runner takes it); what its
/// systems left in `results`, and the plugin's stats.
fn run_to_exit<T: Default>(mut app: App, results: &std::sync::Mutex<T>) -> (T, CacheStats) {
    let stats = app.world().resource::<CacheStats>().clone();
    app.run();
    let left = std::mem::take(&mut *results.lock().unwrap_or_else(|p| p.into_inner()));
    (left, stats)
}

/// An image a camera draws into and the readback copies from: RGBA8 in
/// sRGB, as displayed, or `linear` (`rgba16float`).
fn target_image(images: &mut Assets<Image>, size: u32, linear: bool) -> Handle<Image> {
    let format = if linear {
        TextureFormat::Rgba16Float
    } else {
        TextureFormat::Rgba8UnormSrgb
    };
    let mut image = Image::new_target_texture(size, size, format, None);
    image.texture_descriptor.usage |= TextureUsages::COPY_SRC;
    images.add(image)
}
