//! wgpu render pipelines for every pass of every variant, on whatever
//! adapter the machine has (Mesa's lavapipe in CI).

use std::collections::HashMap;

use crate::back::{self, Language};
use crate::rewrite::{self, Options, Variant};
use crate::runtime::{self, Gpu};

/// The environment variable that lets the tests needing a GPU adapter
/// skip where there is none.
pub const SKIP_GPU_TESTS: &str = "SHADECACHE_SKIP_GPU_TESTS";

/// A device. Without one the test fails — the README's test command runs
/// with a Vulkan driver (lavapipe on a CPU) — unless the skip is asked for
/// with `SHADECACHE_SKIP_GPU_TESTS=1`; then `None`, said on the terminal
/// whatever the test harness captures.
pub fn gpu() -> Option<Gpu> {
    match Gpu::new() {
        Ok(Some(gpu)) => Some(gpu),
        Ok(None) if std::env::var_os(SKIP_GPU_TESTS).is_some_and(|v| v == "1") => {
            use std::io::Write;
            // Written to the stream itself: libtest captures only the
            // print macros, and a skip must not pass unseen.
            let _ = writeln!(
                std::io::stderr(),
                "SKIPPED (no GPU adapter, {SKIP_GPU_TESTS}=1): {}",
                std::thread::current().name().unwrap_or("a test")
            );
            None
        }
        Ok(None) => panic!(
            "no GPU adapter: install a Vulkan driver (apt-get install mesa-vulkan-drivers libvulkan1 gives lavapipe), or set {SKIP_GPU_TESTS}=1 to skip the tests that need one"
        ),
        Err(err) => panic!("{err}"),
    }
}

/// Each pass's WGSL by file name, as the plan names it.
pub(crate) fn wgsl_sources(rewritten: &rewrite::Rewritten) -> HashMap<String, String> {
    back::render_variant(rewritten, Language::Wgsl)
        .unwrap()
        .into_iter()
        .map(|(name, bytes)| (name, String::from_utf8(bytes).unwrap()))
        .collect()
}

/// Writes each pass's WGSL into `dir` as `<label>-<file name>`; their
/// paths, for [`super::util::tint_validate`].
pub(crate) fn write_wgsl(
    dir: &std::path::Path,
    label: &str,
    rewritten: &rewrite::Rewritten,
) -> Vec<std::path::PathBuf> {
    wgsl_sources(rewritten)
        .into_iter()
        .map(|(name, text)| {
            let path = dir.join(format!("{label}-{name}"));
            std::fs::write(&path, text).unwrap();
            path
        })
        .collect()
}

/// Builds a wgpu render pipeline from every pass of `rewritten` (None
/// without a GPU); panics naming `what` when one does not build.
pub fn build_pipelines(rewritten: &rewrite::Rewritten, what: &str) -> Option<usize> {
    let gpu = gpu()?;
    let sources = wgsl_sources(rewritten);
    let pipelines = runtime::build_passes(
        &gpu,
        &rewritten.plan,
        |name| sources.get(name).cloned(),
        runtime::PipelineOptions::default(),
    )
    .unwrap_or_else(|err| panic!("{what}: {err}"));
    Some(pipelines)
}

/// Every pass of every corpus variant ([`super::corpus_rewrites`])
/// builds a wgpu render pipeline, as its plan describes it.
#[test]
fn every_pass_of_every_variant_builds_a_wgpu_pipeline() {
    let Some(mut gpu) = gpu() else { return };
    eprintln!("adapter: {} ({:?})", gpu.adapter.name, gpu.adapter.backend);
    let mut built = 0;
    for (index, rewrite) in super::corpus_rewrites::corpus_rewrites().iter().enumerate() {
        let Ok(emitted) = &rewrite.outcome else {
            continue;
        };
        // A fresh device now and then: lavapipe keeps what it compiled
        // for a device until the device goes (measured: 24 GB over the
        // corpus's 4,000 pipelines on one device).
        if index % 200 == 199 {
            gpu = super::gpu::gpu().expect("the adapter found before");
        }
        emitted
            .plan
            .check()
            .unwrap_or_else(|err| panic!("{}: {err}", rewrite.label()));
        let sources: HashMap<&str, &String> =
            emitted.wgsl.iter().map(|(n, t)| (n.as_str(), t)).collect();
        let pipelines = runtime::build_passes(
            &gpu,
            &emitted.plan,
            |name| sources.get(name).map(|t| t.to_string()),
            runtime::PipelineOptions::default(),
        )
        .unwrap_or_else(|err| panic!("{}: {err}", rewrite.label()));
        built += pipelines;
    }
    assert!(built > 1000, "{built} pipelines");
    eprintln!("built {built} pipelines");
}

/// A shader whose colour is a constant 0.25 whatever the payload, so that
/// with additive blending a pixel's red channel counts its shadings.
const COUNTING_SHADER: &str = r#"
struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
}
@group(0) @binding(0) var<uniform> frame: Frame;

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) normal: vec3<f32>,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>) -> VertexOutput {
    var out: VertexOutput;
    out.clip_position = frame.clip_from_world * (frame.world_from_local * vec4<f32>(position, 1.0));
    out.normal = normal;
    return out;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    let pattern = sin(in.normal * 10.0);
    return vec4<f32>((pattern * 0.0) + vec3<f32>(0.25), 0.25);
}
"#;

