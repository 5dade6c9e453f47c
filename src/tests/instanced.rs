//! Instanced objects whose per-instance data a storage buffer holds
//! (`corpus/instanced_storage.wgsl`), profiled on lavapipe.

use crate::profile::{Nodes, Options};
use crate::rewrite::{CacheFormat, Variant};

use super::profile::run_shader;
use super::util::root;

fn instanced_shader() -> String {
    std::fs::read_to_string(root().join("corpus/instanced_storage.wgsl")).unwrap()
}

/// The wgpu tutorials' instancing: model and normal matrices as
/// per-instance vertex inputs.
fn tutorial_shader() -> String {
    std::fs::read_to_string(root().join("corpus/tutorial_instances.wgsl")).unwrap()
}

/// The tutorial shader's resources under its own names.
const TUTORIAL_TAIL: &str = r#"
[roles]
"camera.view_proj" = "clip_from_world"
"camera.view_pos" = "camera_position"
"light.position" = "light_position"
[uniforms]
color = [1.0, 1.0, 1.0]
[textures.t_diffuse]
generate = "checker"
[textures.t_normal]
generate = "flat-normal"
"#;

/// The `[uniforms]` of the instanced shader.
const UNIFORMS: &str = r#"
[uniforms]
shininess = 32.0
light_color = [1.0, 1.0, 1.0]
rim_strength = 0.3
sky_color = [0.6, 0.7, 0.9]
ambient = 0.4
ground_color = [0.3, 0.25, 0.2]
specular = 0.5
"#;

/// Seen from straight above: a plane, and two cubes in a ring that orbit
/// the vertical axis 16° a frame (each about 9 pixels), given as instances
/// of one object. `effects` and what the shader's resources get (`tail`:
/// storage, uniforms, roles, textures) are the caller's.
fn orbiting_cubes(effects: &str, tail: &str) -> String {
    format!(
        r#"
size = [128, 128]
frames = 1
warmup = 1
effects = [{effects}]
[camera]
eye = [0.0, 12.0, 0.01]
target = [0.0, 0.0, 0.0]
fov_degrees = 26.0
near = 5.0
far = 20.0
{PLANE}[[objects]]
mesh = {{ kind = "cube", size = 1.0 }}
position = [0.0, 0.5, 0.0]
instances = {{ count = 2, layout = "ring", radius = 1.5, orbit_degrees_per_frame = 16.0, spin_degrees_per_frame = [0.0, 5.0, 0.0] }}
{tail}
"#
    )
}

const PLANE: &str = "[[objects]]\nmesh = { kind = \"plane\", size = 8.0, subdivisions = 4 }\n";

const COLOURS: &str = "[storage.instances]\ncolor = { palette = \"rainbow\" }\n";

/// The storage shader's resources: rainbow instances and its uniforms.
fn storage_tail(storage: &str) -> String {
    format!("{storage}{UNIFORMS}")
}

fn options(periods: &[u32]) -> Options {
    Options {
        nodes: Nodes::Top(1),
        refresh_periods: periods.to_vec(),
        refresh_quads: vec![1],
        variants: Variant::CACHE.to_vec(),
        ..Options::default()
    }
}

/// Δn = 1 recomputes every pixel every frame: on the corpus's instanced
/// scene (tori passing each other, each drawn from the storage buffer)
/// every variant's image is the reference's.
#[test]
fn instanced_refresh_period_one_equals_the_reference() {
    let scene = std::fs::read_to_string(root().join("corpus/scenes/instanced_rings.toml")).unwrap();
    let mut opts = options(&[1]);
    opts.cache_formats = vec![CacheFormat::Rgba32float];
    opts.size = Some([64, 64]);
    opts.frames = Some(3);
    opts.warmup = Some(1);
    let Some((_, report, scene)) = run_shader(&instanced_shader(), &scene, opts) else {
        return;
    };
    assert_eq!(scene.objects[0].instance_count(), 12);
    assert_eq!(report.results.len(), Variant::CACHE.len());
    for row in &report.results {
        assert_eq!(row.hit_rate, 0.0, "{}", row.variant);
        assert!(
            row.max_abs_error <= 1.0 / 255.0 + 1e-9,
            "{} {}",
            row.variant,
            row.max_abs_error
        );
        assert_eq!(row.above_threshold, 0.0, "{}", row.variant);
    }
}

