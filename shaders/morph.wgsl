// Morph-and-blur extrapolation (seed 004, Didyk et al. 2010): the frames
// after a rendered frame, warped forward from it with no added lag, their
// errors hidden by blur and the lost high frequencies given back in the
// rendered frame. `src/interpolate/morph.rs` drives the passes and says
// what was decided where the paper is silent:
//
// 1. `fs_flow_edges`: the motion's gradient per pixel, packed with its
//    place in its grid vertex's neighbourhood; `fs_argmax_reduce` halves
//    it log2(grid) times into one texel per grid vertex, the strongest
//    motion discontinuity near it and where it is (the paper's argmax MIP).
// 2. `fs_blur_down`: the rendered frame's low-pass pyramid.
// 3. `fs_compensate`: the rendered frame as displayed, its high
//    frequencies amplified so the group of N frames integrates to it, and
//    the low-pass at full resolution for the in-between frames.
// 4. `vs_morph` + `fs_morph`: one in-between frame, the grid snapped and
//    moved by the motion, rasterised with the rendered frame's depth.
//
// Positions are in pixels (x right, y down, pixel corners at integers),
// colours display values whose light is value^gamma.

struct MorphParams {
    // The frame's size in pixels.
    viewport: vec2<f32>,
    // s_k = k/N: how far along the motion the in-between frame is.
    step: f32,
    // N: displayed frames per rendered frame.
    frames: f32,
    // The display's gamma: light = value^gamma.
    gamma: f32,
    // +1: the flow bound is the motion to the next rendered frame (the
    // twin's); -1: it is the flow to the previous one, extrapolated.
    motion_sign: f32,
    // Degrees per second of eye motion per pixel of flow: R_r / ppd.
    speed_scale: f32,
    // The eye-tracking damping f(v) = 1 - smoothstep(from, to, v), deg/s.
    track_from: f32,
    track_to: f32,
    // The speed gate (`blur_gated_by_speed`, `--blur-min-speed`): blur
    // only where the motion is at least this fast (deg/s). Not the paper's
    // selective blur, which gates by luminance and range.
    blur_min_speed: f32,
    // The grid distortion mapped to full blur: smoothstep(from, to, D).
    distortion_from: f32,
    distortion_to: f32,
    // A vertex snaps only to a motion gradient of at least this (pixels of
    // flow per pixel).
    snap_threshold: f32,
    // The depth buffer's far value: 1, or 0 with reversed Z.
    far_depth: f32,
    // The grid's spacing in pixels (a power of two).
    grid: u32,
    // 1: snap the grid to the motion's discontinuities.
    snap: u32,
}

// Set when the pipelines are made, so that no pass carries a branch it
// never takes (a software rasteriser runs both sides of a branch on a
// uniform): blur the in-between frames and compensate the rendered one;
// blur only where the motion is fast enough (`blur_min_speed`).
override blur: bool = true;
override blur_gated_by_speed: bool = false;

@group(0) @binding(0) var<uniform> params: MorphParams;
// Linear filtering, clamped to the edge.
@group(0) @binding(1) var linear_clamp: sampler;
// The rendered frame.
@group(0) @binding(2) var color: texture_2d<f32>;
@group(0) @binding(3) var depth: texture_depth_2d;
// Its flow (x, y in pixels, w = 0 where not valid): to the next rendered
// frame, or to the previous one (`motion_sign`).
@group(0) @binding(4) var flow: texture_2d<f32>;
// One texel per grid vertex: the argmax of its neighbourhood.
@group(0) @binding(5) var snap: texture_2d<u32>;
// The low-pass: the pyramid level the blur reads.
@group(0) @binding(6) var low: texture_2d<f32>;
// The same read back to full resolution (`fs_compensate`'s second
// output), where the speed gate leaves the frame sharp the frame itself:
// what the in-between frames warp.
@group(0) @binding(9) var low_full: texture_2d<f32>;
// What the reduction and the pyramid passes halve.
@group(0) @binding(7) var argmax_source: texture_2d<u32>;
@group(0) @binding(8) var blur_source: texture_2d<f32>;

@vertex
fn vs_fullscreen(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4<f32>(uv * vec2<f32>(2.0, -2.0) + vec2<f32>(-1.0, 1.0), 0.0, 1.0);
}

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

fn texel_in_frame(p: vec2<i32>) -> vec2<i32> {
    return clamp(p, vec2<i32>(0), vec2<i32>(params.viewport) - 1);
}

// The motion of the surface at texel `p` over one rendered interval, in
// pixels (zero where the flow is not valid).
fn motion_at(p: vec2<i32>) -> vec2<f32> {
    let f = textureLoad(flow, texel_in_frame(p), 0);
    return select(vec2<f32>(0.0), params.motion_sign * f.xy, f.w > 0.0);
}

