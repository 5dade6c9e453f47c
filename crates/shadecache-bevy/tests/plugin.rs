//! The shadecache Bevy plugin in a headless Bevy app on the example's
//! scene: each frame is drawn twice, through the cache and as Bevy draws
//! the material itself, and the two images are compared. Bevy apps own
//! the process's render thread and device, so the runs take turns. They
//! need a GPU adapter (lavapipe will do), unless
//! `SHADECACHE_SKIP_GPU_TESTS=1` says to skip them where there is none.

use std::path::Path;
use std::sync::Mutex;

use shadecache_bevy::CacheMode;
use shadecache_bevy_harness::{
    run_headless, Compared, Headless, HeadlessRun, LeftToBevy, Masked, MaterialEdit, OtherMeshes,
};

#[path = "../../shadecache-bevy-harness/lava_build.rs"]
#[allow(dead_code)] // the build script's `game_build`
mod lava_build;

static ONE_APP_AT_A_TIME: Mutex<()> = Mutex::new(());

/// Whether the test is skipped: no GPU adapter, and
/// `SHADECACHE_SKIP_GPU_TESTS=1` (without it, no adapter is a failure
/// that says so, as in the other crates' tests).
fn skipped() -> bool {
    if shadecache_test_support::adapter().is_some() {
        return false;
    }
    shadecache_test_support::no_adapter();
    true
}

/// The frames compared; the run must have drawn every one through the
/// cache, without an error.
fn run(settings: Headless) -> Vec<Compared> {
    run_with_cut(settings).0
}

/// [`run`], and the frame a cut was marked in.
fn run_with_cut(settings: Headless) -> (Vec<Compared>, Option<u32>) {
    let run = in_turn(settings);
    assert!(run.errors.is_empty(), "{:?}", run.errors);
    assert!(
        run.frames_drawn >= run.compared.len() as u64,
        "{} frames drawn through the cache, {} compared",
        run.frames_drawn,
        run.compared.len()
    );
    (run.compared, run.cut_frame)
}

/// The headless run, once no other test's app is running.
fn in_turn(settings: Headless) -> HeadlessRun {
    let _turn = ONE_APP_AT_A_TIME.lock().unwrap_or_else(|p| p.into_inner());
    run_headless(settings)
}

/// Every frame of `frames` has the lava in it and is Bevy's own (to
/// within 8-bit rounding).
fn all_bevys_own<'a>(frames: impl IntoIterator<Item = &'a Compared>) {
    for frame in frames {
        assert!(frame.lava_pixels > 1000, "{frame:?}");
        assert!(frame.max_error <= 1.0 / 255.0, "{frame:?}");
    }
}

/// With Δn = 1 every pixel is computed every frame, so the variant's pass,
/// drawn with Bevy's view, mesh and material bind groups and Bevy's
/// `DrawMesh`, is Bevy's own frame: the one-pass variant writes what it
/// computes, so equal to the bit.
#[test]
fn bevy_plugin_at_refresh_period_one_equals_the_uncached_frame() {
    if skipped() {
        return;
    }
    let compared = run(Headless {
        refresh_period: Some(1),
        ..Headless::default()
    });
    assert!(compared.len() >= 24, "{} frames compared", compared.len());
    all_bevys_own(&compared);
}

/// At Δn = 1, with `others` beside the lava (and what `with` sets), every
/// frame is Bevy's own to the bit, each drawn through the cache without
/// an error ([`run`]).
fn bevys_own_frames_with(others: OtherMeshes, with: Headless) {
    let compared = run(Headless {
        refresh_period: Some(1),
        other_meshes: others,
        frames: 10,
        ..with
    });
    assert!(compared.len() >= 10, "{} frames compared", compared.len());
    all_bevys_own(&compared);
}

/// An opaque box of Bevy's before the lava sphere hides it: the cached
/// passes test against the depth Bevy's opaque pass left (with the
/// variant's own depth the lava was drawn over the box).
#[test]
fn cached_mesh_is_occluded_by_bevys_meshes() {
    if skipped() {
        return;
    }
    bevys_own_frames_with(OtherMeshes::OpaqueInFront, Headless::default());
}

/// A translucent pane of Bevy's behind the lava sphere is hidden by it:
/// the cached passes write the view's depth, which Bevy's transparent
/// pass tests against (without, the pane blended over the sphere).
#[test]
fn cached_mesh_occludes_bevys_meshes() {
    if skipped() {
        return;
    }
    bevys_own_frames_with(OtherMeshes::TranslucentBehind, Headless::default());
}

/// A translucent pane before the lava sphere blends over it: the cached
/// passes run before Bevy's transparent pass (after it, the lava was
/// drawn over the pane).
#[test]
fn transparent_mesh_over_cached_mesh_blends_in_order() {
    if skipped() {
        return;
    }
    bevys_own_frames_with(OtherMeshes::TranslucentInFront, Headless::default());
}

/// With Bevy's depth prepass on the cameras (TAA's and SSAO's), the
/// view's depth holds the cached meshes' own depth before their passes
/// run; their tests pass on equal depth, so the frame is still Bevy's own
/// (with the plan's strict `less`/`greater`, the lava hid itself).
#[test]
fn cached_mesh_is_drawn_over_its_own_depth_prepass() {
    if skipped() {
        return;
    }
    bevys_own_frames_with(
        OtherMeshes::All,
        Headless {
            depth_prepass: true,
            ..Headless::default()
        },
    );
}

