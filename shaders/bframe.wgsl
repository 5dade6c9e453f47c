// B-frames: the frames between two I-frames, built in one fullscreen pass
// from what the I-frames stored (colour, depth and the flows of
// `shaders/iframe.wgsl`). I-frame 0 is the earlier one (time t), I-frame 1
// the later (t + 1); the B-frame is at t + alpha. Every method is a
// fragment entry point here; `src/interpolate/mod.rs` says which paper
// each follows and what was decided where the paper is silent.
//
// Positions are in pixels (x right, y down, pixel centres at +0.5), as
// `@builtin(position).xy`. Depth is read nearest with `textureLoad`;
// colour and flows bilinearly with `textureSampleLevel` (explicit level:
// nothing here needs uniform control flow).

struct BFrameParams {
    // The frame's size in pixels.
    viewport: vec2<f32>,
    // Where the B-frame is between the I-frames, in [0, 1].
    alpha: f32,
    // ε1: the largest screen-space error, in pixels, of a correspondence.
    screen_epsilon: f32,
    // ε2 and the visibility test: two depths agree when
    // |a - b| < depth_epsilon * |b - far_depth| (the cache's test).
    depth_epsilon: f32,
    // The depth buffer's far value: 1, or 0 with reversed Z.
    far_depth: f32,
    // Bit 0: dual initialisation (seed 000 eqs. 16–17) besides the default.
    // Bit 1: half-velocity merges the earlier frame's velocity into the
    // tails (else the later frame's velocity alone).
    flags: u32,
    // Half-velocity's direction test: the previous velocity is used for a
    // tail only when its cosine with the current one is at least this.
    min_cosine: f32,
    // α' of the B-frame before this one in the interval, whose offsets
    // seed latest-frame initialisation; 0 for an interval's first.
    previous_alpha: f32,
}

@group(0) @binding(0) var<uniform> params: BFrameParams;

// m: the fixed number of search iterations (seed 000 §5.1), set when the
// pipeline is made: a constant bound lets the compiler unroll the search
// (measured on lavapipe: the pass 12% faster than with m in the uniform).
override search_iterations: u32 = 3u;
// Linear filtering, clamped to the edge.
@group(0) @binding(1) var linear_clamp: sampler;
@group(0) @binding(2) var color_0: texture_2d<f32>;
@group(0) @binding(3) var depth_0: texture_depth_2d;
// I-frame 0's flow to the I-frame before it (Vb_t): half-velocity's
// previous velocity.
@group(0) @binding(4) var flow_previous_0: texture_2d<f32>;
// I-frame 0's flow to I-frame 1 (Vf_t).
@group(0) @binding(5) var flow_next_0: texture_2d<f32>;
@group(0) @binding(6) var color_1: texture_2d<f32>;
@group(0) @binding(7) var depth_1: texture_depth_2d;
// I-frame 1's flow to I-frame 0 (Vb_{t+1}).
@group(0) @binding(8) var flow_previous_1: texture_2d<f32>;
// The previous image-based B-frame's offsets (p - q into I-frame 0, p - q
// into I-frame 1) and the depth it chose, for latest-frame
// initialisation.
@group(0) @binding(9) var previous_offsets: texture_2d<f32>;
@group(0) @binding(10) var previous_depths: texture_2d<f32>;

const DUAL_INIT: u32 = 1u;
const VELOCITY_MERGE: u32 = 2u;

// Latest-frame initialisation (seed 000 eqs. 18–19), set when the
// pipeline is made: its code compiled into the pass even behind a false
// uniform flag made the pass half as costly again on lavapipe.
override latest_init: bool = false;
// A search that found nothing has this error.
const NO_ERROR_BOUND: f32 = 1e30;

// What each B-frame pixel decided, written beside its colour.
const SAME_SURFACE: u32 = 0u;
const NEARER_SURFACE: u32 = 1u;
const ONE_DIRECTION: u32 = 2u;
const DOUBLE_MISS: u32 = 3u;
// No geometry at the pixel in either I-frame and nothing found.
const BACKGROUND: u32 = 4u;