// Its speed on the retina, deg/s.
fn speed_at(p: vec2<i32>) -> f32 {
    return length(motion_at(p)) * params.speed_scale;
}

// The eye-tracking damping (seed 004 §6): 1 below `track_from`, 0 above
// `track_to`, a cubic smooth step between.
fn tracking(speed: f32) -> f32 {
    return 1.0 - smoothstep(params.track_from, params.track_to, speed);
}

// ---- 1. The strongest motion discontinuity near each grid vertex ----

// Level 0 of the argmax pyramid, over the frame shifted by grid/2 so that
// texel block [g*i, g*i + g) holds vertex i's neighbourhood
// [g*i - g/2, g*i + g/2). A texel packs the gradient's magnitude
// (16 bits, 1/256 pixel steps, zero under the snap threshold) above its
// place in the block (8 bits each for y and x): the integer maximum of a
// block is its largest gradient, ties going to the larger y, then x.
@fragment
fn fs_flow_edges(@builtin(position) position: vec4<f32>) -> @location(0) u32 {
    let texel = vec2<i32>(position.xy);
    let half = i32(params.grid / 2u);
    let p = texel - vec2<i32>(half);
    let size = vec2<i32>(params.viewport);
    let place = vec2<u32>(texel) % params.grid;
    let place_code = (place.y << 8u) | place.x;
    if any(p < vec2<i32>(0)) || any(p >= size) {
        return place_code;
    }
    let here = motion_at(p);
    var gradient = 0.0;
    if p.x + 1 < size.x {
        gradient = max(gradient, length(motion_at(p + vec2<i32>(1, 0)) - here));
    }
    if p.y + 1 < size.y {
        gradient = max(gradient, length(motion_at(p + vec2<i32>(0, 1)) - here));
    }
    var magnitude = u32(clamp(gradient * 256.0, 0.0, 65535.0));
    if gradient < params.snap_threshold {
        magnitude = 0u;
    }
    return (magnitude << 16u) | place_code;
}

// One level up the argmax pyramid: the largest of four.
@fragment
fn fs_argmax_reduce(@builtin(position) position: vec4<f32>) -> @location(0) u32 {
    let base = vec2<i32>(position.xy) * 2;
    let limit = vec2<i32>(textureDimensions(argmax_source)) - 1;
    let a = textureLoad(argmax_source, min(base, limit), 0).x;
    let b = textureLoad(argmax_source, min(base + vec2<i32>(1, 0), limit), 0).x;
    let c = textureLoad(argmax_source, min(base + vec2<i32>(0, 1), limit), 0).x;
    let d = textureLoad(argmax_source, min(base + vec2<i32>(1, 1), limit), 0).x;
    return max(max(a, b), max(c, d));
}

// ---- 2. The low-pass pyramid ----

// One level down: the binomial [1 3 3 1]/8 in x and y, centred on the
// output texel (the paper's 3-tap binomial sits half a texel off when it
// decimates by two), as four bilinear taps.
@fragment
fn fs_blur_down(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let size = vec2<f32>(textureDimensions(blur_source));
    let base = floor(position.xy) * 2.0;
    let near = (base + vec2<f32>(0.25)) / size;
    let far = (base + vec2<f32>(1.75)) / size;
    let sum = textureSampleLevel(blur_source, linear_clamp, near, 0.0)
        + textureSampleLevel(blur_source, linear_clamp, vec2<f32>(far.x, near.y), 0.0)
        + textureSampleLevel(blur_source, linear_clamp, vec2<f32>(near.x, far.y), 0.0)
        + textureSampleLevel(blur_source, linear_clamp, far, 0.0);
    return sum * 0.25;
}

// The low-pass at `p` (full-resolution pixels): the pyramid level read
// with a cubic B-spline, as four bilinear taps (GPU Gems 2, ch. 20).
fn low_pass(p: vec2<f32>) -> vec4<f32> {
    let size = vec2<f32>(textureDimensions(low));
    let scale = size / params.viewport;
    let t = p * scale - 0.5;
    let i = floor(t);
    let f = t - i;
    let f2 = f * f;
    let f3 = f2 * f;
    let w0 = (1.0 - 3.0 * f + 3.0 * f2 - f3) / 6.0;
    let w1 = (4.0 - 6.0 * f2 + 3.0 * f3) / 6.0;
    let w2 = (1.0 + 3.0 * f + 3.0 * f2 - 3.0 * f3) / 6.0;
    let w3 = f3 / 6.0;
    let g0 = w0 + w1;
    let g1 = w2 + w3;
    let h0 = (i - 0.5 + w1 / g0) / size;
    let h1 = (i + 1.5 + w3 / g1) / size;
    return g0.y * (g0.x * textureSampleLevel(low, linear_clamp, h0, 0.0)
        + g1.x * textureSampleLevel(low, linear_clamp, vec2<f32>(h1.x, h0.y), 0.0))
        + g1.y * (g0.x * textureSampleLevel(low, linear_clamp, vec2<f32>(h0.x, h1.y), 0.0)
        + g1.x * textureSampleLevel(low, linear_clamp, h1, 0.0));
}