/// All of them at once, with a floor the sphere sinks into.
#[test]
fn bevy_plugin_shares_the_depth_of_bevys_own_meshes() {
    if skipped() {
        return;
    }
    bevys_own_frames_with(OtherMeshes::All, Headless::default());
}

/// A lava mesh marked for the cache that the variant cannot draw as Bevy
/// does is left to Bevy with a reason, once, while the others are cached:
/// every frame is Bevy's own at Δn = 1 (drawn by both, a blended mesh
/// was drawn twice).
fn left_to_bevy_with_a_reason(which: LeftToBevy, reason: &str) {
    let run = in_turn(Headless {
        refresh_period: Some(1),
        left_to_bevy: Some(which),
        frames: 10,
        ..Headless::default()
    });
    assert!(run.frames_drawn > 0, "{:?}", run.errors);
    let said: Vec<&String> = run.errors.iter().filter(|e| e.contains(reason)).collect();
    assert_eq!(said.len(), 1, "{:?}", run.errors);
    assert_eq!(run.errors.len(), 1, "{:?}", run.errors);
    assert!(
        run.compared.len() >= 10,
        "{} frames compared",
        run.compared.len()
    );
    all_bevys_own(&run.compared);
}

#[test]
fn alpha_blend_mesh_is_left_to_bevy_with_a_reason() {
    if skipped() {
        return;
    }
    left_to_bevy_with_a_reason(LeftToBevy::AlphaBlend, "drawn with alpha mode Blend");
}

#[test]
fn lightmapped_mesh_is_left_to_bevy_with_a_reason() {
    if skipped() {
        return;
    }
    left_to_bevy_with_a_reason(LeftToBevy::Lightmapped, "lightmapped");
}

/// A lava mesh with vertex colours, where the lava's cache has no build
/// composed with `VERTEX_COLORS`: Bevy composes that mesh's pipeline
/// otherwise than the variant was, so it is left to Bevy, the def named in
/// the reason. Without the check of the plan's defs against Bevy's, the
/// mesh is drawn through the variant (white vertex colours leave the
/// lava's colour as it is, so only the check can tell).
#[test]
fn mesh_bevy_composes_otherwise_is_left_to_bevy_with_a_reason() {
    if skipped() {
        return;
    }
    left_to_bevy_with_a_reason(
        LeftToBevy::ComposedOtherwise,
        "VERTEX_COLORS: Bevy set, the variant unset",
    );
}

/// A camera drawing into the right half of its target (split screen):
/// the variant's passes draw into its viewport and map last frame's
/// positions into it, so at Δn = 1 every frame is Bevy's own, lava
/// included, and at the plan's Δn under a moving camera the lava is reused
/// (past the start's transient every frame differs from Bevy's) within
/// the error the whole-target view has. Without the viewport's corner in
/// the lookups, last frame's positions fell in the target's left half,
/// where the cache holds nothing of this view, and every pixel missed.
#[test]
fn split_screen_viewport_is_honoured() {
    if skipped() {
        return;
    }
    bevys_own_at_one_then_reusing(
        Headless {
            half_viewport: true,
            ..Headless::default()
        },
        72,
        "split screen",
    );
}

/// `with` at Δn = 1 for 8 frames: every frame is Bevy's own. Then for
/// `frames` at the plan's Δn: the last 24 reuse, each above 30 dB (their
/// PSNRs said on stderr, as `what`).
fn bevys_own_at_one_then_reusing(with: Headless, frames: u32, what: &str) {
    let run = in_turn(Headless {
        refresh_period: Some(1),
        frames: 8,
        ..with.clone()
    });
    assert!(run.errors.is_empty(), "{:?}", run.errors);
    assert!(run.frames_drawn >= 8, "{} frames drawn", run.frames_drawn);
    all_bevys_own(&run.compared);

    let run = in_turn(Headless { frames, ..with });
    assert!(run.errors.is_empty(), "{:?}", run.errors);
    let steady = &run.compared[run.compared.len() - 24..];
    let psnr: Vec<String> = steady.iter().map(|f| format!("{:.1}", f.psnr)).collect();
    eprintln!("{what}, PSNR of the steady frames: {}", psnr.join(" "));
    assert!(
        steady.iter().all(|f| f.max_error > 0.0),
        "a frame equals Bevy's: nothing was reused\n{steady:?}"
    );
    assert!(
        steady.iter().all(|f| f.psnr > 30.0),
        "the reused lava is far from Bevy's\n{steady:?}"
    );
}

/// Frames the cache runs after its cold start before its error is
/// measured, and the frames measured. The warm-up is one refresh period
/// (Δn = 32) and the frame after it: Δn frames after a cold start nearly
/// every value reaches age Δn together and is recomputed (docs/rewrite.md,
/// "Bounded staleness"), a transient of the start that the steady state
/// leaves out.
const WARMUP: u32 = 33;
const MEASURED: u32 = 32;

