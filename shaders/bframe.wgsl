// B-frames: the frames between two I-frames, built in one fullscreen pass
// from what the I-frames stored (colour, depth and the flows of
// `shaders/iframe.wgsl`). I-frame 0 is the earlier one (time t), I-frame 1
// the later (t + 1); the B-frame is at t + alpha. Every method is a
// fragment entry point here; `src/interpolate/mod.rs` says which paper
// each follows and what was decided where the paper is silent.
//
// Positions are in pixels (x right, y down, pixel centres at +0.5), as
// `@builtin(position).xy`. Depth and flows are read per texel with
// `textureLoad`; colour bilinearly with `textureSampleLevel` (explicit
// level: nothing here needs uniform control flow).

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
    // tails (else the later frame's velocity alone). Bit 2: half-velocity
    // has its moving objects drawn and removed. Bit 3: of two converged
    // starts on different surfaces the smaller residual wins (the paper),
    // not the nearer.
    flags: u32,
    // Half-velocity's direction test: the previous velocity is used for a
    // tail only when its cosine with the current one is at least this.
    min_cosine: f32,
    // α' of the B-frame before this one in the interval, whose offsets
    // seed latest-frame initialisation; 0 for an interval's first.
    previous_alpha: f32,
    // Character removal's neighbour distance, in pixels (`fs_inpaint`).
    inpaint_delta: i32,
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

// Half-velocity's moving objects (seed 003's dynamic objects, slides
// 33–47), drawn by the scene-assisted pass in its moving-objects mode;
// zero where there are none, or when the method leaves them out.
// The moving objects at the B-frame's time: (p - p0, 0, 1), p0 where the
// pixel's point is in I-frame 0; w is the mask.
@group(0) @binding(11) var moving_now: texture_2d<f32>;
// I-frame 0 with the moving objects it shows wiped out (`fs_inpaint`), at
// quarter resolution.
@group(0) @binding(12) var removed_0: texture_2d<f32>;

const DUAL_INIT: u32 = 1u;
const VELOCITY_MERGE: u32 = 2u;
// Bit 2: half-velocity has its moving objects (`moving_now`, `removed_0`).
const MOVING_OBJECTS: u32 = 4u;
// Bit 3: of two converged starts the smaller residual wins, as seed 000
// states it (`--paper`), not the nearer surface.
const SMALLER_RESIDUAL: u32 = 8u;

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

// A flow at `p`: its texel's, unfiltered. Filtering would mix an
// object's flow with the background's along its silhouette and send the
// search to a point on neither surface; unfiltered, it converges onto one
// of them and the decisions pick. Measured on the walking scene (256²):
// SSIM unchanged to 0.001 and the pass a third cheaper than bilinear.
// Invalid texels (w = 0: no geometry there, or a twin behind the camera)
// hold zeros.
fn flow_at(t: texture_2d<f32>, p: vec2<f32>) -> vec4<f32> {
    return textureLoad(t, texel(p), 0);
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
    // The point's depth in its own I-frame, and the I-frame's flow there
    // (towards the other I-frame): what eqs. 14–15 read again.
    own_depth: f32,
    flow: vec4<f32>,
}

// The fixed-point search of seed 000 §5.1: q <- p - s·V(q) for at most m
// iterations (the paper always runs m; this stops early where a step
// stays in its texel, which gives the same point: see the loop), V the
// I-frame's flow towards
// the other I-frame and s the share of it the B-frame is away. It starts
// at `start`, whose flow `start_flow` the caller has read (the default
// start's is shared with the dual start of the other direction).
fn search(flow: texture_2d<f32>, depth: texture_depth_2d, p: vec2<f32>, start: vec2<f32>, start_flow: vec4<f32>, s: f32) -> Found {
    var q = start;
    var v = start_flow;
    for (var i = 0u; i < search_iterations; i++) {
        let next = p - s * v.xy;
        // Flows are read per texel: a step that stays in q's texel reads
        // the same V again and lands on the same point, every step after.
        // Stopping there changes nothing but the time.
        let stays = all(texel(next) == texel(q));
        q = next;
        if stays {
            break;
        }
        v = flow_at(flow, q);
    }
    let valid = (v.w > 0.5) & on_screen(q);
    let error = length(q + s * v.xy - p);
    let own_depth = depth_at(depth, q);
    return Found(q, select(NO_ERROR_BOUND, error, valid), own_depth + s * v.z, own_depth, v);
}

// The search from another start, reading its flow.
fn search_from(flow: texture_2d<f32>, depth: texture_depth_2d, p: vec2<f32>, start: vec2<f32>, s: f32) -> Found {
    return search(flow, depth, p, start, flow_at(flow, start), s);
}

