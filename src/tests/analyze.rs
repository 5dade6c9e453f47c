//! The analysis on shaders with known answers: screen-space and
//! per-frame payloads flagged.

/// Per-pixel values of a surface, a dither over the pixel's own screen
/// position, and values that read time and the camera.
const PAYLOAD_DEPENDENCES: &str = include_str!("../../tests/shaders/dependences.wgsl");

/// A vertex stage that computes the eye vector and a time-driven ripple
/// per vertex: the fragment stage reads no per-frame uniform itself.
const VARYING_DEPENDENCES: &str = r#"
struct Frame {
    clip_from_world: mat4x4<f32>,
    camera_position: vec3<f32>,
    time: f32,
}
@group(0) @binding(0) var<uniform> frame: Frame;

struct VertexOutput {
    @builtin(position) position: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) to_eye: vec3<f32>,
    @location(2) ripple: f32,
}

fn ripple_at(p: vec3<f32>) -> f32 {
    return sin(p.x * 4.0 + frame.time);
}

@vertex
fn vs(@location(0) position: vec3<f32>) -> VertexOutput {
    var out: VertexOutput;
    out.position = frame.clip_from_world * vec4<f32>(position, 1.0);
    out.world = position;
    out.to_eye = frame.camera_position - position;
    out.ripple = ripple_at(position);
    return out;
}

@fragment
fn fs(in: VertexOutput) -> @location(0) vec4<f32> {
    let pattern = sin(in.world.x * 10.0) * cos(in.world.y * 7.0);
    let sheen = pow(max(normalize(in.to_eye).z, 0.0), 8.0);
    let wave = in.ripple * sin(in.world.z * 5.0);
    return vec4<f32>(pattern, sheen, wave, 1.0);
}
"#;

/// A value of the pixel's place on the screen (a dither) would land on
/// other pixels when reprojected: rejected as screen-space. The position's
/// depth belongs to the surface point and stays cacheable.
#[test]
fn screen_space_payload_is_rejected() {
    let (_, analysis) = super::util::analyzed("dependences.wgsl", PAYLOAD_DEPENDENCES);
    let dither = analysis
        .rejected
        .iter()
        .find(|r| {
            r.node.text == "fract(sin(dot(pixel.xy, vec2<f32>(12.9898, 78.233))) * 43758.5453)"
        })
        .expect("the dither is rejected");
    assert_eq!(dither.reason, crate::analysis::RejectReason::ScreenSpace);
    assert!(
        dither.detail.contains("@builtin(position).xy"),
        "{}",
        dither.detail
    );
    // Everything that sums the dither in is screen-space too.
    assert!(analysis.rejected.iter().any(|r| r
        .node
        .text
        .starts_with("pattern * depth_fog + dither")
        && r.reason == crate::analysis::RejectReason::ScreenSpace));
    let fog = super::util::candidate(&analysis, "exp(-pixel.z * 4.0)");
    assert!(fog.depends_on.is_empty());
    // The corpus's screen-space plasma: its palette is rejected, its fog
    // from the fragment's depth is cached.
    let shader =
        crate::front::load(&super::util::root().join("corpus/position_direct.wgsl")).unwrap();
    let plasma = crate::analysis::analyze(&shader, &Default::default()).unwrap();
    assert!(plasma.rejected.iter().any(|r| r
        .node
        .text
        .starts_with("vec3<f32>(0.5) + (vec3<f32>(0.5) * cos(")
        && r.reason == crate::analysis::RejectReason::ScreenSpace));
    super::util::candidate(&plasma, "1.0 - exp(-0.08 * view_depth * view_depth)");
}

/// Values the vertex stage computes from the camera or from time, read as
/// varyings, make a fragment value just as stale as reading the uniforms
/// would: `depends_on` follows the varying back into the vertex stage and
/// into the helpers it calls.
#[test]
fn a_varying_computed_from_the_camera_is_flagged() {
    let (_, analysis) = super::util::analyzed("varyings.wgsl", VARYING_DEPENDENCES);
    let sheen = super::util::candidate(&analysis, "pow(max(normalize(in.to_eye).z, 0.0), 8.0)");
    assert_eq!(sheen.depends_on, ["camera"]);
    let wave = super::util::candidate(&analysis, "in.ripple * sin(in.world.z * 5.0)");
    assert_eq!(wave.depends_on, ["time"]);
    let pattern =
        super::util::candidate(&analysis, "sin(in.world.x * 10.0) * cos(in.world.y * 7.0)");
    assert!(pattern.depends_on.is_empty());
}