/// With the plan's Δn (32) under an orbiting camera the cache reuses last
/// frame's crust, and its error is what `shadecache profile` measures on
/// the same material and motion: the shader the build script composed, on
/// `assets/lava.toml` (the game's meshes, camera path, projection and
/// time step), from the frame the plugin's cache started cold at. Both
/// are PSNR over the whole frame in linear float (the plugin's frames in
/// HDR), mean over the same frames of the path.
#[test]
fn bevy_plugin_reuses_under_camera_motion() {
    if skipped() {
        return;
    }
    // A cut a few frames after both images show lava (the plugin caches a
    // mesh from the frame after Bevy's pipeline for it is made, so the
    // first frames with lava can be Bevy's own): the plugin's cache
    // starts cold at a known frame of the camera's path.
    let (compared, cut) = run_with_cut(Headless {
        frames: WARMUP + MEASURED + 8,
        cut_after: Some(4),
        linear: true,
        ..Headless::default()
    });
    let cut = cut.expect("the cut was marked");
    // The frame drawn at the cut comes back a few frames later (Bevy
    // renders a frame behind and reads back after that): the first frame
    // after it equal to Bevy's, every pixel computed.
    let cold = compared
        .iter()
        .find(|f| f.frame > cut && f.max_error == 0.0)
        .unwrap_or_else(|| panic!("no frame after the cut misses everywhere: {compared:?}"));
    let window = cold.frame + WARMUP..cold.frame + WARMUP + MEASURED;
    let steady: Vec<&Compared> = compared
        .iter()
        .filter(|f| window.contains(&f.frame))
        .collect();
    assert!(steady.len() as u32 >= MEASURED - 2, "{compared:?}");
    assert!(
        steady.iter().all(|f| f.max_error > 0.0),
        "a frame equals Bevy's: nothing was reused\n{steady:?}"
    );
    let plugin = mean(steady.iter().map(|f| f.psnr.min(PSNR_CAP)));

    let profiled = profile_from(cut);
    assert_eq!(profiled.len() as u32, MEASURED);
    let profiled = mean(profiled.into_iter());
    eprintln!(
        "PSNR over frames {window:?} after the cut at {cut}: plugin {plugin:.2} dB, profile {profiled:.2} dB"
    );
    assert!(
        (plugin - profiled).abs() <= 0.5,
        "the plugin's PSNR is {plugin:.2} dB, the profiler's {profiled:.2} dB on the same material and motion\n{steady:?}"
    );
}

/// The profiler's cap on PSNR (identical frames).
const PSNR_CAP: f64 = 100.0;

fn mean(values: impl Iterator<Item = f64>) -> f64 {
    let values: Vec<f64> = values.collect();
    values.iter().sum::<f64>() / values.len().max(1) as f64
}

/// What `shadecache profile` measures of the game's variant: the
/// whole-frame PSNR of each measured frame of the one-pass variant of the
/// build's node, Δn = 32, on `assets/lava.toml` started `start_frame`
/// frames into its motion.
fn profile_from(start_frame: u32) -> Vec<f64> {
    use shadecache::profile::{self, Nodes, Quiet};
    // naga's front end recurses deeply in an unoptimised build; the CLI
    // and the build script run it on a large stack too.
    let worker = std::thread::Builder::new()
        .stack_size(256 * 1024 * 1024)
        .spawn(move || {
            let shaders = lava_build::lava_build(Path::new(shadecache_bevy_harness::ASSETS))
                .quiet()
                .composed()
                .unwrap_or_else(|e| panic!("{:?}", e.errors));
            let path = Path::new(shadecache_bevy_harness::ASSETS).join("lava.toml");
            let mut scene =
                shadecache::scene::Scene::load(&path).unwrap_or_else(|e| panic!("{}", e.render()));
            scene.start_frame = start_frame;
            let options = profile::Options {
                nodes: Nodes::Ids(vec![lava_build::NODE.into()]),
                variants: vec![shadecache::rewrite::Variant::OnePass],
                refresh_periods: vec![32],
                frames: Some(MEASURED),
                warmup: Some(WARMUP),
                size: Some([128, 128]),
                ..profile::Options::default()
            };
            let (report, _) = profile::profile(&shaders[0], &scene, &path, &options, &mut Quiet)
                .unwrap_or_else(|e| panic!("{}", e.render()));
            let row = &report.results[0];
            row.frame_stats.iter().map(|f| f.psnr_frame).collect()
        })
        .expect("a worker thread");
    worker.join().expect("the profile ran")
}

/// When the view's target changes size, the cache's targets are made
/// again at the new size and the first frame the view draws at it misses
/// everywhere, with the plan's Δn: it is Bevy's own frame. (Bevy's camera
/// takes the new image's size a frame after its target changes: the first
/// image at the new size can still be the old view's, scaled.)
#[test]
fn bevy_plugin_resets_on_resize() {
    if skipped() {
        return;
    }
    let compared = run(Headless {
        frames: 4,
        resize: Some((12, 192)),
        ..Headless::default()
    });
    let first_resized = compared
        .iter()
        .position(|f| f.size == 192)
        .unwrap_or_else(|| panic!("no frame at the new size: {compared:?}"));
    assert!(first_resized >= 12, "{compared:?}");
    let after = &compared[first_resized..];
    assert!(after.len() >= 3, "{after:?}");
    let exact = after[..2]
        .iter()
        .position(|f| f.max_error <= 1.0 / 255.0)
        .unwrap_or_else(|| panic!("no frame after the resize misses everywhere: {after:?}"));
    assert!(after[exact].lava_pixels > 1000, "{after:?}");
    // And the cache reuses again after it.
    assert!(
        after[exact + 1..].iter().any(|f| f.max_error > 2.0 / 255.0),
        "{after:?}"
    );
}