// One direction's search: from p itself and, with dual initialisation,
// also from `dual` (eqs. 16–17). The second search is skipped where it
// starts within ε1 of where the first ended (it would converge to the
// same point; most pixels of a frame do).
fn best_search(flow: texture_2d<f32>, depth: texture_depth_2d, p: vec2<f32>, flow_at_p: vec4<f32>, dual: vec2<f32>, s: f32) -> Found {
    let plain = search(flow, depth, p, p, flow_at_p, s);
    if ((params.flags & DUAL_INIT) == 0u) | (distance(dual, plain.point) < params.screen_epsilon) {
        return plain;
    }
    return better(plain, search_from(flow, depth, p, dual, s));
}

// Of two correspondences for the same pixel in the same I-frame: where
// both are under ε1 on different surfaces, the nearer (both are fixed
// points; the farther is the surface the nearer hides at the B-frame's
// time, the floor behind a moving sphere's rim); else the smaller
// residual, as the paper. Measured on the walking scene (256²): mean SSIM
// 0.967 -> 0.980 over the smaller residual alone (which `SMALLER_RESIDUAL`
// asks for).
fn better(a: Found, b: Found) -> Found {
    let both = (a.error < params.screen_epsilon) & (b.error < params.screen_epsilon);
    let nearer_rule = (params.flags & SMALLER_RESIDUAL) == 0u;
    if nearer_rule & both & !depths_agree(a.depth, b.depth) {
        if nearer(b.depth, a.depth) {
            return b;
        }
        return a;
    }
    if b.error < a.error {
        return b;
    }
    return a;
}

// Eqs. 14–15: the colour of a point found in one I-frame (`own`),
// blended with the same point in the other (carried there by the exact
// flow, weighted `other_weight`) where it is visible there; else its own
// I-frame's alone (§5.2's fallback).
fn carried(found: Found, own: texture_2d<f32>, other: texture_2d<f32>, other_depth: texture_depth_2d, other_weight: f32) -> vec4<f32> {
    let color = bilinear(own, found.point);
    let there = found.point + found.flow.xy;
    let agree = depths_agree(depth_at(other_depth, there), found.own_depth + found.flow.z);
    if (found.flow.w > 0.5) & on_screen(there) & agree {
        return mix(color, bilinear(other, there), other_weight);
    }
    return color;
}

// What the image-based pass writes: besides the colour and decision, the
// offsets it found and the depth it chose, for the next B-frame's
// latest-frame initialisation, and which direction it took (1 forward,
// into I-frame 0; 0 backward), which Fig. 11's E_total reads.
struct ImageBased {
    @location(0) color: vec4<f32>,
    @location(1) decision: u32,
    @location(2) offsets: vec4<f32>,
    @location(3) depth: vec2<f32>,
}

// The diagonal neighbours of latest-frame initialisation's neighbourhood,
// `latest_radius` pixels away (the centre and these: the design note's 5
// taps; the paper leaves the neighbourhood's size open).
const LATEST_TAPS: array<vec2<i32>, 4> = array<vec2<i32>, 4>(
    vec2<i32>(-1, -1), vec2<i32>(1, -1), vec2<i32>(-1, 1), vec2<i32>(1, 1),
);
override latest_radius: i32 = 1;

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
        let tap = clamp(at + latest_radius * LATEST_TAPS[i], vec2<i32>(0), last);
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
    // The two flows at p: each direction's first step, and (eqs. 16–17)
    // the other direction's dual start.
    let forward_at_p = flow_at(flow_next_0, p);
    let backward_at_p = flow_at(flow_previous_1, p);
    var forward = best_search(flow_next_0, depth_0, p, forward_at_p, p + a * backward_at_p.xy, a);
    var backward = best_search(flow_previous_1, depth_1, p, backward_at_p, p + (1.0 - a) * forward_at_p.xy, 1.0 - a);
    // Eqs. 18–19, in addition: the smaller residual wins.
    if latest_init && (params.previous_alpha > 0.0) {
        let start = latest_offsets(p);
        if distance(p - start.xy, forward.point) >= params.screen_epsilon {
            forward = better(forward, search_from(flow_next_0, depth_0, p, p - start.xy, a));
        }
        if distance(p - start.zw, backward.point) >= params.screen_epsilon {
            backward = better(backward, search_from(flow_previous_1, depth_1, p, p - start.zw, 1.0 - a));
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
        let geometry = (forward_at_p.w > 0.5) | (backward_at_p.w > 0.5);
        decision = select(BACKGROUND, DOUBLE_MISS, geometry);
    }
    var color: vec4<f32>;
    var depth: f32;
    if use_forward {
        color = carried(forward, color_0, color_1, depth_1, params.alpha);
        depth = forward.depth;
    } else {
        color = carried(backward, color_1, color_0, depth_0, 1.0 - params.alpha);
        depth = backward.depth;
    }
    let direction = select(0.0, 1.0, use_forward);
    return ImageBased(color, decision, vec4<f32>(p - forward.point, p - backward.point), vec2<f32>(depth, direction));
}

