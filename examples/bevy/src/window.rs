//! The game in a window: the lava and stone meshes under an orbiting
//! camera, space toggles the cache, and a readout shows the GPU time of
//! the materials' passes (Bevy's opaque pass plus the plugin's), cached
//! or not. The cache runs as a game would ship it, `CacheMode::Auto`:
//! the governor measures on this GPU whether it pays, and the readout
//! shows its speed-up and state from Bevy's diagnostics.

use bevy::diagnostic::{DiagnosticPath, DiagnosticsStore};
use bevy::prelude::*;
use bevy::render::diagnostic::RenderDiagnosticsPlugin;
use shadecache_bevy::{CacheMode, CacheStats, ReprojectionCache};

use shadecache_bevy_harness::scene::{self, LavaMaterial, StoneMaterial};

const OPAQUE: &str = "render/main_opaque_pass_3d/elapsed_gpu";
const CACHE: &str = "render/shadecache/elapsed_gpu";

/// The readout's text.
#[derive(Component)]
struct Readout;

/// Opens the window and runs the game until it is closed. Without a
/// display, says so and exits (Bevy's window would panic).
pub fn run() {
    #[cfg(all(unix, not(target_os = "macos")))]
    if std::env::var_os("DISPLAY").is_none() && std::env::var_os("WAYLAND_DISPLAY").is_none() {
        eprintln!(
            "error: no display (neither DISPLAY nor WAYLAND_DISPLAY is set): run `compare` or `measure`, which are headless"
        );
        std::process::exit(2);
    }
    App::new()
        .add_plugins(DefaultPlugins.set(AssetPlugin {
            file_path: shadecache_bevy_harness::ASSETS.into(),
            ..default()
        }))
        .add_plugins((RenderDiagnosticsPlugin, scene::MaterialsPlugin::default()))
        .add_systems(Startup, setup)
        .add_systems(Update, (orbit, toggle, readout))
        .run();
}

fn setup(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<LavaMaterial>>,
    mut stone: ResMut<Assets<StoneMaterial>>,
    mut standard: ResMut<Assets<StandardMaterial>>,
) {
    scene::spawn_meshes(&mut commands, &mut meshes, &mut materials, true);
    scene::spawn_stone(&mut commands, &mut meshes, &mut stone);
    scene::spawn_props(&mut commands, &mut meshes, &mut standard, true);
    commands.spawn((
        Camera3d::default(),
        // The cache holds one value per pixel.
        Msaa::Off,
        // Bevy's default tonemapper needs the `tonemapping_luts` feature.
        bevy::core_pipeline::tonemapping::Tonemapping::None,
        ReprojectionCache {
            // Governed, and kept within 35 dB of Bevy's own frame.
            mode: CacheMode::Auto {
                min_psnr: Some(35.0),
            },
            ..default()
        },
        scene::orbit_at(0.0),
    ));
    commands.spawn((
        Text::new("…"),
        Node {
            position_type: PositionType::Absolute,
            top: px(12),
            left: px(12),
            ..default()
        },
        Readout,
    ));
}

/// A quarter turn every ten seconds.
fn orbit(time: Res<Time>, mut cameras: Query<&mut Transform, With<Camera3d>>) {
    for mut transform in &mut cameras {
        *transform = scene::orbit_at(time.elapsed_secs() * 9.0);
    }
}

fn toggle(keys: Res<ButtonInput<KeyCode>>, mut caches: Query<&mut ReprojectionCache>) {
    if keys.just_pressed(KeyCode::Space) {
        for mut cache in &mut caches {
            cache.enabled = !cache.enabled;
        }
    }
}

fn readout(
    store: Res<DiagnosticsStore>,
    stats: Res<CacheStats>,
    caches: Query<&ReprojectionCache>,
    mut text: Query<&mut Text, With<Readout>>,
) {
    let smoothed = |path: &'static str| {
        store
            .get(&DiagnosticPath::const_new(path))
            .and_then(|d| d.smoothed())
    };
    let enabled = caches.iter().any(|c| c.enabled);
    let opaque = smoothed(OPAQUE).unwrap_or(0.0);
    let cache = if enabled {
        smoothed(CACHE).unwrap_or(0.0)
    } else {
        0.0
    };
    let mut line = format!(
        "cache {} (space toggles)\nmaterial passes: {:.2} ms GPU (opaque {opaque:.2} + cache {cache:.2})",
        if enabled { "on" } else { "off" },
        opaque + cache
    );
    for material in ["LavaMaterial", "StoneMaterial"] {
        let diagnostic = |measure: &str| {
            store
                .get(&DiagnosticPath::new(format!(
                    "render/shadecache/{material}/{measure}"
                )))
                .and_then(|d| d.value())
        };
        if let Some(speedup) = diagnostic("speedup") {
            line.push_str(&format!(
                "\n{material}: governor {:.2}× [{:.2}, {:.2}], cache {}, Δn {}, watched {:.1} dB",
                speedup,
                diagnostic("speedup_low").unwrap_or(0.0),
                diagnostic("speedup_high").unwrap_or(0.0),
                if diagnostic("cached") == Some(1.0) {
                    "on"
                } else {
                    "off"
                },
                diagnostic("delta_n").unwrap_or(0.0),
                diagnostic("psnr").unwrap_or(f64::NAN)
            ));
        }
    }
    if let Some(err) = stats.errors().last() {
        line.push_str(&format!("\nerror: {err}"));
    }
    for mut text in &mut text {
        text.0.clone_from(&line);
    }
}