/// The memory a game reads (`CacheStats::target_bytes`) is the caching
/// view's cache at the view's size: the lava's one-pass variant owns its
/// payload (`rgba16float`, or `rgba32float` for an unbounded node), age
/// and depth twice and its classification once, 32 or 48 bytes a pixel,
/// and a quarter of that once the view is half as wide and high.
#[test]
fn cache_memory_is_its_targets_at_the_views_size() {
    if skipped() {
        return;
    }
    let whole = in_turn(Headless {
        frames: 4,
        ..Headless::default()
    });
    assert!(whole.errors.is_empty(), "{:?}", whole.errors);
    let pixels = 128 * 128;
    assert!(
        [32 * pixels, 48 * pixels].contains(&whole.target_bytes),
        "{} bytes at 128²",
        whole.target_bytes
    );
    let resized = in_turn(Headless {
        frames: 4,
        resize: Some((4, 64)),
        ..Headless::default()
    });
    assert!(resized.errors.is_empty(), "{:?}", resized.errors);
    assert_eq!(resized.target_bytes * 4, whole.target_bytes);
}

/// A camera cut forgets last frame: the frame drawn after it, with the
/// plan's Δn, is Bevy's own, though the camera moved on smoothly (so
/// without the cut the cache would reuse), and reuse resumes after it.
#[test]
fn bevy_plugin_resets_on_camera_cut() {
    if skipped() {
        return;
    }
    let (compared, cut) = run_with_cut(Headless {
        frames: 6,
        cut_after: Some(12),
        ..Headless::default()
    });
    let cut = cut.expect("the cut was marked");
    starts_afresh_at(&compared, cut, "cut");
}

/// The frames before `at` reuse; one of the four after it is Bevy's own
/// (the cache started afresh: it came back a few frames after it was
/// drawn), and reuse resumes after that one.
fn starts_afresh_at(compared: &[Compared], at: u32, what: &str) {
    let reused = |f: &&Compared| f.max_error > 1.0 / 255.0;
    let before: Vec<&Compared> = compared.iter().filter(|f| f.frame < at).collect();
    assert!(
        before.iter().rev().take(4).all(reused),
        "the frames before the {what} reuse: {before:?}"
    );
    let after: Vec<&Compared> = compared.iter().filter(|f| f.frame >= at).collect();
    let exact = after
        .iter()
        .take(4)
        .position(|f| !reused(f))
        .unwrap_or_else(|| panic!("no frame after the {what} is Bevy's own: {after:?}"));
    assert!(
        after[exact + 1..].iter().any(reused),
        "reuse does not resume after the {what}: {after:?}"
    );
}

/// A material's values edited while the game runs (every
/// `StandardMaterial`'s base colour, as a game recolours a mesh) reach the
/// cached frame at once: the frame of the edit, the box's caches start
/// afresh and the frame is Bevy's own with the new colour (without the
/// reset the box showed its old colour where it reused, up to Δn frames),
/// and reuse resumes after it.
#[test]
fn edited_material_values_reset_its_caches() {
    if skipped() {
        return;
    }
    let (run, edit) = material_edited(MaterialEdit::EveryColour, OtherMeshes::None);
    starts_afresh_at(&run.compared, edit, "edit");
}

/// The box cached in Bevy's `StandardMaterial` under a 1°/frame orbit
/// (the lava left to Bevy, `others` beside it), its `StandardMaterial`s
/// edited as `edit` says after 40 compared frames and 8 more compared: the
/// run, and the frame of the edit.
fn material_edited(edit: MaterialEdit, others: OtherMeshes) -> (HeadlessRun, u32) {
    let run = in_turn(Headless {
        frames: 8,
        step_degrees: 1.0,
        standard_material: true,
        lava_uncached: true,
        other_meshes: others,
        edit_standard_material_after: Some(40),
        material_edit: edit,
        ..Headless::default()
    });
    assert!(run.errors.is_empty(), "{:?}", run.errors);
    let edit = run.edit_frame.expect("the material was edited");
    (run, edit)
}

/// A cached mesh given another material asset while the game runs (as a
/// game highlights a selected mesh) shows it at once: the frame of the
/// swap, the box's caches start afresh and the frame is Bevy's own with
/// the new asset's colour, and reuse resumes after it. Checked: without
/// the plugin comparing each mesh's asset with last frame's, no frame
/// after the swap is Bevy's own.
#[test]
fn a_cached_meshs_material_swapped_resets_its_caches() {
    if skipped() {
        return;
    }
    let (run, swap) = material_edited(MaterialEdit::SwapMarked, OtherMeshes::None);
    starts_afresh_at(&run.compared, swap, "swap");
}

/// Under Bevy's TAA, which jitters the projection every frame, the cache
/// reprojects through last frame's jittered view (its twin of Bevy's view
/// uniform), so it finds each point where last frame's jittered raster
/// shaded it. At Δn = 1 every frame is Bevy's own TAA frame; at the plan's
/// Δn it reuses.
#[test]
fn taa_camera_caches_under_its_jitter() {
    if skipped() {
        return;
    }
    bevys_own_at_one_then_reusing(
        Headless {
            taa: true,
            ..Headless::default()
        },
        48,
        "TAA",
    );
}