// Whether the blur applies at texel `p`: everywhere, or with the speed
// gate only where the motion is fast enough to be tracked and blurred.
fn blurs_at(p: vec2<i32>) -> bool {
    return !blur_gated_by_speed || speed_at(p) >= params.blur_min_speed;
}

// ---- 3. High-frequency compensation ----

// The displayed rendered frame O from its colour `i` and low-pass `l`
// (seed 004 §5.1): N·i^g = O^g + (N - 1)·l^g, so that the group of N
// frames integrates to i. Where i is darker than l the original is kept
// (black stays black). Where O^g leaves [0, 1] it is clamped, and the
// in-between frames take the rest (`in_between`).
fn compensated(i: vec3<f32>, l: vec3<f32>) -> vec3<f32> {
    if luminance(i) < luminance(l) {
        return i;
    }
    let g = params.gamma;
    let n = params.frames;
    let energy = n * pow(i, vec3<f32>(g)) - (n - 1.0) * pow(l, vec3<f32>(g));
    return pow(clamp(energy, vec3<f32>(0.0), vec3<f32>(1.0)), vec3<f32>(1.0 / g));
}

// An in-between frame from its warped colour `m` and warped low-pass `l`:
// the low-pass, plus the share of the rendered frame's energy it could not
// show (above 1 or below 0), split over the N - 1 in-between frames. The
// decision is made again on luminance here, as the paper says suffices.
fn in_between(m: vec3<f32>, l: vec3<f32>) -> vec3<f32> {
    if luminance(m) < luminance(l) {
        return m;
    }
    let g = params.gamma;
    let n = params.frames;
    let lg = pow(l, vec3<f32>(g));
    let energy = n * pow(m, vec3<f32>(g)) - (n - 1.0) * lg;
    let rest = energy - clamp(energy, vec3<f32>(0.0), vec3<f32>(1.0));
    let shown = clamp(lg + rest / (n - 1.0), vec3<f32>(0.0), vec3<f32>(1.0));
    return pow(shown, vec3<f32>(1.0 / g));
}

struct Compensated {
    // The rendered frame as displayed.
    @location(0) displayed: vec4<f32>,
    // The low-pass it was compensated against.
    @location(1) low: vec4<f32>,
}

@fragment
fn fs_compensate(@builtin(position) position: vec4<f32>) -> Compensated {
    let texel = vec2<i32>(position.xy);
    let c = textureLoad(color, texel, 0);
    let i = clamp(c.rgb, vec3<f32>(0.0), vec3<f32>(1.0));
    var l = i;
    if blurs_at(texel) {
        l = clamp(low_pass(position.xy).rgb, vec3<f32>(0.0), vec3<f32>(1.0));
    }
    return Compensated(vec4<f32>(compensated(i, l), c.a), vec4<f32>(l, c.a));
}

// ---- 4. The grid morph ----

struct Morphed {
    @builtin(position) position: vec4<f32>,
    // Where in the rendered frame this point comes from, in pixels.
    @location(0) @interpolate(linear) source: vec2<f32>,
}

// Grid vertex `v` in the rendered frame: on the regular grid, or snapped
// to the strongest motion discontinuity of its neighbourhood (the corner
// after the pixel whose forward difference it is). Border vertices stay.
fn grid_vertex(v: vec2<u32>) -> vec2<f32> {
    let regular = vec2<f32>(v * params.grid);
    let last = vec2<u32>(params.viewport) / params.grid;
    let border = v.x == 0u || v.y == 0u || v.x == last.x || v.y == last.y;
    if border || params.snap == 0u {
        return regular;
    }
    let packed = textureLoad(snap, v, 0).x;
    if (packed >> 16u) == 0u {
        return regular;
    }
    let place = vec2<f32>(f32(packed & 0xffu), f32((packed >> 8u) & 0xffu));
    return regular - f32(params.grid / 2u) + place + 1.0;
}

// Of the four pixels around the corner `corner`, the nearest surface's
// texel: a vertex on an occluding edge moves with the occluder.
fn nearest_around(corner: vec2<f32>) -> vec2<i32> {
    let c = vec2<i32>(corner);
    var best = texel_in_frame(c);
    var best_depth = textureLoad(depth, best, 0);
    for (var k = 1; k < 4; k += 1) {
        let p = texel_in_frame(c - vec2<i32>(k & 1, k >> 1u));
        let d = textureLoad(depth, p, 0);
        if abs(d - params.far_depth) > abs(best_depth - params.far_depth) {
            best = p;
            best_depth = d;
        }
    }
    return best;
}