struct BFrame {
    @location(0) color: vec4<f32>,
    @location(1) decision: u32,
}

@vertex
fn vs_fullscreen(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4<f32>(uv * vec2<f32>(2.0, -2.0) + vec2<f32>(-1.0, 1.0), 0.0, 1.0);
}

fn on_screen(p: vec2<f32>) -> bool {
    return all(p >= vec2<f32>(0.0)) & all(p <= params.viewport);
}

fn bilinear(t: texture_2d<f32>, p: vec2<f32>) -> vec4<f32> {
    return textureSampleLevel(t, linear_clamp, p / params.viewport, 0.0);
}

// A flow at `p`, bilinear. Invalid texels (w = 0, no geometry there or a
// twin behind the camera) hold zeros, so dividing by the interpolated w
// averages the valid ones; w says how much of the footprint was valid.
fn flow_at(t: texture_2d<f32>, p: vec2<f32>) -> vec4<f32> {
    let f = bilinear(t, p);
    if f.w > 0.0 {
        return vec4<f32>(f.xyz / f.w, f.w);
    }
    return vec4<f32>(0.0);
}

fn texel(p: vec2<f32>) -> vec2<i32> {
    return clamp(vec2<i32>(floor(p)), vec2<i32>(0), vec2<i32>(params.viewport) - vec2<i32>(1));
}

fn depth_at(t: texture_depth_2d, p: vec2<f32>) -> f32 {
    return textureLoad(t, texel(p), 0);
}

// ε2 and the visibility tests: the cache's relative depth test (equal
// depths agree, the far plane's too).
fn depths_agree(a: f32, b: f32) -> bool {
    return (a == b) | (abs(a - b) < params.depth_epsilon * abs(b - params.far_depth));
}

// Whether depth a is nearer the camera than b.
fn nearer(a: f32, b: f32) -> bool {
    return select((a > b), (a < b), params.far_depth > 0.5);
}

// A correspondence found by the search.
struct Found {
    // Where the B-frame pixel's surface point is in the I-frame.
    point: vec2<f32>,
    // The residual |q + s·V(q) - p| in pixels (eqs. 7, 12);
    // NO_ERROR_BOUND where the search left the screen or the flow there
    // is invalid.
    error: f32,
    // The point's depth carried to the B-frame's time (eqs. 6, 11).
    depth: f32,
}

// The fixed-point search of seed 000 §5.1 from `start`: q <- p - s·V(q)
// for m iterations (no early exit, as the paper), V the I-frame's flow
// towards the other I-frame and s the share of it the B-frame is away.
fn search(flow: texture_2d<f32>, depth: texture_depth_2d, p: vec2<f32>, start: vec2<f32>, s: f32) -> Found {
    var q = start;
    for (var i = 0u; i < search_iterations; i++) {
        q = p - s * flow_at(flow, q).xy;
    }
    let v = flow_at(flow, q);
    let valid = (v.w > 0.5) & on_screen(q);
    let error = length(q + s * v.xy - p);
    return Found(q, select(NO_ERROR_BOUND, error, valid), depth_at(depth, q) + s * v.z);
}

// A residual below this (pixels) is a converged search: another start
// cannot do measurably better.
const CONVERGED: f32 = 0.01;

// The better of the default start (p itself) and, with dual
// initialisation, `dual`: the smaller error. The second search is skipped
// where the first converged (the paper runs both; the result is the same
// to CONVERGED, and most pixels of a frame converge from p).
fn best_search(flow: texture_2d<f32>, depth: texture_depth_2d, p: vec2<f32>, dual: vec2<f32>, s: f32) -> Found {
    let plain = search(flow, depth, p, p, s);
    if ((params.flags & DUAL_INIT) == 0u) | (plain.error < CONVERGED) {
        return plain;
    }
    let other = search(flow, depth, p, dual, s);
    if other.error < plain.error {
        return other;
    }
    return plain;
}