/// An edit of a material no cached mesh binds (the `StandardMaterial` of
/// an opaque box Bevy draws, beside the cached box's own) leaves the
/// caches of `StandardMaterial` as they are: every frame from the edit on
/// reuses, as before it. Checked: with the caches reset whenever any asset
/// of the material's type is modified, a frame after the edit is Bevy's
/// own.
#[test]
fn an_edit_of_a_material_no_cached_mesh_binds_leaves_the_cache_reusing() {
    if skipped() {
        return;
    }
    let (run, edit) = material_edited(MaterialEdit::UncachedColours, OtherMeshes::OpaqueInFront);
    let around: Vec<&Compared> = run
        .compared
        .iter()
        .filter(|f| f.frame + 4 >= edit)
        .take(10)
        .collect();
    assert!(
        around.iter().all(|f| f.max_error > 1.0 / 255.0),
        "a frame around the edit at {edit} is Bevy's own: {around:?}"
    );
}

/// What the host refuses is an error at start-up, never a panic in the
/// game: with MSAA (a cache holds one value per pixel) the view's cache
/// is not made, the error says why, and Bevy draws the material as
/// without the plugin.
#[test]
fn bevy_plugin_refuses_msaa_and_leaves_the_material_to_bevy() {
    if skipped() {
        return;
    }
    let run = in_turn(Headless {
        frames: 8,
        msaa: true,
        ..Headless::default()
    });
    assert_eq!(run.frames_drawn, 0);
    assert!(
        run.errors
            .iter()
            .any(|e| e.contains("cannot be made") && e.contains("4 samples per pixel")),
        "{:?}",
        run.errors
    );
    assert!(run.compared.len() >= 8, "{:?}", run.compared);
    all_bevys_own(&run.compared);
}

/// A mesh marked for the cache whose material has no variant (Bevy's
/// `StandardMaterial`, for which no `ShadecachePlugin` was added) is left
/// to Bevy with a reason, once, while the lava is cached: every frame is
/// Bevy's own at Δn = 1.
#[test]
fn mesh_of_a_material_without_a_variant_is_left_to_bevy_with_a_reason() {
    if skipped() {
        return;
    }
    let run = in_turn(Headless {
        refresh_period: Some(1),
        frames: 8,
        foreign_material: true,
        ..Headless::default()
    });
    assert!(run.frames_drawn > 0, "{:?}", run.errors);
    let said: Vec<&String> = run
        .errors
        .iter()
        .filter(|e| e.contains("of a material no ShadecachePlugin was added for"))
        .collect();
    assert_eq!(said.len(), 1, "{:?}", run.errors);
    assert_eq!(run.errors.len(), 1, "{:?}", run.errors);
    assert!(run.compared.len() >= 8, "{:?}", run.compared);
    all_bevys_own(&run.compared);
}

/// Runs `with` at Δn = 1, 8 frames, and checks that every frame is
/// Bevy's own, nothing was refused, and two caches drew every frame
/// compared: the lava's meshes that `with` draws one way and the others
/// another.
fn two_caches_each_frame(with: Headless) {
    let run = in_turn(Headless {
        refresh_period: Some(1),
        frames: 8,
        ..with
    });
    assert!(run.errors.is_empty(), "{:?}", run.errors);
    assert!(run.compared.len() >= 8, "{:?}", run.compared);
    assert!(
        run.frames_drawn >= 2 * run.compared.len() as u64,
        "{} caches drawn over {} frames",
        run.frames_drawn,
        run.compared.len()
    );
    all_bevys_own(&run.compared);
}

/// Lava meshes of two vertex layouts in one view (one has vertex
/// colours): each is drawn through the lava's build composed as Bevy
/// composes it (the one with `VERTEX_COLORS` for the coloured mesh), in a
/// cache of its own, drawn in turn, and at Δn = 1 every frame is Bevy's
/// own.
#[test]
fn meshes_of_several_vertex_layouts_in_one_view() {
    if skipped() {
        return;
    }
    two_caches_each_frame(Headless {
        coloured_mesh: true,
        ..Headless::default()
    });
}

/// The material's own `specialize` is Bevy's to apply, and the cache
/// draws as Bevy's specialised pipeline does: a lava quad seen from its
/// back, whose material turns culling off, is drawn by the cache too (with
/// the culling the plugin once set itself, it was missing), in a cache of
/// its own, and at Δn = 1 every frame is Bevy's own.
#[test]
fn material_specialize_is_honoured() {
    if skipped() {
        return;
    }
    two_caches_each_frame(Headless {
        double_sided: true,
        ..Headless::default()
    });
}

/// Two cached materials in one app, each through its own variant (the
/// lava's named node, the stone's top-ranked one): at Δn = 1 every frame
/// is Bevy's own, and both variants drew every frame compared.
#[test]
fn two_cached_materials_in_one_app() {
    if skipped() {
        return;
    }
    let run = in_turn(Headless {
        refresh_period: Some(1),
        frames: 8,
        stone: true,
        other_meshes: OtherMeshes::OpaqueInFront,
        ..Headless::default()
    });
    let lava = run.frames_drawn - run.stone_frames_drawn;
    eight_frames_bevys_own_through(&run, &[("stone", run.stone_frames_drawn), ("lava", lava)]);
}