/// Δn = 1 on the corpus's instanced crates, whose model matrices are
/// per-instance vertex inputs with previous-frame twins: every variant of
/// the wood grain and of the lit colour gives the reference's image.
#[test]
fn instance_inputs_at_refresh_period_one_equal_the_reference() {
    let scene = std::fs::read_to_string(root().join("corpus/scenes/instanced_crates.toml"))
        .unwrap()
        .replace("size = [256, 256]", "size = [64, 64]");
    let shader = tutorial_shader();
    let analysis = super::util::analyzed("tutorial_instances.wgsl", &shader).1;
    let ids = [
        "wood_grain(in.object_position)",
        "vec4<f32>(result, object_color.a)",
    ]
    .iter()
    .map(|text| super::util::candidate(&analysis, text).node.id.clone())
    .collect();
    let mut opts = options(&[1]);
    opts.nodes = Nodes::Ids(ids);
    opts.cache_formats = vec![CacheFormat::Rgba32float];
    opts.frames = Some(3);
    opts.warmup = Some(1);
    let Some((_, report, scene)) = run_shader(&shader, &scene, opts) else {
        return;
    };
    assert_eq!(scene.objects[1].instance_count(), 9);
    assert_eq!(report.results.len(), 2 * Variant::CACHE.len());
    for row in &report.results {
        // The crates and the plane are drawn: an equality of two empty
        // frames would say nothing.
        assert!(
            row.coverage > 0.2,
            "{} covers {}",
            row.variant,
            row.coverage
        );
        assert!(
            row.max_abs_error <= 1.0 / 255.0 + 1e-9,
            "{} {} {}",
            row.node,
            row.variant,
            row.max_abs_error
        );
    }
}

/// Only the per-instance inputs the position reads get previous-frame
/// twins: the tutorial's model matrix, not its normal matrix (which would
/// not fit in WebGPU's 16 vertex attributes beside the rest).
#[test]
fn only_instance_inputs_the_position_reads_get_twins() {
    let shader = tutorial_shader();
    let (shader, analysis) = super::util::analyzed("tutorial_instances.wgsl", &shader);
    let node = super::util::candidate(&analysis, "wood_grain(in.object_position)");
    let rewritten = crate::rewrite::rewrite(
        &shader,
        &analysis,
        node,
        Variant::TwoPass,
        &crate::rewrite::Options::default(),
    )
    .unwrap();
    let layout = &rewritten.plan.vertex_layout;
    let twins: Vec<(u32, &str)> = layout
        .iter()
        .filter_map(|a| a.previous_of.map(|of| (of, a.name.as_str())))
        .collect();
    assert_eq!(
        twins,
        [
            (5, "previous_model_matrix_0"),
            (6, "previous_model_matrix_1"),
            (7, "previous_model_matrix_2"),
            (8, "previous_model_matrix_3")
        ]
    );
    use crate::plan::StepMode;
    let per_instance = layout
        .iter()
        .filter(|a| a.step == StepMode::Instance)
        .count();
    assert_eq!(per_instance, 7 + 4);
    assert!(layout.iter().all(|a| a.location < 16));
}

/// Nothing declared moves: the instances' orbit and spin are ignored, and
/// after the first frame every covered pixel of every variant is reused.
/// Both instances are drawn, where the scene puts them.
#[test]
fn static_instances_hit_everywhere_after_the_first_frame() {
    // The cubes alone, so that the covered pixels are theirs.
    let scene = orbiting_cubes("", &storage_tail(COLOURS))
        .replace("frames = 1", "frames = 3")
        .replace(PLANE, "");
    let Some((pictures, report, scene)) = run_shader(&instanced_shader(), &scene, options(&[0]))
    else {
        return;
    };
    assert_eq!(report.results.len(), Variant::CACHE.len());
    for row in &report.results {
        for (frame, stats) in row.frame_stats.iter().enumerate() {
            assert_eq!(
                stats.hit_rate, 1.0,
                "{} frame {frame}: {stats:?}",
                row.variant
            );
        }
    }
    // The covered pixels are the CPU's silhouettes of both instances.
    let (w, h) = (128usize, 128usize);
    let cubes = super::util::silhouette(&scene, 0, 0, w, h);
    let inside = super::util::interior(&cubes, w);
    assert!(inside.iter().filter(|&&i| i).count() > 500);
    for (result, (_, classes)) in report.results.iter().zip(&pictures.results) {
        let covered = |i: usize| classes[i * 4..i * 4 + 3] != [0, 0, 0];
        for (i, &inside) in inside.iter().enumerate() {
            assert!(
                !inside || covered(i),
                "{}: pixel {i} is not drawn",
                result.variant
            );
            assert!(
                !covered(i) || super::util::near(&cubes, w, i),
                "{}: pixel {i} is drawn outside the silhouettes",
                result.variant
            );
        }
    }
}