// Seed 003: the earlier I-frame sampled back along the velocity,
// alpha of the way (half-way at n = 2). A moving object's pixel at the
// B-frame's time is taken from where its point is in I-frame 0, exactly
// (the moving-objects pass rasterised it there). Elsewhere the velocity
// is the later I-frame's (its flow to the earlier one) where that frame's
// surface is the nearer or the same; where the earlier frame's surface is
// nearer (a moving object's tail, gone by the later frame) it is the
// earlier frame's own velocity, extrapolated, unless its direction
// disagrees with the later one's, where the pixel is held (no worse than
// sample and hold). Where the point sampled showed a moving object in
// I-frame 0 that is not at the pixel now, the frame with the objects
// wiped out is shown instead (slide 47).
@fragment
fn fs_half_velocity(@builtin(position) frag_coord: vec4<f32>) -> BFrame {
    let p = frag_coord.xy;
    let at = texel(p);
    let moving = textureLoad(moving_now, at, 0);
    if moving.w > 0.5 {
        return BFrame(bilinear(color_0, p - moving.xy), SAME_SURFACE);
    }
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
    let q = p + params.alpha * v;
    let color = bilinear(color_0, q);
    // Whether I-frame 0 shows a moving object at q, from its flow at full
    // resolution (the removal's own mask is at quarter resolution); then
    // the removal's colour, filtered.
    let removal = (params.flags & MOVING_OBJECTS) != 0u;
    if removal && (textureLoad(flow_next_0, texel(q), 0).w > 1.5) {
        let uv = q / (2.0 * vec2<f32>(removal_size()));
        let removed = textureSampleLevel(removed_0, linear_clamp, uv, 0.0);
        return BFrame(vec4<f32>(removed.rgb, color.a), decision);
    }
    return BFrame(color, decision);
}

// Character removal (seed 003, slides 39–46), one pass at quarter
// resolution (half the width and height, as the paper's): a masked pixel
// takes the mean of the unmasked ones among its four neighbours
// `inpaint_delta` pixels away (left, right, up, down) and is unmasked for
// the next pass, so the fill grows in from the mask's edge; one with no
// unmasked neighbour is left as it is, still masked. The first pass
// (`fs_inpaint_first`) reads I-frame 0's colour and its flow, whose w is
// 2 on a moving object, at full resolution, one pixel of every four; the
// next ones the pass before's result, whose w says what became of each
// pixel: 0 never masked, 0.5 filled, 1 still masked. Andreev's
// refinements (horizontal patches move only horizontally, the interior
// blurred) are left out.
@group(0) @binding(14) var inpaint_color: texture_2d<f32>;
@group(0) @binding(15) var inpaint_mask: texture_2d<f32>;

const INPAINT_NEIGHBOURS: array<vec2<i32>, 4> = array<vec2<i32>, 4>(
    vec2<i32>(-1, 0), vec2<i32>(1, 0), vec2<i32>(0, -1), vec2<i32>(0, 1),
);

// The size of character removal's frames: half the B-frame's, rounded up.
fn removal_size() -> vec2<i32> {
    return (vec2<i32>(params.viewport) + vec2<i32>(1)) / 2;
}

@fragment
fn fs_inpaint_first(@builtin(position) frag_coord: vec4<f32>) -> @location(0) vec4<f32> {
    return inpaint(vec2<i32>(frag_coord.xy), 2, 1.5);
}

@fragment
fn fs_inpaint(@builtin(position) frag_coord: vec4<f32>) -> @location(0) vec4<f32> {
    return inpaint(vec2<i32>(frag_coord.xy), 1, 0.75);
}

// Removal pixel `at`, reading the inputs every `step` texels, a pixel
// masked where the mask's w is at least `masked`.
fn inpaint(at: vec2<i32>, step: i32, masked: f32) -> vec4<f32> {
    let size = removal_size();
    let last = vec2<i32>(textureDimensions(inpaint_color)) - vec2<i32>(1);
    let own = textureLoad(inpaint_color, min(at * step, last), 0).rgb;
    let mask = textureLoad(inpaint_mask, min(at * step, last), 0).w;
    if mask < masked {
        // Never masked (0, or a still object's flow), or filled by an
        // earlier pass (0.5).
        return vec4<f32>(own, select(0.0, 0.5, (mask > 0.25) & (mask < 0.75)));
    }
    var sum = vec3<f32>(0.0);
    var count = 0.0;
    for (var i = 0; i < 4; i++) {
        let tap = at + params.inpaint_delta * INPAINT_NEIGHBOURS[i];
        let inside = all(tap >= vec2<i32>(0)) & all(tap < size);
        let tap_at = clamp(tap * step, vec2<i32>(0), last);
        if inside & (textureLoad(inpaint_mask, tap_at, 0).w < masked) {
            sum += textureLoad(inpaint_color, tap_at, 0).rgb;
            count += 1.0;
        }
    }
    if count > 0.0 {
        return vec4<f32>(sum / count, 0.5);
    }
    return vec4<f32>(own, 1.0);
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