/// Asserts that `run` logged no error and compared 8 frames or more, each
/// Bevy's own, and that each variant named (with the frames it drew) drew
/// every one of them.
fn eight_frames_bevys_own_through(run: &HeadlessRun, variants: &[(&str, u64)]) {
    assert!(run.errors.is_empty(), "{:?}", run.errors);
    assert!(run.compared.len() >= 8, "{:?}", run.compared);
    for (variant, drawn) in variants {
        assert!(*drawn >= 8, "the {variant}'s variant drew {drawn} frames");
    }
    all_bevys_own(&run.compared);
}

/// Bevy's own `StandardMaterial` in the cache: a lit box drawn through
/// the two-pass variant of bevy_pbr's `pbr.wesl`, composed by the build
/// script with Bevy's defs for the box's layout, beside the lava: at
/// Δn = 1 every frame is Bevy's own to the bit, and the variant drew
/// every frame compared.
#[test]
fn standard_material_is_cached() {
    if skipped() {
        return;
    }
    let run = in_turn(Headless {
        refresh_period: Some(1),
        frames: 8,
        standard_material: true,
        ..Headless::default()
    });
    eight_frames_bevys_own_through(&run, &[("StandardMaterial", run.standard_frames_drawn)]);

    // At the plan's Δn (32), with the camera orbiting 1° a frame and the
    // box the only cached mesh (Bevy draws the lava), the box's lit colour
    // is reused: past the start's transient (Δn frames after the cold
    // start every value is recomputed at once), every frame differs from
    // Bevy's, by what reuse under motion leaves. Measured over each
    // material's pixels too (the mask camera's), the error is all the
    // box's: the lava Bevy draws is its own to the bit, the box's pixels
    // are further from Bevy's than the whole frame is.
    let run = in_turn(Headless {
        frames: 80,
        step_degrees: 1.0,
        standard_material: true,
        lava_uncached: true,
        masks: true,
        ..Headless::default()
    });
    assert!(run.errors.is_empty(), "{:?}", run.errors);
    assert_eq!(run.frames_drawn, run.standard_frames_drawn);
    let steady = &run.compared[run.compared.len() - 24..];
    let psnr: Vec<String> = steady.iter().map(|f| format!("{:.1}", f.psnr)).collect();
    eprintln!(
        "Bevy PBR reused, PSNR of the steady frames: {}",
        psnr.join(" ")
    );
    assert!(
        steady.iter().all(|f| f.max_error > 0.0),
        "a frame equals Bevy's: nothing was reused\n{steady:?}"
    );
    assert!(
        steady.iter().all(|f| f.psnr > 30.0),
        "the reused box is far from Bevy's\n{steady:?}"
    );
    for frame in steady {
        let lava = frame.psnr_over(Masked::Lava);
        let the_box = frame.psnr_over(Masked::StandardMaterial);
        assert_eq!(lava, Some(f64::INFINITY), "{frame:?}");
        assert!(
            the_box.is_some_and(|psnr| psnr < frame.psnr - 3.0),
            "the box's pixels are not where the error is\n{frame:?}"
        );
    }
}

/// `ExtendedMaterial<StandardMaterial, _>` in the cache: a sphere whose
/// material extends Bevy's PBR with a rim light (`assets/rim.wesl`, built
/// two-pass), lit by a point light, beside the lava: Bevy's frame to the
/// bit at Δn = 1, the variant drawing every frame compared.
#[test]
fn extended_material_is_cached() {
    if skipped() {
        return;
    }
    let run = in_turn(Headless {
        refresh_period: Some(1),
        frames: 8,
        rim: true,
        ..Headless::default()
    });
    eight_frames_bevys_own_through(&run, &[("rim material", run.rim_frames_drawn)]);
}

/// The game's scene: the lava (a custom material) and the props in Bevy's
/// `StandardMaterial` (a floor the sphere rests on, a pillar and a crate
/// before the lava) cached at once, each through its own variant, a glass
/// pane blending over them in Bevy's transparent pass and a point light
/// on them: at Δn = 1 every frame is Bevy's own to the bit (the props and
/// the lava hide each other as Bevy's depth says), and both variants drew
/// every frame compared.
#[test]
fn game_scene_caches_standard_material_and_lava_together() {
    if skipped() {
        return;
    }
    let run = in_turn(Headless {
        refresh_period: Some(1),
        frames: 8,
        standard_material: true,
        props: true,
        ..Headless::default()
    });
    let lava = run.frames_drawn - run.standard_frames_drawn;
    eight_frames_bevys_own_through(
        &run,
        &[
            ("StandardMaterial", run.standard_frames_drawn),
            ("lava", lava),
        ],
    );
}

/// A view with a depth prepass already holds the cached meshes' depth,
/// and two-pass's second pass draws only the pixels the first left, told
/// by the depth the first wrote: the view refuses Bevy PBR's two-pass
/// variant with that reason, once, and Bevy draws the box, so every frame
/// is Bevy's own (the lava's one-pass still caches). Without the refusal
/// the second pass, its test passing on equal depth, computed every pixel
/// the prepass covered again: Bevy's frames, at the cost of both passes.
#[test]
fn multi_pass_variant_over_a_prepass_is_left_to_bevy_with_a_reason() {
    if skipped() {
        return;
    }
    let run = in_turn(Headless {
        refresh_period: Some(1),
        frames: 10,
        standard_material: true,
        depth_prepass: true,
        ..Headless::default()
    });
    let said: Vec<&String> = run
        .errors
        .iter()
        .filter(|e| e.contains("the view has a prepass"))
        .collect();
    assert_eq!(said.len(), 1, "{:?}", run.errors);
    assert_eq!(run.errors.len(), 1, "{:?}", run.errors);
    assert_eq!(run.standard_frames_drawn, 0);
    assert!(run.frames_drawn >= 10, "{} frames drawn", run.frames_drawn);
    all_bevys_own(&run.compared);
}