/// The cubes orbit: the pixels they newly cover this frame (the leading
/// band, two pixels in from its edges) were the plane last frame at the
/// same place, and the cube top at the place the previous-frame storage
/// twin reprojects them to. So they hit only if that twin holds last
/// frame's instance transforms.
#[test]
fn moving_instances_reproject_with_last_frames_storage() {
    assert_moving_cubes_reproject(&instanced_shader(), &storage_tail(COLOURS));
}

/// The same orbiting cubes drawn by a shader that takes each instance's
/// model matrix as four per-instance vertex inputs, as the wgpu tutorials
/// do: the leading band hits only if the inputs' previous-frame twins
/// hold last frame's matrices.
#[test]
fn moving_instance_inputs_reproject_with_last_frames_matrix() {
    assert_moving_cubes_reproject(&tutorial_shader(), TUTORIAL_TAIL);
}

/// On the orbiting cubes, three-pass without refresh: the leading band of
/// each cube hits and the band it uncovered misses.
fn assert_moving_cubes_reproject(shader: &str, tail: &str) {
    let scene = orbiting_cubes("\"object-motion\", \"disocclusion\"", tail);
    let mut opts = options(&[0]);
    opts.variants = vec![Variant::ThreePass];
    let Some((pictures, _, scene)) = run_shader(shader, &scene, opts) else {
        return;
    };
    let (band, uncovered) = super::util::moved_bands(&scene, 1, 128, 128);
    let hit = |i: usize| super::util::is_hit(&pictures.results[0].1, i);
    assert!(band.len() > 50, "the leading band is {} pixels", band.len());
    let missed = band.iter().filter(|&&i| !hit(i)).count();
    assert_eq!(missed, 0, "of {} leading-band pixels", band.len());

    // And the band they uncovered misses.
    assert!(uncovered.len() > 50);
    assert!(uncovered.iter().all(|&i| !hit(i)));
}

fn profile_error(scene: &str) -> String {
    super::util::profile_error("corpus/instanced_storage.wgsl", scene)
}

/// A storage member the scene does not set is an error naming it, not
/// zeros.
#[test]
fn a_missing_storage_member_is_an_error_naming_it() {
    let err = profile_error(&orbiting_cubes("", &storage_tail("")));
    assert!(err.contains("`instances.color`"), "{err}");
    assert!(err.contains("[storage.instances]"), "{err}");
}

/// A list of values per instance must have one per instance of its
/// object: the error says so and points at the list.
#[test]
fn a_list_that_disagrees_with_the_instance_count_is_an_error() {
    let storage = "[objects.storage.instances]\ncolor = [[1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0], [0.0, 0.0, 1.0, 1.0]]\n[storage.instances]\ncolor = [0.5, 0.5, 0.5, 1.0]\n";
    let scene = orbiting_cubes("", &storage_tail(storage));
    let err = profile_error(&scene);
    assert!(err.contains("`instances.color`"), "{err}");
    assert!(err.contains("lists 3 values for 2 instances"), "{err}");
    let line = scene.lines().position(|l| l.starts_with("color")).unwrap() + 1;
    assert!(err.contains(&format!("scene.toml:{line}:")), "{err}");

    // Many instances of a shader that cannot tell them apart.
    let marble = super::util::marble_scene("", "").replace(
        "rotation_degrees_per_frame",
        "instances = 4\nrotation_degrees_per_frame",
    );
    let err = super::util::profile_error("corpus/noise_marble.wgsl", &marble);
    assert!(err.contains("instance_index"), "{err}");
}
