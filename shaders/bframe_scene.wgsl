// Scene-assisted B-frames (seed 000 §4), imported at IR level into the
// I-frame module: the geometry is rasterised at the B-frame's time with
// its position at both I-frames (the twins), and each fragment takes its
// colour from the I-frames where its surface point is visible there. The
// rewriter assigns the bind group (the first free one after the twins');
// the host binds the two I-frames' colour and depth.

struct SceneParams {
    // The frame's size in pixels.
    viewport: vec2<f32>,
    // Where the B-frame is between the I-frames, in [0, 1].
    alpha: f32,
    // Two depths agree when |a - b| < depth_epsilon * |b - far_depth|.
    depth_epsilon: f32,
    // The depth buffer's far value: 1, or 0 with reversed Z.
    far_depth: f32,
    // 0: closest-on-miss (the paper's choice); 1: shade-on-miss, whose
    // double misses are discarded here and shaded by the next pass;
    // 2: single-direction reverse reprojection from I-frame 0, no
    // reshading (a baseline); 3: not a B-frame but each pixel's exact
    // correspondence in I-frame 0, (p - p0, seen there, 1), against which
    // the image-based search is measured; 4: not a B-frame but the moving
    // objects alone (the host draws no other), each fragment's offset from
    // I-frame 0, (p - p0, 0, 1), where nothing still hides it (seed 003's
    // dynamic-object velocity and mask); 5: reverse reprojection from
    // I-frame 0 whose misses are discarded here and shaded by the next
    // pass (seed 000's baseline, Figs. 7-10).
    mode: u32,
}

@group(2) @binding(0) var<uniform> scene_params: SceneParams;
@group(2) @binding(1) var scene_color_0: texture_2d<f32>;
@group(2) @binding(2) var scene_depth_0: texture_depth_2d;
@group(2) @binding(3) var scene_color_1: texture_2d<f32>;
@group(2) @binding(4) var scene_depth_1: texture_depth_2d;
// Linear filtering, clamped to the edge.
@group(2) @binding(5) var scene_sampler: sampler;

const CLOSEST_ON_MISS: u32 = 0u;
const SHADE_ON_MISS: u32 = 1u;
const REVERSE_REPROJECTION: u32 = 2u;
const CORRESPONDENCE: u32 = 3u;
const MOVING_OBJECTS: u32 = 4u;
const REVERSE_REPROJECTION_RESHADE: u32 = 5u;

// As `shaders/bframe.wgsl`'s decisions.
const SAME_SURFACE: u32 = 0u;
const ONE_DIRECTION: u32 = 2u;
const DOUBLE_MISS: u32 = 3u;

struct SceneAssisted {
    color: vec4<f32>,
    decision: u32,
}

// Where a surface point at clip position `clip` falls in an I-frame:
// its pixel position, its depth there, and whether it is on screen in
// front of the camera.
struct Reprojected {
    pixel: vec2<f32>,
    depth: f32,
    inside: bool,
}

fn scene_finite(v: vec4<f32>) -> bool {
    let exponent = bitcast<vec4<u32>>(v) & vec4<u32>(0x7f800000u);
    return all(exponent != vec4<u32>(0x7f800000u));
}

fn scene_reproject(clip: vec4<f32>) -> Reprojected {
    let ndc = clip.xyz / clip.w;
    let pixel = vec2<f32>(
        (ndc.x * 0.5 + 0.5) * scene_params.viewport.x,
        (0.5 - 0.5 * ndc.y) * scene_params.viewport.y,
    );
    let inside = (clip.w > 1e-6) & scene_finite(clip) & all(pixel >= vec2<f32>(0.0))
        & all(pixel < scene_params.viewport);
    return Reprojected(pixel, ndc.z, inside);
}

fn scene_texel(pixel: vec2<f32>) -> vec2<i32> {
    return clamp(vec2<i32>(floor(pixel)), vec2<i32>(0), vec2<i32>(scene_params.viewport) - vec2<i32>(1));
}

fn scene_agrees(a: f32, b: f32) -> bool {
    return abs(a - b) < scene_params.depth_epsilon * abs(b - scene_params.far_depth);
}

fn scene_nearer(a: f32, b: f32) -> bool {
    return select((a > b), (a < b), scene_params.far_depth > 0.5);
}

// The B-frame fragment's colour from the I-frames: its surface point
// seen in both is blended by alpha, in one taken from that one; in
// neither (a double miss), the I-frame whose depth at the reprojected
// position is the nearer (closest-on-miss), or nothing (shade-on-miss:
// discarded for the shading pass).
fn scene_assisted(frag_coord: vec4<f32>, previous_clip: vec4<f32>, next_clip: vec4<f32>) -> SceneAssisted {
    let p0 = scene_reproject(previous_clip);
    let p1 = scene_reproject(next_clip);
    let uv0 = p0.pixel / scene_params.viewport;
    let uv1 = p1.pixel / scene_params.viewport;
    let z0 = textureLoad(scene_depth_0, scene_texel(p0.pixel), 0);
    let z1 = textureLoad(scene_depth_1, scene_texel(p1.pixel), 0);
    let c0 = textureSampleLevel(scene_color_0, scene_sampler, uv0, 0.0);
    let c1 = textureSampleLevel(scene_color_1, scene_sampler, uv1, 0.0);
    let seen_0 = p0.inside & scene_agrees(z0, p0.depth);
    let seen_1 = p1.inside & scene_agrees(z1, p1.depth);
    if scene_params.mode == CORRESPONDENCE {
        let offset = frag_coord.xy - p0.pixel;
        return SceneAssisted(vec4<f32>(offset, select(0.0, 1.0, seen_0), 1.0), SAME_SURFACE);
    }
    if scene_params.mode == MOVING_OBJECTS {
        // The still geometry is not drawn: a fragment is hidden where both
        // I-frames show a nearer surface at its pixel (I-frame 0 alone at
        // I-frame 0's own time, where that is exact).
        let here = scene_texel(frag_coord.xy);
        let z = frag_coord.z;
        let here_0 = textureLoad(scene_depth_0, here, 0);
        let here_1 = textureLoad(scene_depth_1, here, 0);
        let hidden_0 = scene_nearer(here_0, z) & !scene_agrees(here_0, z);
        let hidden_1 = scene_nearer(here_1, z) & !scene_agrees(here_1, z);
        if hidden_0 & (hidden_1 | (scene_params.alpha == 0.0)) {
            discard;
        }
        return SceneAssisted(vec4<f32>(frag_coord.xy - p0.pixel, 0.0, 1.0), SAME_SURFACE);
    }
    if scene_params.mode == REVERSE_REPROJECTION {
        return SceneAssisted(c0, select(DOUBLE_MISS, SAME_SURFACE, seen_0));
    }
    if scene_params.mode == REVERSE_REPROJECTION_RESHADE {
        // What I-frame 0 does not show is shaded again (the second pass).
        if !seen_0 {
            discard;
        }
        return SceneAssisted(c0, SAME_SURFACE);
    }
    if seen_0 & seen_1 {
        return SceneAssisted(mix(c0, c1, scene_params.alpha), SAME_SURFACE);
    }
    if seen_0 | seen_1 {
        return SceneAssisted(select(c1, c0, seen_0), ONE_DIRECTION);
    }
    if scene_params.mode == SHADE_ON_MISS {
        discard;
    }
    // Closest-on-miss: an I-frame whose reprojected position is off
    // screen has nothing to offer.
    let take_0 = p0.inside & (!p1.inside | scene_nearer(z0, z1));
    return SceneAssisted(select(c1, c0, take_0), DOUBLE_MISS);
}