/// Switching the cache off hands the meshes back to Bevy's opaque pass:
/// a few frames after, every frame is Bevy's own, lava included (a mesh
/// left out of the opaque phase would be missing from the image).
#[test]
fn bevy_plugin_hands_the_meshes_back_when_switched_off() {
    if skipped() {
        return;
    }
    let run = in_turn(Headless {
        frames: 12,
        switch_off_after: Some(12),
        ..Headless::default()
    });
    assert!(run.errors.is_empty(), "{:?}", run.errors);
    let off = run.switch_off_frame.expect("the cache was switched off");
    // No frame without the lava: the view is handed back as the frame that
    // stops caching is extracted, and Bevy queues its meshes in that frame
    // (found in its queue, they came back a frame late: one frame at
    // 15 dB, the lava's pixels black).
    reused_before_then_bevys_own(&run, off, 0);
}

/// Asserts that `run` reused before frame `handed_back`, that every
/// compared frame from a few after it on is Bevy's own (the images take a
/// few frames to come back), and that at most `gaps` frames between are
/// drawn by neither: the others are the cache's (its reuse error, above
/// 35 dB) or Bevy's.
fn reused_before_then_bevys_own(run: &HeadlessRun, handed_back: u32, gaps: usize) {
    let neither: Vec<&Compared> = run
        .compared
        .iter()
        .filter(|f| f.frame >= handed_back && f.psnr <= 35.0)
        .collect();
    assert!(
        neither.len() <= gaps,
        "frames drawn by neither after the hand-back: {neither:?}"
    );
    let before: Vec<&Compared> = run
        .compared
        .iter()
        .filter(|f| f.frame < handed_back)
        .collect();
    assert!(
        before.iter().any(|f| f.max_error > 2.0 / 255.0),
        "nothing was reused before: {before:?}"
    );
    let after: Vec<&Compared> = run
        .compared
        .iter()
        .filter(|f| f.frame >= handed_back + 4)
        .collect();
    assert!(after.len() >= 6, "{:?}", run.compared);
    all_bevys_own(after);
}

/// The caches' pipelines compiled by Bevy's `PipelineCache` (found there,
/// labelled `shadecache …`), off the frame as a game makes them by
/// default: the frames before a cache is ready are drawn by Bevy (the
/// meshes stay in its opaque pass), and from then on by the cache. At
/// Δn = 1 every frame is Bevy's own either way; the cache draws, and over
/// the same compared frames it draws fewer than a cache made in the frame
/// (synchronous), whose first frame is already cached: the compile did
/// not hold the frame up.
#[test]
fn caches_are_made_off_the_frame_while_bevy_draws() {
    if skipped() {
        return;
    }
    let run_with = |async_cache| {
        in_turn(Headless {
            refresh_period: Some(1),
            frames: 16,
            async_cache,
            ..Headless::default()
        })
    };
    let (off_the_frame, in_the_frame) = (run_with(true), run_with(false));
    for run in [&off_the_frame, &in_the_frame] {
        assert!(run.errors.is_empty(), "{:?}", run.errors);
        assert!(run.compared.len() >= 16, "{:?}", run.compared);
        all_bevys_own(&run.compared);
        assert!(
            run.variant_pipelines_in_bevys_cache >= 1,
            "the variant's pipelines are not Bevy's pipeline cache's"
        );
    }
    assert!(off_the_frame.frames_drawn > 0, "the cache never drew");
    assert!(
        off_the_frame.frames_drawn < in_the_frame.frames_drawn,
        "made off the frame, the cache drew {} frames; made in it, {}",
        off_the_frame.frames_drawn,
        in_the_frame.frames_drawn
    );
}

/// A cache made again for what it was made for before (its camera's
/// cache switched off, then on) takes the pipelines queued for it then:
/// Bevy's pipeline cache, which keeps every pipeline queued in it, holds
/// the one-pass variant's one pipeline once, and the cache draws again.
#[test]
fn a_cache_made_again_takes_its_pipelines_from_bevys_cache() {
    if skipped() {
        return;
    }
    let run = in_turn(Headless {
        frames: 8,
        switch_off_after: Some(8),
        switch_on_after: Some(16),
        ..Headless::default()
    });
    assert!(run.errors.is_empty(), "{:?}", run.errors);
    let on = run.compared.len() as u64;
    assert!(
        run.frames_drawn > on / 2,
        "the cache did not draw again: {} frames drawn of {on}",
        run.frames_drawn
    );
    assert_eq!(run.variant_pipelines_in_bevys_cache, 1);
}

