//! Skinned meshes (`corpus/skinned_arm.wgsl`): joint indices and weights
//! per vertex, the joints' matrices in a storage array the scene animates.
//! Last frame's position of a vertex needs last frame's joint matrices,
//! which the array's previous-frame twin holds.

use crate::profile::{Nodes, Options};
use crate::rewrite::{CacheFormat, Variant};

use super::profile::run_shader;
use super::util::root;

fn shader() -> String {
    std::fs::read_to_string(root().join("corpus/skinned_arm.wgsl")).unwrap()
}

/// The node that caches the scales' albedo: it depends on the rest pose
/// alone, so a value reprojected to where its surface point was is exact.
const ALBEDO: &str = "n0cb8907c";

/// A two-joint arm before a wall at 128², seen along the bend axis: the
/// forearm bends `degrees_per_frame` about it from -30°, so it sweeps over
/// the wall.
fn arm(degrees_per_frame: f32, frames: u32, warmup: u32) -> String {
    format!(
        r#"
size = [128, 128]
frames = {frames}
warmup = {warmup}
effects = ["deformation", "disocclusion"]
[camera]
eye = [0.0, 0.2, 3.2]
target = [0.0, 0.2, 0.0]
fov_degrees = 45.0
[light]
position = [2.0, 3.0, 4.0]
[[objects]]
mesh = {{ kind = "plane", size = 6.0, subdivisions = 4 }}
position = [0.0, 0.0, -0.8]
rotation_degrees = [90.0, 0.0, 0.0]
[[objects]]
mesh = {{ kind = "cylinder", radius = 0.25, length = 2.4, rings = 48, segments = 32 }}
position = [-0.4, -0.2, 0.0]
[objects.skin]
joints = 2
root = [-1.2, 0.0, 0.0]
segment = 1.2
axis = [0.0, 0.0, 1.0]
bend_degrees = -30.0
bend_degrees_per_frame = {degrees_per_frame}
blend = 0.3
[uniforms]
rim_strength = 0.25
"#
    )
}

/// The forearm turns 14° in one frame about the elbow. The pixels it newly
/// covers (two pixels in from the band's edges) were wall last frame at
/// the same place, and forearm at the place last frame's joint matrices
/// put that surface point: they hit only if the vertex stage's previous
/// position is where the vertex was. The band it uncovers misses, and the
/// image is the reference's.
#[test]
fn skinned_mesh_previous_position_is_exact() {
    let options = Options {
        nodes: Nodes::Ids(vec![ALBEDO.into()]),
        variants: vec![Variant::ThreePass],
        refresh_periods: vec![0],
        refresh_quads: vec![1],
        cache_formats: vec![CacheFormat::Rgba32float],
        ..Options::default()
    };
    let Some((pictures, report, scene)) = run_shader(&shader(), &arm(14.0, 1, 1), options) else {
        return;
    };
    let (band, uncovered) = super::util::moved_bands(&scene, 1, 128, 128);
    let hit = |i: usize| super::util::is_hit(&pictures.results[0].1, i);
    assert!(band.len() > 30, "the leading band is {} pixels", band.len());
    let missed = band.iter().filter(|&&i| !hit(i)).count();
    assert_eq!(missed, 0, "of {} leading-band pixels", band.len());
    assert!(
        uncovered.len() > 30,
        "the uncovered band is {} pixels",
        uncovered.len()
    );
    assert!(uncovered.iter().all(|&i| !hit(i)));

    let row = &report.results[0];
    assert!(row.psnr >= 45.0, "PSNR {} dB", row.psnr);
}

/// The arm bends 2° a frame for 16 frames, the lit colour cached with a
/// refresh every 8: where the forearm uncovers the wall, no stale arm
/// colour stays behind (it would, were the previous positions wrong: the
/// lookups would find the arm where it no longer is), so every frame
/// stays close to the reference.
#[test]
fn skinned_mesh_cache_has_no_tail() {
    let options = Options {
        nodes: Nodes::Top(1),
        variants: vec![Variant::ThreePass],
        refresh_periods: vec![8],
        refresh_quads: vec![2],
        cache_formats: vec![CacheFormat::Rgba32float],
        ..Options::default()
    };
    let Some((_, report, _)) = run_shader(&shader(), &arm(2.0, 16, 8), options) else {
        return;
    };
    let row = &report.results[0];
    assert!(row.hit_rate > 0.8, "hit rate {}", row.hit_rate);
    assert!(row.psnr >= 40.0, "PSNR {} dB", row.psnr);
    assert!(row.worst_psnr >= 34.0, "worst frame {} dB", row.worst_psnr);
}

/// Whole-frame reuse of the bending arm: the I-frame pass computes each
/// vertex at the previous and the next I-frame with those I-frames' joint
/// matrices (the array's twins), so the scene-assisted B-frames follow the
/// forearm: close to rendering every frame, and far closer than blending
/// the two I-frames, which ghosts the forearm.
#[test]
fn skinned_mesh_interpolates_with_each_i_frames_joints() {
    use crate::interpolate::{Method, Options};
    let options = Options {
        methods: vec![Method::SceneAssisted, Method::LinearBlend],
        frames: Some(8),
        ..Options::default()
    };
    let Some((report, _, _)) =
        super::interpolate::run_interpolation(&shader(), &arm(4.0, 8, 0), options)
    else {
        return;
    };
    let psnr = |m: Method| {
        report
            .methods
            .iter()
            .find(|r| r.method == m)
            .map(|r| r.psnr_mean)
            .unwrap_or_else(|| panic!("{} missing", m.name()))
    };
    let (scene_assisted, blend) = (psnr(Method::SceneAssisted), psnr(Method::LinearBlend));
    assert!(scene_assisted >= 35.0, "scene-assisted {scene_assisted} dB");
    assert!(
        scene_assisted >= blend + 6.0,
        "scene-assisted {scene_assisted} dB, linear blend {blend} dB"
    );
}