// Eq. 14: the colour of a point found in I-frame 0, blended with the same
// point in I-frame 1 (carried there by the exact flow) where it is visible
// there; else I-frame 0's alone (§5.2's fallback).
fn from_frame_0(q: vec2<f32>) -> vec4<f32> {
    let c0 = bilinear(color_0, q);
    let v = flow_at(flow_next_0, q);
    let there = q + v.xy;
    let expected = depth_at(depth_0, q) + v.z;
    let agree = depths_agree(depth_at(depth_1, there), expected);
    if (v.w > 0.5) & on_screen(there) & agree {
        return mix(c0, bilinear(color_1, there), params.alpha);
    }
    return c0;
}

// Eq. 15: the same from a point found in I-frame 1.
fn from_frame_1(q: vec2<f32>) -> vec4<f32> {
    let c1 = bilinear(color_1, q);
    let v = flow_at(flow_previous_1, q);
    let there = q + v.xy;
    let expected = depth_at(depth_1, q) + v.z;
    let agree = depths_agree(depth_at(depth_0, there), expected);
    if (v.w > 0.5) & on_screen(there) & agree {
        return mix(bilinear(color_0, there), c1, params.alpha);
    }
    return c1;
}

// What the image-based pass writes: besides the colour and decision, the
// offsets it found and the depth it chose, for the next B-frame's
// latest-frame initialisation.
struct ImageBased {
    @location(0) color: vec4<f32>,
    @location(1) decision: u32,
    @location(2) offsets: vec4<f32>,
    @location(3) depth: f32,
}

// The diagonal neighbours of latest-frame initialisation's neighbourhood
// (the centre and these: the design note's 5 taps; the paper leaves its
// size open).
const LATEST_TAPS: array<vec2<i32>, 4> = array<vec2<i32>, 4>(
    vec2<i32>(-1, -1), vec2<i32>(1, -1), vec2<i32>(-1, 1), vec2<i32>(1, 1),
);

// Eqs. 18–19: the start offsets from the previous B-frame's, rescaled to
// this α (forward by α/α', backward by (1 - α)/(1 - α')): of the taps
// around p, the one whose chosen surface was the nearest (§5.3: "whichever
// has the smallest depth").
fn latest_offsets(p: vec2<f32>) -> vec4<f32> {
    let at = texel(p);
    let last = vec2<i32>(params.viewport) - vec2<i32>(1);
    var best = textureLoad(previous_offsets, at, 0);
    var best_depth = textureLoad(previous_depths, at, 0).x;
    for (var i = 0; i < 4; i++) {
        let tap = clamp(at + LATEST_TAPS[i], vec2<i32>(0), last);
        let depth = textureLoad(previous_depths, tap, 0).x;
        if nearer(depth, best_depth) {
            best = textureLoad(previous_offsets, tap, 0);
            best_depth = depth;
        }
    }
    let forward = params.alpha / params.previous_alpha;
    let backward = (1.0 - params.alpha) / (1.0 - params.previous_alpha);
    return vec4<f32>(best.xy * forward, best.zw * backward);
}

// Seed 000 §5: image-based bidirectional reprojection.
@fragment
fn fs_image_based(@builtin(position) frag_coord: vec4<f32>) -> BFrame {
    let found = image_based(frag_coord.xy);
    return BFrame(found.color, found.decision);
}

// The same, writing its offsets and chosen depth for the next B-frame's
// latest-frame initialisation (two more targets: measured on lavapipe,
// half as costly again, so only the pass that initialises from them
// writes them).
@fragment
fn fs_image_based_latest(@builtin(position) frag_coord: vec4<f32>) -> ImageBased {
    return image_based(frag_coord.xy);
}