/// Hot reload: the lava's shader asset changes while the game runs (as
/// Bevy's file watcher changes it). The variant was rewritten from the
/// shader the game was built with, so from then on the lava is Bevy's:
/// the plugin says so once, hands its meshes back, and every frame a few
/// frames after the change is Bevy's own (before, the cache reused).
/// Without the watch the cache went on drawing the old variant.
#[test]
fn shader_hot_reload_hands_the_material_back_to_bevy() {
    if skipped() {
        return;
    }
    let run = in_turn(Headless {
        frames: 12,
        reload_shader_after: Some(12),
        ..Headless::default()
    });
    let said: Vec<&String> = run
        .errors
        .iter()
        .filter(|e| e.contains("changed while the game runs"))
        .collect();
    assert_eq!(said.len(), 1, "{:?}", run.errors);
    assert_eq!(run.errors.len(), 1, "{:?}", run.errors);
    let changed = run.reload_frame.expect("the shader changed");
    // No frame lacks the lava. In the frame of the change Bevy makes its
    // pipeline for the changed shader again; the cache's queue, which took
    // only meshes whose Bevy pipeline was made, dropped them while it was
    // not, and they were out of Bevy's opaque phase too: one frame drawn by
    // neither (15 dB). A pipeline made before and being made again keeps
    // its meshes queued.
    reused_before_then_bevys_own(&run, changed, 0);
}

/// `CacheMode::Auto` in a headless app: the governor gives one frame in
/// 16 to Bevy's own pipelines (the plugin draws the cached meshes with
/// them, in its pass), times both kinds of frame with timestamp queries
/// and reads the times back without a wait. Every frame, cached at Δn = 1
/// or drawn Bevy's way, is Bevy's own to the bit, and the governor holds
/// its state (frames of each kind, times measured) for Bevy's
/// diagnostics.
#[test]
fn bevy_plugin_auto_probes_with_bevys_own_pipelines_and_measures_both() {
    if skipped() {
        return;
    }
    let run = in_turn(Headless {
        refresh_period: Some(1),
        frames: 48,
        mode: CacheMode::Auto { min_psnr: None },
        ..Headless::default()
    });
    assert!(run.errors.is_empty(), "{:?}", run.errors);
    assert!(run.compared.len() >= 48, "{} compared", run.compared.len());
    all_bevys_own(&run.compared);
    let governor = run.governor.expect("the lava's governor reported");
    assert!(governor.on, "{governor:?}");
    assert!(
        governor.original_frames >= 2 && governor.cached_frames >= 30,
        "{governor:?}"
    );
    // The cached frames the harness counts are the governor's.
    assert_eq!(run.frames_drawn, governor.cached_frames, "{governor:?}");
    assert!(
        governor.measured_frames + 8 >= governor.original_frames + governor.cached_frames,
        "{governor:?}"
    );
    // Bevy's diagnostics carry its state.
    let diagnostic = |name: &str| {
        run.diagnostics
            .iter()
            .find(|(path, _)| path == &format!("render/shadecache/LavaMaterial/{name}"))
            .map(|(_, value)| *value)
    };
    assert_eq!(diagnostic("cached"), Some(1.0), "{:?}", run.diagnostics);
    assert_eq!(diagnostic("delta_n"), Some(1.0), "{:?}", run.diagnostics);
}

/// `CacheMode::Off`: the plugin's pass draws the cached meshes every
/// frame with the pipelines Bevy specialised for them, batch by batch as
/// Bevy draws a phase (a batch of several meshes is one indirect draw of
/// its first item), and the frames are Bevy's own to the bit; nothing is
/// drawn through the cache.
#[test]
fn cache_mode_off_draws_every_frame_with_bevys_pipelines() {
    if skipped() {
        return;
    }
    let run = in_turn(Headless {
        frames: 12,
        mode: CacheMode::Off,
        ..Headless::default()
    });
    assert!(run.errors.is_empty(), "{:?}", run.errors);
    assert!(run.compared.len() >= 12, "{} compared", run.compared.len());
    all_bevys_own(&run.compared);
    assert_eq!(run.frames_drawn, 0);
}

/// `CacheMode::Auto` with an error budget: on a watched frame the plugin
/// copies the view as Bevy's opaque pass left it, draws the cached meshes
/// Bevy's way into the copy, and the host crate's watch compares the two
/// frames over the pixels either changed. At Δn = 1 the cached frame is
/// Bevy's own (the watch reads it so, and the view's frames stay Bevy's
/// own to the bit: the watch draws beside them, not in them); at the
/// plan's Δn under camera motion the watch reads a finite error, and
/// Bevy's diagnostics carry it.
#[test]
fn bevy_plugin_auto_watches_the_error_against_bevys_own_frame() {
    if skipped() {
        return;
    }
    let budget = CacheMode::Auto {
        min_psnr: Some(20.0),
    };
    let exact = in_turn(Headless {
        refresh_period: Some(1),
        frames: 40,
        mode: budget,
        ..Headless::default()
    });
    assert!(exact.errors.is_empty(), "{:?}", exact.errors);
    all_bevys_own(&exact.compared);
    let watched = exact.governor.and_then(|g| g.psnr);
    assert!(watched.is_some_and(|db| db >= 50.0), "{:?}", exact.governor);

    let reused = in_turn(Headless {
        frames: 60,
        step_degrees: 1.0,
        mode: budget,
        ..Headless::default()
    });
    assert!(reused.errors.is_empty(), "{:?}", reused.errors);
    let psnr = reused.governor.and_then(|g| g.psnr);
    assert!(
        psnr.is_some_and(|db| db > 15.0 && db < 100.0),
        "{:?}",
        reused.governor
    );
    assert!(
        reused
            .diagnostics
            .iter()
            .any(|(path, _)| path == "render/shadecache/LavaMaterial/psnr"),
        "{:?}",
        reused.diagnostics
    );
}