// One vertex per grid point, (W/grid + 1) to a row, drawn through an index
// buffer of two triangles per tile (so each is shaded once): no vertex
// buffer.
@vertex
fn vs_morph(@builtin(vertex_index) index: u32) -> Morphed {
    let columns = u32(params.viewport.x) / params.grid + 1u;
    let v = vec2<u32>(index % columns, index / columns);
    let source = grid_vertex(v);
    let last = vec2<u32>(params.viewport) / params.grid;
    let border = v.x == 0u || v.y == 0u || v.x == last.x || v.y == last.y;
    let texel = nearest_around(source);
    let motion = motion_at(texel);
    var moved = source;
    if !border {
        moved += params.step * tracking(length(motion) * params.speed_scale) * motion;
    }
    let z = textureLoad(depth, texel, 0);
    // Nearer wins under LessEqual whichever way the depth runs.
    let ordered = select(1.0 - z, z, params.far_depth > 0.5);
    var out: Morphed;
    out.position = vec4<f32>(
        moved.x / params.viewport.x * 2.0 - 1.0,
        1.0 - moved.y / params.viewport.y * 2.0,
        ordered,
        1.0,
    );
    out.source = source;
    return out;
}

// How far the grid's mapping at this fragment is from a translation: the
// larger of |s - 1| over the singular values s of d(source)/d(screen).
fn distortion(dx: vec2<f32>, dy: vec2<f32>) -> f32 {
    let t = dot(dx, dx) + dot(dy, dy);
    let det = dx.x * dy.y - dx.y * dy.x;
    let root = sqrt(max(t * t - 4.0 * det * det, 0.0));
    let s1 = sqrt(max(0.5 * (t + root), 0.0));
    let s2 = sqrt(max(0.5 * (t - root), 0.0));
    return max(abs(s1 - 1.0), abs(s2 - 1.0));
}

@fragment
fn fs_morph(in: Morphed) -> @location(0) vec4<f32> {
    // Derivatives first, in uniform control flow.
    let d = distortion(dpdx(in.source), dpdy(in.source));
    let sharp = textureSampleLevel(color, linear_clamp, in.source / params.viewport, 0.0);
    if !blur {
        return sharp;
    }
    let m = clamp(sharp.rgb, vec3<f32>(0.0), vec3<f32>(1.0));
    // The low-pass warped by the same grid: one bilinear tap of it at full
    // resolution (smooth, so as good as the cubic read it was made with).
    let l = textureSampleLevel(low_full, linear_clamp, in.source / params.viewport, 0.0).rgb;
    let shown = in_between(m, l);
    return vec4<f32>(mix(shown, l, smoothstep(params.distortion_from, params.distortion_to, d)), sharp.a);
}

// ---- 5. The paper's order (`--blur-order paper`) ----
//
// Seed 004 blurs each morphed frame: R6 morphs the sharp rendered frame
// (`fs_warp_and_distortion`, the grid as above, writing the distortion
// too), R7 blurs the morphed frame with the pyramid passes of step 2,
// and R8 (`fs_assemble`) makes the in-between frame from the morphed
// frame and its own low-pass. Near a motion edge the low-pass then mixes
// both sides as they are in the in-between frame, not as they were in the
// rendered one; it costs the pyramid again per in-between frame.

// The distortion of the grid at each pixel of the morphed frame (x).
@group(0) @binding(10) var warp_distortion: texture_2d<f32>;

struct Warped {
    // M_k: the rendered frame morphed, sharp.
    @location(0) color: vec4<f32>,
    // D_k in x.
    @location(1) distortion: vec4<f32>,
}

@fragment
fn fs_warp_and_distortion(in: Morphed) -> Warped {
    let d = distortion(dpdx(in.source), dpdy(in.source));
    let sharp = textureSampleLevel(color, linear_clamp, in.source / params.viewport, 0.0);
    return Warped(sharp, vec4<f32>(d, 0.0, 0.0, 1.0));
}

// R8: `color` is bound to the morphed frame M_k and `low` to the last
// level of its own pyramid.
@fragment
fn fs_assemble(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let texel = vec2<i32>(position.xy);
    let sharp = textureLoad(color, texel, 0);
    let m = clamp(sharp.rgb, vec3<f32>(0.0), vec3<f32>(1.0));
    var l = m;
    // The speed gate reads the rendered frame's motion at the pixel: ours,
    // and only an approximation in the morphed frame.
    if blurs_at(texel) {
        l = clamp(low_pass(position.xy).rgb, vec3<f32>(0.0), vec3<f32>(1.0));
    }
    let d = textureLoad(warp_distortion, texel, 0).x;
    let shown = in_between(m, l);
    return vec4<f32>(mix(shown, l, smoothstep(params.distortion_from, params.distortion_to, d)), sharp.a);
}