fn image_based(p: vec2<f32>) -> ImageBased {
    let a = params.alpha;
    // Eqs. 16–17: each direction may also start from the velocity the
    // other I-frame stored at p.
    var forward = best_search(flow_next_0, depth_0, p, p + a * flow_at(flow_previous_1, p).xy, a);
    var backward = best_search(flow_previous_1, depth_1, p, p + (1.0 - a) * flow_at(flow_next_0, p).xy, 1.0 - a);
    // Eqs. 18–19, in addition: the smaller residual wins.
    if latest_init && (params.previous_alpha > 0.0) {
        let start = latest_offsets(p);
        if forward.error >= CONVERGED {
            let latest = search(flow_next_0, depth_0, p, p - start.xy, a);
            if latest.error < forward.error {
                forward = latest;
            }
        }
        if backward.error >= CONVERGED {
            let latest = search(flow_previous_1, depth_1, p, p - start.zw, 1.0 - a);
            if latest.error < backward.error {
                backward = latest;
            }
        }
    }
    let ok_forward = forward.error < params.screen_epsilon;
    let ok_backward = backward.error < params.screen_epsilon;
    // Ties take eq. 15 (eb <= ef).
    var use_forward = forward.error < backward.error;
    var decision = SAME_SURFACE;
    if ok_forward & ok_backward {
        if !depths_agree(forward.depth, backward.depth) {
            // Different surfaces: the nearer occludes the other.
            use_forward = nearer(forward.depth, backward.depth);
            decision = NEARER_SURFACE;
        }
    } else if ok_forward | ok_backward {
        use_forward = ok_forward;
        decision = ONE_DIRECTION;
    } else {
        let geometry = (textureLoad(flow_next_0, texel(p), 0).w > 0.5) | (textureLoad(flow_previous_1, texel(p), 0).w > 0.5);
        decision = select(BACKGROUND, DOUBLE_MISS, geometry);
    }
    var color: vec4<f32>;
    var depth: f32;
    if use_forward {
        color = from_frame_0(forward.point);
        depth = forward.depth;
    } else {
        color = from_frame_1(backward.point);
        depth = backward.depth;
    }
    return ImageBased(color, decision, vec4<f32>(p - forward.point, p - backward.point), depth);
}

// Seed 003: the earlier I-frame sampled back along the velocity,
// alpha of the way (half-way at n = 2). The velocity is the later
// I-frame's (its flow to the earlier one) where that frame's surface is
// the nearer or the same; where the earlier frame's surface is nearer (a
// moving object's tail, gone by the later frame) it is the earlier
// frame's own velocity, extrapolated, unless its direction disagrees with
// the later one's, where the pixel is held (no worse than sample and
// hold).
@fragment
fn fs_half_velocity(@builtin(position) frag_coord: vec4<f32>) -> BFrame {
    let p = frag_coord.xy;
    let at = texel(p);
    let now = textureLoad(flow_previous_1, at, 0);
    let before = textureLoad(flow_previous_0, at, 0);
    let z1 = textureLoad(depth_1, at, 0);
    let z0 = textureLoad(depth_0, at, 0);
    var v = select(vec2<f32>(0.0), now.xy, now.w > 0.5);
    var decision = SAME_SURFACE;
    let merge = (params.flags & VELOCITY_MERGE) != 0u;
    if merge & (before.w > 0.5) & nearer(z0, z1) & !depths_agree(z0, z1) {
        v = before.xy;
        decision = NEARER_SURFACE;
        let moving = (length(now.xy) > 0.5) & (length(before.xy) > 0.5) & (now.w > 0.5);
        if moving && dot(normalize(now.xy), normalize(before.xy)) < params.min_cosine {
            v = vec2<f32>(0.0);
            decision = ONE_DIRECTION;
        }
    }
    return BFrame(bilinear(color_0, p + params.alpha * v), decision);
}

// Baseline: the earlier I-frame shown again.
@fragment
fn fs_sample_and_hold(@builtin(position) frag_coord: vec4<f32>) -> BFrame {
    return BFrame(textureLoad(color_0, texel(frag_coord.xy), 0), SAME_SURFACE);
}

// Baseline: the two I-frames cross-faded at the same pixel.
@fragment
fn fs_linear_blend(@builtin(position) frag_coord: vec4<f32>) -> BFrame {
    let at = texel(frag_coord.xy);
    return BFrame(mix(textureLoad(color_0, at, 0), textureLoad(color_1, at, 0), params.alpha), SAME_SURFACE);
}