/// A UV sphere of `rings × segments` quads, as packed positions and
/// normals (float32x3 each).
fn sphere(rings: u32, segments: u32) -> runtime::Mesh {
    let mut vertices = Vec::new();
    for ring in 0..=rings {
        let theta = std::f32::consts::PI * ring as f32 / rings as f32;
        for segment in 0..=segments {
            let phi = std::f32::consts::TAU * segment as f32 / segments as f32;
            let n = [
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            ];
            for value in n.iter().chain(n.iter()) {
                vertices.extend(value.to_le_bytes());
            }
        }
    }
    let mut indices = Vec::new();
    let row = segments + 1;
    for ring in 0..rings {
        for segment in 0..segments {
            let a = ring * row + segment;
            let (b, c, d) = (a + 1, a + row, a + row + 1);
            indices.extend([a, c, b, b, c, d]);
        }
    }
    runtime::Mesh { vertices, indices }
}

/// The depth tests between passes hold only if every pass computes a
/// bit-identical position (`@invariant`, one position function): pass 3 of
/// three-pass, drawn with depth `equal`, must shade every covered pixel
/// exactly once — no holes, no double shading — on a mesh of many small
/// triangles, with the camera moving so passes 1 and 2 both draw.
#[test]
fn three_pass_shades_every_covered_pixel_exactly_once() {
    let Some(gpu) = gpu() else { return };
    let (shader, analysis) = super::util::analyzed("counting.wgsl", COUNTING_SHADER);
    let candidate = super::util::candidate(&analysis, "sin(in.normal * 10.0)");
    let options = Options {
        color_format: crate::plan::TextureFormat::Rgba16Float,
        refresh_period: 4,
        refresh_quad: 2,
        ..Options::default()
    };
    let rewritten =
        rewrite::rewrite(&shader, &analysis, candidate, Variant::ThreePass, &options).unwrap();
    let sources = wgsl_sources(&rewritten);
    let mesh = sphere(96, 192);
    assert!(mesh.indices.len() / 3 > 30_000, "many small triangles");
    let size = (128, 128);
    let mut runner = runtime::Runner::new(
        &gpu,
        &rewritten.plan,
        |name| sources.get(name).cloned(),
        &[mesh],
        &HashMap::new(),
        size,
        runtime::RunOptions {
            pipelines: runtime::PipelineOptions {
                count_shading: true,
                cull_back_faces: false,
            },
            classify: true,
            external_group: None,
        },
    )
    .unwrap();
    let projection = glam::Mat4::perspective_rh(60f32.to_radians(), 1.0, 0.5, 10.0);
    for frame in 0..4 {
        let angle = (frame as f32 * 2.0).to_radians();
        let eye = glam::Vec3::new(3.0 * angle.sin(), 0.8, 3.0 * angle.cos());
        let clip_from_world =
            projection * glam::Mat4::look_at_rh(eye, glam::Vec3::ZERO, glam::Vec3::Y);
        let world_from_local = glam::Mat4::from_rotation_y((frame as f32 * 1.5).to_radians());
        let mut uniform = Vec::new();
        for value in clip_from_world
            .to_cols_array()
            .iter()
            .chain(world_from_local.to_cols_array().iter())
        {
            uniform.extend(value.to_le_bytes());
        }
        let inputs = runtime::FrameInputs {
            objects: vec![runtime::ObjectInputs {
                mesh: 0,
                buffers: HashMap::from([([0, 0], uniform)]),
                ..runtime::ObjectInputs::default()
            }],
            ..runtime::FrameInputs::default()
        };
        runner.frame(&gpu, &inputs, None).unwrap();

        let color = runtime::read_texture(&gpu, runner.color().unwrap(), 8).unwrap();
        let depth = runtime::read_texture(&gpu, runner.depth(), 4).unwrap();
        // After the first frame most pixels are reused: pass 1 writes their
        // depth and pass 2 is depth-tested against it, so all three passes'
        // positions must agree.
        if frame > 0 {
            let classes = runtime::read_texture(&gpu, runner.classes(), 4).unwrap();
            let decisions = crate::measure::metrics::decisions(&classes);
            assert!(decisions.hit > 0.5, "frame {frame}: {decisions:?}");
        }
        let (mut covered, mut holes, mut doubled) = (0, 0, 0);
        for pixel in 0..(size.0 * size.1) as usize {
            let d = f32::from_le_bytes(depth[pixel * 4..pixel * 4 + 4].try_into().unwrap());
            let red = half::f16::from_le_bytes([color[pixel * 8], color[pixel * 8 + 1]]).to_f32();
            let shadings = (red / 0.25).round() as i32;
            if d < 1.0 {
                covered += 1;
                match shadings {
                    1 => {}
                    0 => holes += 1,
                    _ => doubled += 1,
                }
            } else {
                assert_eq!(shadings, 0, "frame {frame}: shaded outside the mesh");
            }
        }
        assert!(
            covered > 2000,
            "frame {frame}: the sphere covers {covered} pixels"
        );
        assert_eq!(
            (holes, doubled),
            (0, 0),
            "frame {frame}: {covered} covered pixels"
        );
    }
}
