// Reverse-reprojection cache helpers (seed 002, §2–§3), imported at IR level
// into every module shadecache rewrites. The rewriter assigns the bind group
// of these resources (the first group the user's shader leaves free); the
// bindings below are fixed and the pass plan lists them.
//
// The cache of a frame is its payload texture plus the frame's depth
// buffer. Next frame, both are read here: the payload with a bilinear
// reconstruction from four texels, the depth to check that the surface
// point seen now is the one that was cached (no disocclusion).

struct CacheParams {
    // The viewport's size in pixels: the whole render target's, or the
    // part of it a camera draws into (split screen; its corner is
    // `viewport_origin`).
    viewport: vec2<f32>,
    // ε, relative: a tap agrees when |cached depth - expected depth| <
    // depth_epsilon * |expected depth - far_depth|, the expected depth
    // following the surface's slope (see `cache_depth_agrees`).
    depth_epsilon: f32,
    // (c mod Δn), advanced by the host each frame as (phase + 1) mod Δn;
    // it must be below Δn. Passing the phase rather than c keeps the refresh
    // period exact when the host's frame counter wraps, whatever Δn is.
    refresh_phase: u32,
    // Δn: each pixel is recomputed once every Δn frames; 0 turns refresh
    // off, and at most 65535 (see `cache_refresh`).
    refresh_period: u32,
    // k: refresh decisions are made per k×k block of pixels.
    refresh_quad: u32,
    // c, the frame counter (for debugging views; not used by the shaders).
    frame: u32,
    // The largest payload magnitude the cache format holds: 65504 for
    // rgba16float, the largest f32 for rgba32float.
    payload_limit: f32,
    // The depth buffer's value at the far plane (at infinity when the far
    // plane is infinite): 1 for standard depth, 0 for reversed Z.
    far_depth: f32,
    // The lowres variant's knobs (seed 001; the plan's `upsampling`): σn of
    // the normal weight, σz of the depth weight (relative to the depth, or
    // with CACHE_MODE_DEPTH_RANGE to `upsample_depth_range`), and
    // a, the history's sensitivity to the temporal gradient (eq. 8). Its
    // factor s is `refresh_quad`, and the sample's phase `refresh_phase`
    // (the host keeps it as frame mod s²).
    upsample_sigma_normal: f32,
    upsample_sigma_depth: f32,
    upsample_sensitivity: f32,
    // The camera's far − near (view-space distance), where σz is a share of
    // it (CACHE_MODE_DEPTH_RANGE, the paper's); 0 where the host was not
    // told the planes or the far plane is infinite: σz is then relative to
    // the depth.
    upsample_depth_range: f32,
    // The viewport's top-left corner in the render target, in pixels (0, 0
    // for the whole target), and the render target's size: the cache's
    // textures are the target's size, and a fragment's `@builtin(position)`
    // is in the target's pixels, so last frame's clip position maps into
    // the viewport's rectangle of them. Lowres takes the whole target only.
    viewport_origin: vec2<f32>,
    target_size: vec2<f32>,
}

@group(1) @binding(0) var<uniform> cache_params: CacheParams;
// Last frame's payload (rgba16float or rgba32float).
@group(1) @binding(1) var cache_previous_payload: texture_2d<f32>;
// Last frame's depth buffer.
@group(1) @binding(2) var cache_previous_depth: texture_depth_2d;
// This frame's payload, read at the pixel itself (three-pass, pass 3).
@group(1) @binding(3) var cache_current_payload: texture_2d<f32>;
// Linear filtering, clamped to the edge: one bilinear sample of an
// rgba16float payload, and one gather of the four depths around a point.
@group(1) @binding(4) var cache_sampler: sampler;
// Last frame's age of each cached value (r16float): how many frames ago
// it was computed, 0 where it was computed that frame (see `cache_age`).
@group(1) @binding(5) var cache_previous_age: texture_2d<f32>;

// The lowres variant's samples: this frame's payload at 1/s × 1/s of the
// pixels, in the cache's format.
@group(1) @binding(6) var cache_samples: texture_2d<f32>;
// Their geometry (rgba32float): the octahedral normal (x, y), the view
// depth (z), and the draw id and relative temporal gradient in one number
// (w = 4 id + gradient + 1, see `cache_sample_texel`).
@group(1) @binding(7) var cache_sample_geometry: texture_2d<f32>;
// Last frame's upsampling history (rgba32float, see `cache_upsample`).
@group(1) @binding(8) var cache_previous_history: texture_2d<f32>;
// The draw's id (x): its ordinal in the pass, bound per draw at a dynamic
// offset by the host. A material id, for the upsampling's weights.
@group(1) @binding(9) var<uniform> cache_draw: vec4<u32>;

struct CacheLookup {
    payload: vec4<f32>,
    hit: bool,
    // Why it missed: 0 hit, 1 off-screen (behind the previous camera or
    // outside the viewport), 2 disoccluded (depth disagrees), 3 the cached
    // payload read back is not finite.
    status: u32,
    // The age the payload read here has this frame if it is reused: one
    // more than the oldest of the texels it was read from (`cache_age`).
    age: f32,
}

// Whether every component is finite, by its exponent bits: WGSL lets
// compilers assume floats are never NaN or infinite, so `x != x` may be
// folded away, but integer tests on the bits may not.
fn cache_finite(v: vec4<f32>) -> bool {
    let exponent = bitcast<vec4<u32>>(v) & vec4<u32>(0x7f800000u);
    return all(exponent != vec4<u32>(0x7f800000u));
}

// A lookup whose reconstructed payload is not finite, or not below the
// format's limit, is a miss (status 3). So a NaN or an infinity the shader
// produced at one pixel is recomputed there every frame rather than reused,
// and never spreads to the neighbours whose bilinear footprint touches it:
// they miss and recompute too. Payloads beyond an rgba16float cache's range
// were written as NaN (`cache_encode`), so they are recomputed rather than
// reused wrong.
fn cache_checked(payload: vec4<f32>, status: u32, age: f32) -> CacheLookup {
    let valid = cache_finite(payload) & all(abs(payload) < vec4<f32>(cache_params.payload_limit));
    let checked = select(status, 3u, (status == 0u) & !valid);
    return CacheLookup(payload, checked == 0u, checked, age);
}

// Bounded staleness. The refresh indicator below is decided per block of
// the *screen*; a surface point that moves across blocks meets a new
// phase at every crossing, so under motion a value could be reused for
// far longer than Δn frames (simulated at 0.25–2 px a frame: 27–37% of
// reused values Δn or more frames old, the 99th percentile 103–148 frames
// at Δn = 32). So the cache keeps each value's age beside it, and a value
// is refreshed when its age reaches Δn, whatever the phase says: no
// surface point is ever shown from a value older than Δn − 1 frames. At
// rest the two rules fire on the same frames (the age counts up from the
// block's last phase refresh), so the random phase still spreads the
// refreshes over the period.
//
// A reused value's age is one more than the oldest texel it was read from
// (those with bilinear weight at least 0.001, as in the depth test): a
// blend is as stale as its stalest part. Ages are whole numbers in an
// r16float texture, exact up to 2048; refresh fires at min(Δn, 2048).
const CACHE_AGE_LIMIT: f32 = 2048.0;

// textureGather's weights of the four texels around a point at fraction f
// from the top-left one: (0, 1), (1, 1), (1, 0), (0, 0).
fn cache_bilinear_weights(f: vec2<f32>) -> vec4<f32> {
    return vec4<f32>((1.0 - f.x) * f.y, f.x * f.y, f.x * (1.0 - f.y), (1.0 - f.x) * (1.0 - f.y));
}

// The age of a value blended from the 2×2 texels from `base` with
// fractions `f`: one more than the oldest texel that weighs.
fn cache_age(base: vec2<f32>, f: vec2<f32>) -> f32 {
    let ages = textureGather(0, cache_previous_age, cache_sampler, (base + vec2<f32>(1.0)) / cache_params.target_size);
    let counted = select(vec4<f32>(0.0), ages, cache_bilinear_weights(f) >= vec4<f32>(0.001));
    return min(max(max(counted.x, counted.y), max(counted.z, counted.w)) + 1.0, CACHE_AGE_LIMIT);
}

// The age of the value read from one texel.
fn cache_age_at(texel: vec2<i32>) -> f32 {
    return min(textureLoad(cache_previous_age, texel, 0).x + 1.0, CACHE_AGE_LIMIT);
}

// What a pass writes to the age target beside the payload: the age the
// lookup gave where the value was reused, 0 where it was computed.
fn cache_age_written(lookup: CacheLookup, reused: bool) -> f32 {
    return select(0.0, lookup.age, reused);
}

// PCG hash (O'Neill 2014, "pcg32" output permutation on one u32 of state).
fn cache_hash(v: u32) -> u32 {
    let state = (v * 747796405u) + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// The refresh indicator of seed 002, eq. 1: b = (h(x/k, y/k) + c) mod Δn,
// refresh when b == 0. h is a hash of the k×k block rather than a noise
// texture: no extra binding, the same offsets on every machine, and every
// block's offset uniform in [0, Δn) up to the hash's quality.
//
// Integer division is slow on many GPUs and on CPU rasterisers (it is not
// vectorised), so none is used on the per-pixel path: the block index
// divides by k in f32, exact because a pixel centre x + 0.5 is never within
// rounding of a multiple of k; one hash of both block coordinates gives 16
// bits h, and h·Δn / 2^16 maps them onto [0, Δn) with a multiply and a
// shift (Lemire's range reduction: each offset gets ⌊2^16/Δn⌋ or
// ⌈2^16/Δn⌉ of the hash values, so Δn ≤ 65535 keeps h·Δn in a u32);
// (offset + c) mod Δn of two numbers below Δn is one conditional
// subtraction, so the host passes c already reduced mod Δn.
// The code is branch-free, as is the lookup below: selects instead of
// branches keep SIMD lanes together. Measured on lavapipe at 512×512, the
// branch-free code took the reprojection pass from 5.6 to 4.3 ms, and this
// hash and reduction (instead of two hashes, an f32 division and two
// corrections) from 4.5 to 4.2 ms, what it costs with refresh taken out.
//
// A value whose age (`CacheLookup.age`) has reached Δn is refreshed too.
fn cache_refresh(frag_coord: vec4<f32>, age: f32) -> bool {
    // Δn = 0 turns refresh off.
    let period = cache_params.refresh_period;
    let k = f32(max(cache_params.refresh_quad, 1u));
    let block = vec2<u32>(frag_coord.xy / k);
    let h = cache_hash(block.x ^ (block.y * 0x9e3779b9u)) >> 16u;
    let offset = (h * period) >> 16u;
    var b = offset + cache_params.refresh_phase;
    b = select(b, b - period, b >= period);
    let stale = age >= min(f32(period), CACHE_AGE_LIMIT);
    return (period != 0u) & ((b == 0u) | stale);
}

// The depth slope of the previous frame, per texel of last frame's cache:
// how the point's previous depth changes as its previous position moves
// one texel along x or y. Derivatives give the slope per pixel of *this*
// frame (`dpdx`, `dpdy` of the depth) and how the previous position moves
// per pixel of this frame (`dpdx`, `dpdy` of the texel position, the 2×2
// Jacobian J of the mapping from this frame's pixels to last frame's
// texels); the slope per previous texel is the first through J⁻¹. The tap
// offsets of a footprint are in previous texels, so only this slope is in
// the right space: under a zoom, a roll or a grazing view the mapping is
// far from the identity, and the per-pixel slope would extrapolate the
// taps' depths along the wrong axes by the wrong amount. Where J is
// singular or not finite (a surface seen edge-on last frame), the slope
// per pixel stands in. Derivatives are taken here, so this runs at the top
// of every pass, in uniform control flow.
fn cache_previous_slope(depth: f32, texel: vec2<f32>) -> vec2<f32> {
    let per_pixel = vec2<f32>(dpdx(depth), dpdy(depth));
    let along_x = dpdx(texel);
    let along_y = dpdy(texel);
    let det = (along_x.x * along_y.y) - (along_y.x * along_x.y);
    // per_pixel = per_texel · J, so per_texel = per_pixel · J⁻¹.
    let per_texel = vec2<f32>(
        (per_pixel.x * along_y.y) - (per_pixel.y * along_x.y),
        (per_pixel.y * along_x.x) - (per_pixel.x * along_y.x),
    ) / det;
    // Comparisons with NaN are false: a NaN slope falls back too.
    let usable = (abs(det) > 1e-6) & all(abs(per_texel) < vec2<f32>(1e30));
    return select(per_pixel, per_texel, usable);
}

// The depth a cached texel should hold if it shows the same surface as
// the point: the point's previous depth, carried along the surface's depth
// slope per previous texel (`cache_previous_slope`) by the texel's offset
// from the point, in texels. On a sloped surface the texels of the
// footprint legitimately differ from the point's own depth by up to a
// texel's worth of slope; extrapolating along the surface's plane accounts
// for that, while a texel across a silhouette lies far off the plane and
// still misses.
fn cache_expected_depth(depth: f32, slope: vec2<f32>, offset_x: vec4<f32>, offset_y: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(depth) + (offset_x * slope.x) + (offset_y * slope.y);
}

// Whether cached depths agree with the expected ones, tested relative to
// the far plane's depth. In a perspective projection a point's depth lies
// n/z (infinite far plane) or n(f - z)/((f - n)z) (far plane f) from the
// far plane's, for standard and reversed Z alike, so
// |d - e| < ε·|e - far_depth| bounds the relative difference in distance,
// |Δz|/z < ε (tighter by (f - z)/f towards a finite far plane): two
// surfaces 10% apart are told apart at 1 unit as at 1000. An absolute ε is
// not: with reversed Z and an infinite far plane, depth is n/z, and the
// surfaces at 100 and 110 units (n = 0.1) differ by 0.00009; with standard
// Z, depth crowds towards 1 the same way. A depth at the far plane itself
// (the cleared "no previous frame") never agrees, as ε < 1.
fn cache_depth_agrees(taps: vec4<f32>, expected: vec4<f32>) -> vec4<bool> {
    let tolerance = cache_params.depth_epsilon * abs(expected - vec4<f32>(cache_params.far_depth));
    return abs(taps - expected) < tolerance;
}

// Where a fragment was last frame: its depth then, its position in texel
// units (texel centres at whole numbers), and whether it was on screen.
struct CachePoint {
    depth: f32,
    texel: vec2<f32>,
    inside: bool,
}

// Off-screen when the point was behind the previous camera (w ≤ 0, or NaN)
// or outside the viewport's texel centres by more than a thousandth of a
// texel (a bilinear footprint there has weight only inside).
fn cache_point(previous_clip: vec4<f32>) -> CachePoint {
    let ndc = previous_clip.xyz / previous_clip.w;
    let texel = ((vec2<f32>((ndc.x * 0.5) + 0.5, 0.5 - (ndc.y * 0.5)) * cache_params.viewport) + cache_params.viewport_origin) - vec2<f32>(0.5);
    let slack = vec2<f32>(0.001);
    // Comparisons with NaN are false, so a NaN position is off-screen too.
    let inside = (previous_clip.w > 0.0)
        & all(texel >= (cache_params.viewport_origin - slack))
        & all(texel <= ((cache_params.viewport_origin + cache_params.viewport - vec2<f32>(1.0)) + slack));
    return CachePoint(ndc.z, texel, inside);
}

// Where a fragment was last frame, in the cache.
struct CacheFootprint {
    // 0 the point was visible, 1 off-screen, 2 disoccluded.
    status: u32,
    // The top-left texel of the 2×2 bilinear footprint, and the weights.
    base: vec2<f32>,
    weights: vec2<f32>,
}

// Its previous clip position (from the vertex stage evaluated with last
// frame's uniforms) → NDC → texel coordinates in the cache. Off-screen when
// the point was behind the previous camera (w ≤ 0, or NaN) or outside the
// viewport's texel centres; disoccluded when a texel of the 2×2 bilinear
// footprint (one gather from last frame's depth buffer) disagrees with the
// point's previous depth (`cache_depth_agrees`). Texels whose bilinear weight is
// below 0.001 do not count: without that, a point that reprojects exactly
// onto a texel centre next to a silhouette (a static scene) would miss
// because of a neighbour it does not read; with it, a footprint that
// really straddles a silhouette still misses.
fn cache_footprint(previous_clip: vec4<f32>) -> CacheFootprint {
    let point = cache_point(previous_clip);
    let texel = point.texel;
    let base = floor(texel);
    let f = texel - base;
    // textureGather's order: (0, 1), (1, 1), (1, 0), (0, 0) from `base`.
    let weights = cache_bilinear_weights(f);
    let depths = textureGather(cache_previous_depth, cache_sampler, (base + vec2<f32>(1.0)) / cache_params.target_size);
    let expected = cache_expected_depth(
        point.depth,
        cache_previous_slope(point.depth, texel),
        vec4<f32>(-f.x, 1.0 - f.x, 1.0 - f.x, -f.x),
        vec4<f32>(1.0 - f.y, 1.0 - f.y, -f.y, -f.y),
    );
    let agree = all(cache_depth_agrees(depths, expected) | (weights < vec4<f32>(0.001)));
    let status = select(1u, select(2u, 0u, agree), point.inside);
    return CacheFootprint(status, base, f);
}

// The cached payload where this fragment was last frame, with one bilinear
// sample (for the filterable rgba16float cache). The payload is meaningful
// only on a hit; it is read either way, to keep the code branch-free.
fn cache_lookup(previous_clip: vec4<f32>) -> CacheLookup {
    let footprint = cache_footprint(previous_clip);
    let at = (footprint.base + vec2<f32>(0.5) + footprint.weights) / cache_params.target_size;
    let payload = textureSampleLevel(cache_previous_payload, cache_sampler, at, 0.0);
    return cache_checked(payload, footprint.status, cache_age(footprint.base, footprint.weights));
}

// Lowres's history where this fragment was last frame: `cache_lookup`
// without the age (lowres keeps none), one gather and one sample.
fn cache_history(previous_clip: vec4<f32>) -> CacheLookup {
    let footprint = cache_footprint(previous_clip);
    let at = (footprint.base + vec2<f32>(0.5) + footprint.weights) / cache_params.target_size;
    let payload = textureSampleLevel(cache_previous_payload, cache_sampler, at, 0.0);
    return cache_checked(payload, footprint.status, 0.0);
}

// The same with four loads, for an rgba32float cache.
fn cache_history_loads(previous_clip: vec4<f32>) -> CacheLookup {
    let footprint = cache_footprint(previous_clip);
    return cache_checked(cache_bilinear_loads(footprint.base, footprint.weights), footprint.status, 0.0);
}

// The same with four loads, for the rgba32float cache, which cannot be
// filtered.
fn cache_lookup_loads(previous_clip: vec4<f32>) -> CacheLookup {
    let footprint = cache_footprint(previous_clip);
    let payload = cache_bilinear_loads(footprint.base, footprint.weights);
    return cache_checked(payload, footprint.status, cache_age(footprint.base, footprint.weights));
}

// Bilinear interpolation of last frame's payload between the texel `base`
// and its right, lower and lower-right neighbours, with weights `f`, by
// four loads. Taps just outside the viewport (weight below 0.001) read the
// edge; a NaN position is clamped to some texel and is a miss anyway.
fn cache_bilinear_loads(base: vec2<f32>, f: vec2<f32>) -> vec4<f32> {
    let first = vec2<i32>(cache_params.viewport_origin);
    let last = vec2<i32>(cache_params.viewport_origin + cache_params.viewport) - vec2<i32>(1);
    let t0 = clamp(vec2<i32>(base), first, last);
    let t1 = clamp(vec2<i32>(base) + vec2<i32>(1), first, last);
    let top = mix(
        textureLoad(cache_previous_payload, t0, 0),
        textureLoad(cache_previous_payload, vec2<i32>(t1.x, t0.y), 0),
        f.x,
    );
    let bottom = mix(
        textureLoad(cache_previous_payload, vec2<i32>(t0.x, t1.y), 0),
        textureLoad(cache_previous_payload, t1, 0),
        f.x,
    );
    return mix(top, bottom, f.y);
}

// Nearest reconstruction: the texel the point falls in, tested on its own
// depth. Two loads instead of a gather and a filtered sample: cheaper,
// blockier under motion, and it never blends across a silhouette.
fn cache_lookup_nearest(previous_clip: vec4<f32>) -> CacheLookup {
    let texel = cache_nearest(previous_clip);
    let agree = cache_depth_agrees(vec4<f32>(textureLoad(cache_previous_depth, texel.at, 0)), vec4<f32>(texel.expected)).x;
    let status = select(1u, select(2u, 0u, agree), texel.inside);
    return cache_checked(textureLoad(cache_previous_payload, texel.at, 0), status, cache_age_at(texel.at));
}

// The texel a point falls in, whether the point was on screen, and the
// depth the texel should hold (the point's, carried to the texel's centre
// along the surface's slope).
struct CacheNearest {
    at: vec2<i32>,
    inside: bool,
    expected: f32,
}

fn cache_nearest(previous_clip: vec4<f32>) -> CacheNearest {
    let ndc = previous_clip.xyz / previous_clip.w;
    let origin = cache_params.viewport_origin;
    let position = (vec2<f32>((ndc.x * 0.5) + 0.5, 0.5 - (ndc.y * 0.5)) * cache_params.viewport) + origin;
    // Comparisons with NaN are false, so a NaN position is off-screen.
    let inside = (previous_clip.w > 0.0) & all(position >= origin) & all(position < (origin + cache_params.viewport));
    let t = clamp(vec2<i32>(floor(position)), vec2<i32>(origin), vec2<i32>(origin + cache_params.viewport) - vec2<i32>(1));
    let offset = (vec2<f32>(t) + vec2<f32>(0.5)) - position;
    let slope = cache_previous_slope(ndc.z, position);
    let expected = cache_expected_depth(ndc.z, slope, vec4<f32>(offset.x), vec4<f32>(offset.y));
    return CacheNearest(t, inside, expected.x);
}

// Packed reconstructions (`bilinear-packed`, `nearest-packed`) keep the
// depth in the payload texture's fourth channel, which a payload of up to
// three components leaves free, as seed 002 §2.1 describes: "efficient
// hardware support for bilinear texture filtering to reconstruct the cache
// payload and depth". One read then gives both: no gather of the depth
// buffer (on lavapipe at 512², the gather is about 0.5 of the reprojection
// pass's 4.2 ms). The channel holds the depth measured from the far
// plane's, d − far_depth, small and signed: f16 keeps 11 bits of it at any
// distance, ample for the relative test (ε = 0.02 of the same quantity),
// and a cleared texel (0) reads as the far plane, so it never agrees.
//
// The bilinear test differs from the separate one: it compares the
// filtered depth at the point with the point's depth (a plane's depth
// interpolates exactly, so no slope correction is needed) rather than
// every tap with the slope-corrected depth. A footprint straddling a
// silhouette still misses unless the far side's weight w is below
// ε·|e − far|/|Δd|: at most that share of the other surface's payload
// blends in (the more conservative hit/miss tests near depth boundaries
// that seed 002 §2 cites from Nehab et al. 2007 for filtered depth).
fn cache_pack(cache: vec4<f32>, frag_coord: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(cache.xyz, frag_coord.z - cache_params.far_depth);
}

// The packed payload and depth agree with the point's depth, and are valid.
fn cache_packed_checked(texel: vec4<f32>, expected: f32, inside: bool, age: f32) -> CacheLookup {
    let agree = cache_depth_agrees(vec4<f32>(texel.w + cache_params.far_depth), vec4<f32>(expected)).x;
    let status = select(1u, select(2u, 0u, agree), inside);
    return cache_checked(vec4<f32>(texel.xyz, 0.0), status, age);
}

// `bilinear-packed` with an rgba16float cache: one filtered sample.
fn cache_lookup_packed(previous_clip: vec4<f32>) -> CacheLookup {
    let point = cache_point(previous_clip);
    let at = (point.texel + vec2<f32>(0.5)) / cache_params.target_size;
    let texel = textureSampleLevel(cache_previous_payload, cache_sampler, at, 0.0);
    let base = floor(point.texel);
    let age = cache_age(base, point.texel - base);
    return cache_packed_checked(texel, point.depth, point.inside, age);
}

// `bilinear-packed` with an rgba32float cache, which cannot be filtered:
// four loads.
fn cache_lookup_loads_packed(previous_clip: vec4<f32>) -> CacheLookup {
    let point = cache_point(previous_clip);
    let base = floor(point.texel);
    let texel = cache_bilinear_loads(base, point.texel - base);
    let age = cache_age(base, point.texel - base);
    return cache_packed_checked(texel, point.depth, point.inside, age);
}

// `nearest-packed`: one load.
fn cache_lookup_nearest_packed(previous_clip: vec4<f32>) -> CacheLookup {
    let nearest = cache_nearest(previous_clip);
    let texel = textureLoad(cache_previous_payload, nearest.at, 0);
    return cache_packed_checked(texel, nearest.expected, nearest.inside, cache_age_at(nearest.at));
}

// A payload on its way into the cache. Finite components at or beyond the
// format's limit become NaN: left alone, an rgba16float target may store
// them as its largest finite value (lavapipe does), which a bilinear read
// would blend into plausible wrong values; a NaN spreads through the
// filter instead, so every footprint touching it reads as invalid and
// misses (see `cache_checked`). Infinities and NaNs the shader produced
// are kept as they are: three-pass shades from this texel in the same
// frame and must see the shader's own value. The NaN is made at run time
// from the uniform, since a NaN constant is not valid WGSL.
fn cache_encode(payload: vec4<f32>) -> vec4<f32> {
    let nan = bitcast<f32>(0x7fc00000u | (cache_params.frame & 0u));
    let finite = (bitcast<vec4<u32>>(payload) & vec4<u32>(0x7f800000u)) != vec4<u32>(0x7f800000u);
    let beyond = abs(payload) >= vec4<f32>(cache_params.payload_limit);
    return select(payload, vec4<f32>(nan), finite & beyond);
}

// This frame's cache at the fragment's own pixel (three-pass, pass 3).
fn cache_current(frag_coord: vec4<f32>) -> vec4<f32> {
    return textureLoad(cache_current_payload, vec2<i32>(frag_coord.xy), 0);
}

// The payload of a pixel where the cached node is not computed: the node
// sits under a branch this pixel does not take (or a uniform branch the
// draw does not take). It is NaN, so that next frame's lookup there misses
// (`cache_checked`) instead of reusing a value that never existed; the
// shading never reads it, since it reads the node only where the original
// computes it. Made at run time, like `cache_encode`'s NaN.
fn cache_absent() -> vec4<f32> {
    return vec4<f32>(bitcast<f32>(0x7fc00000u | (cache_params.frame & 0u)));
}

// The class colour of a pixel where the node is not computed (grey): not
// counted as a hit, a miss or a refresh.
fn cache_classify_absent(present: bool, classes: vec4<f32>) -> vec4<f32> {
    return select(vec4<f32>(0.5, 0.5, 0.5, 1.0), classes, present);
}

// What the cache does at this pixel, as a colour for the profiler's maps,
// from the status of the variant's own lookup: reused (green), refreshed
// (blue), missed because the point was off-screen last frame (orange),
// disoccluded (red), or because the cached payload is not finite (magenta).
fn cache_classify(status: u32, frag_coord: vec4<f32>, age: f32) -> vec4<f32> {
    if (status == 3u) {
        return vec4<f32>(1.0, 0.0, 1.0, 1.0);
    }
    if (status == 1u) {
        return vec4<f32>(1.0, 0.5, 0.0, 1.0);
    }
    if (status == 2u) {
        return vec4<f32>(1.0, 0.0, 0.0, 1.0);
    }
    if (cache_refresh(frag_coord, age)) {
        return vec4<f32>(0.0, 0.0, 1.0, 1.0);
    }
    return vec4<f32>(0.0, 1.0, 0.0, 1.0);
}

// ---------------------------------------------------------------------------
// The lowres variant: spatio-temporal upsampling (seed 001, Herzog et al.
// 2010). Each frame the payload is shaded at one pixel of every s×s window
// (pass 1, at 1/s × 1/s of the pixels, the geometry jittered so each
// sample lands on a full-resolution pixel centre), and pass 2 rebuilds it
// at every pixel from the four nearest samples and last frame's result.

// The offset (x, y) within every s×s window that this frame samples: the
// phase p = frame mod s² (`refresh_phase`) read through a Bayer order,
// M(x, y) = reverse(interleave(x ^ y, y)) on 2·log2(s) bits, so that
// consecutive frames sample far apart and s² frames sample every offset
// once (for s = 4 the matrix [[0,8,2,10],[12,4,14,6],[3,11,1,9],[15,7,13,5]]).
// Here M is inverted: p's bits reversed, de-interleaved into a = x ^ y and
// b = y. s must be a power of two (2 or 4).
fn cache_sample_offset() -> vec2<u32> {
    let s = max(cache_params.refresh_quad, 1u);
    let bits = countTrailingZeros(s);
    let reversed = select(reverseBits(cache_params.refresh_phase) >> (32u - (2u * bits)), 0u, bits == 0u);
    var a = 0u;
    var b = 0u;
    for (var i = 0u; i < bits; i = i + 1u) {
        a = a | (((reversed >> (2u * i)) & 1u) << i);
        b = b | (((reversed >> ((2u * i) + 1u)) & 1u) << i);
    }
    return vec2<u32>(a ^ b, b);
}

// The samples' target size: ceil(W/s) × ceil(H/s).
fn cache_sample_size() -> vec2<f32> {
    return ceil(cache_params.viewport / f32(max(cache_params.refresh_quad, 1u)));
}

// The clip position of pass 1's vertex stage: the frame's projection moved
// (and, where s does not divide the size, scaled) so that the centre of
// low-resolution pixel a sees the point at full-resolution pixel centre
// s·a + offset + 0.5. In normalised coordinates u_low = (u − c) / m with
// m = s·w / W and c = (offset + 0.5 − s/2) / W, on x and on y (which runs
// down the framebuffer, up in NDC); with s dividing the size this is the
// translation x += (s − 2·offset − 1) / W · w_clip of the paper's jittered
// projection.
fn cache_jitter(position: vec4<f32>) -> vec4<f32> {
    let s = f32(max(cache_params.refresh_quad, 1u));
    let offset = vec2<f32>(cache_sample_offset());
    let m = (s * cache_sample_size()) / cache_params.viewport;
    let c = ((offset + vec2<f32>(0.5)) - vec2<f32>(0.5 * s)) / cache_params.viewport;
    let w = position.w;
    let x = (((position.x + w) - (2.0 * c.x * w)) / m.x) - w;
    let y = w - (((w - position.y) - (2.0 * c.y * w)) / m.y);
    return vec4<f32>(x, y, position.z, w);
}

// The deferred lowres's samples pass runs in screen space at 1/s × 1/s:
// low-resolution pixel a shades the full-resolution pixel s·a + offset,
// whose centre this is (clamped to the frame where s does not divide its
// size), read from the G-buffer.
fn cache_lattice_pixel(low: vec4<f32>) -> vec2<f32> {
    let s = f32(max(cache_params.refresh_quad, 1u));
    let pixel = (floor(low.xy) * s) + vec2<f32>(cache_sample_offset());
    return min(pixel, cache_params.viewport - vec2<f32>(1.0)) + vec2<f32>(0.5);
}

// The draw's id: its ordinal (`cache_draw`), which the deferred lowres's
// G-buffer keeps at each pixel (its samples pass, at another size than
// the stencil, tells the draws apart by it), and which lowres's samples
// and history keep beside a gradient (`cache_with_id`).
fn cache_draw_id() -> u32 {
    return cache_draw.x & 511u;
}

// A gradient in [−1, 1] and this draw's id in one number, w = 4·id +
// gradient + 1 (exact to 2^-14 for ids below 2^9), and the two read back.
fn cache_with_id(gradient: f32) -> f32 {
    return ((4.0 * f32(cache_draw_id())) + gradient) + 1.0;
}

fn cache_id_of(w: f32) -> u32 {
    return u32(max(floor(w * 0.25), 0.0));
}

fn cache_gradient_of(w: f32) -> f32 {
    return (w - (4.0 * f32(cache_id_of(w)))) - 1.0;
}

// A unit normal folded onto the octahedron, two numbers.
fn cache_octahedral(n: vec3<f32>) -> vec2<f32> {
    let p = n.xy / max(abs(n.x) + abs(n.y) + abs(n.z), 1e-20);
    let folded = (vec2<f32>(1.0) - abs(p.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), p >= vec2<f32>(0.0));
    return select(folded, p, n.z >= 0.0);
}

fn cache_from_octahedral(e: vec2<f32>) -> vec3<f32> {
    let z = 1.0 - abs(e.x) - abs(e.y);
    let t = max(-z, 0.0);
    let xy = e + select(vec2<f32>(t), vec2<f32>(-t), e >= vec2<f32>(0.0));
    return normalize(vec3<f32>(xy, z));
}

// The fragment's unit normal from a normal the shader interpolates;
// (0, 0, 1) where it is zero or not finite.
fn cache_unit_normal(n: vec3<f32>) -> vec3<f32> {
    let l = length(n);
    let ok = (l > 1e-20) & cache_finite(vec4<f32>(n, 0.0));
    return select(vec3<f32>(0.0, 0.0, 1.0), n / max(l, 1e-20), ok);
}

// The geometric normal where the shader has none: the cross product of
// the screen derivatives of a point (ndc.x·z, ndc.y·z, z), z the view depth.
// Only compared with other normals made the same way, so its space does
// not matter; `low` says whether the pass renders the samples. Takes
// derivatives: call it at the top of the entry point.
fn cache_geometric_normal(frag_coord: vec4<f32>, low: bool) -> vec3<f32> {
    let size = select(cache_params.viewport, cache_sample_size(), low);
    let z = 1.0 / frag_coord.w;
    let ndc = ((frag_coord.xy / size) * 2.0) - vec2<f32>(1.0);
    let p = vec3<f32>(ndc * z, z);
    return cache_unit_normal(cross(dpdx(p), dpdy(p)));
}

// The scalar the temporal gradient is taken of: the luminance of a colour
// (three or four components), the mean of two, the value of one.
fn cache_gradient_scalar(v: vec4<f32>, components: u32) -> f32 {
    if (components >= 3u) {
        return dot(v.xyz, vec3<f32>(0.2126, 0.7152, 0.0722));
    }
    return select(v.x, 0.5 * (v.x + v.y), components == 2u);
}

// The relative temporal gradient (§3.5.1): (now − before) / max(|now|,
// |before|), clamped to [−1, 1], guarded where both are 0; 1, its largest,
// where there is no before (disoccluded, off-screen, not finite).
fn cache_relative_gradient(now: vec4<f32>, before: vec4<f32>, hit: bool, components: u32) -> f32 {
    let a = cache_gradient_scalar(now, components);
    let b = cache_gradient_scalar(before, components);
    let g = clamp((a - b) / max(max(abs(a), abs(b)), 1e-6), -1.0, 1.0);
    return select(1.0, g, hit & cache_finite(vec4<f32>(a, b, 0.0, 0.0)));
}

// Pass 1's geometry texel of a sample: its normal, view depth, and its
// temporal gradient against the history where the sample's point was last
// frame (`before`, a lookup of the previous payload) with the draw's id
// (`cache_with_id`).
fn cache_sample_texel(payload: vec4<f32>, normal: vec3<f32>, frag_coord: vec4<f32>, before: vec4<f32>, hit: bool, components: u32) -> vec4<f32> {
    let gradient = cache_relative_gradient(payload, before, hit, components);
    return vec4<f32>(cache_octahedral(normal), 1.0 / frag_coord.w, cache_with_id(gradient));
}

// The tri-weight kernel of eq. 3, g(x, σ, γ) = max(ε, 1 − x/σ)^γ, with
// ε = 0.01: every product of three stays above f32's smallest normal.
fn cache_kernel(x: f32, sigma: f32, gamma: f32) -> f32 {
    return pow(max(0.01, 1.0 - (x / sigma)), gamma);
}

// The weight of another draw's sample (a material edge): tiny, not zero, so
// that a pixel with only foreign samples still gets a plausible value.
const CACHE_FOREIGN_WEIGHT: f32 = 1e-6;

// The largest accumulated history weight hw: a static pixel's hw grows by
// about one a frame (§A.6.4 of our notes); clamped so that it stays exact
// in f32 and a change after a long rest is taken within frames.
const CACHE_HISTORY_WEIGHT_LIMIT: f32 = 8.0;

// The history's exactness mark, added to hw: the pixel's history is its
// own shaded sample, kept since through hits that landed on texel centres.
const CACHE_EXACT: f32 = 1024.0;

// The spatial weight sum below which no sample shows the pixel's surface:
// a sample of another draw weighs at most CACHE_FOREIGN_WEIGHT (four of
// them 4e-6), and one of this surface, its normal and depth within σn and
// σz, its linear hat (at least 0.01 within the four nearest).
const CACHE_RELIABLE: f32 = 1e-5;

// The relative gradient of this frame's samples from which the history is
// dropped rather than blended.
const CACHE_CHANGED: f32 = 0.5;

// The filtered relative gradient below which a pixel counts as unchanged:
// its exact history is kept as it is (a 5% change of luminance is not).
const CACHE_STILL: f32 = 0.05;

// Lowres's classes: a pixel on this frame's lattice (shaded this frame,
// blue), else what the history lookup found: reused (green), off-screen
// (orange), disoccluded (red), not finite (magenta).
fn cache_classify_lowres(status: u32, frag_coord: vec4<f32>, age: f32) -> vec4<f32> {
    let s = max(cache_params.refresh_quad, 1u);
    let offset = cache_sample_offset();
    let pixel = vec2<u32>(frag_coord.xy);
    let sampled = all((pixel % vec2<u32>(s)) == offset);
    var classes = array<vec4<f32>, 4>(
        vec4<f32>(0.0, 1.0, 0.0, 1.0),
        vec4<f32>(1.0, 0.5, 0.0, 1.0),
        vec4<f32>(1.0, 0.0, 0.0, 1.0),
        vec4<f32>(1.0, 0.0, 1.0, 1.0),
    );
    let found = classes[min(status, 3u)] + vec4<f32>(0.0 * age);
    return select(found, vec4<f32>(0.0, 0.0, 1.0, 1.0), sampled & (status != 3u));
}

// Adaptive refresh of the cache variants (ours, after seed 001's temporal
// gradient): the age a value computed now starts from. Where it differs
// from what the cache held for the same surface point (a hit) by a
// relative CACHE_ADAPTIVE_CHANGE or more in a component, it starts at three
// quarters of Δn, so the age rule (`cache_refresh`) refreshes it again Δn/4
// frames on; elsewhere at 0, a whole Δn. Values that change are refreshed
// four times as often, still ones as before.
const CACHE_ADAPTIVE_CHANGE: f32 = 0.1;

fn cache_adaptive_age(lookup: CacheLookup, payload: vec4<f32>) -> f32 {
    let largest = max(max(abs(payload), abs(lookup.payload)), vec4<f32>(1e-6));
    let changed = lookup.hit & any((abs(payload - lookup.payload) / largest) >= vec4<f32>(CACHE_ADAPTIVE_CHANGE));
    let period = min(f32(cache_params.refresh_period), CACHE_AGE_LIMIT);
    return select(0.0, floor(0.75 * period), changed);
}

// The history of a pixel shaded at full resolution (adaptive refresh's
// third pass): exact, of weight 1, unchanged.
fn cache_exact_history() -> vec4<f32> {
    return cache_history_texel(CACHE_EXACT + 1.0, vec3<f32>(0.0));
}

// A texel of the history: hw (+ CACHE_EXACT when exact), and the three
// latest gradients, newest first, the oldest with the draw's id
// (`cache_with_id`), so that the next frame can tell which draw the point
// showed (CACHE_MODE_MATERIAL_IDS; 0 where none wrote it).
fn cache_history_texel(weight: f32, gradients: vec3<f32>) -> vec4<f32> {
    return vec4<f32>(weight, gradients.x, gradients.y, cache_with_id(gradients.z));
}

// Whether every texel of the history's bilinear footprint around `texel`
// (in texels, integers at their centres) showed this draw last frame:
// with material ids, a lookup that reads another draw's texel misses.
fn cache_history_same_draw(texel: vec2<f32>) -> bool {
    let base = vec2<i32>(floor(texel));
    let last = vec2<i32>(cache_params.viewport) - vec2<i32>(1);
    var same = true;
    for (var i = 0; i < 4; i = i + 1) {
        let at = clamp(base + vec2<i32>(i & 1, i >> 1u), vec2<i32>(0), last);
        same = same & (cache_id_of(textureLoad(cache_previous_history, at, 0).w) == cache_draw_id());
    }
    return same;
}

// The three gradients a history texel keeps, newest first.
fn cache_history_gradients(history: vec4<f32>) -> vec3<f32> {
    return vec3<f32>(history.y, history.z, cache_gradient_of(history.w));
}

struct CacheUpsampled {
    // The payload at this pixel.
    payload: vec4<f32>,
    // What the history target keeps of it: hw (+ CACHE_EXACT when exact),
    // and the three latest gradients, newest first.
    history: vec4<f32>,
    // Whether the upsampling cannot vouch for the pixel (the paper's Fig. 5
    // "red"): no temporal weight (disoccluded, off-screen or changed), no
    // own sample, and undersampled (its samples' spatial weight below
    // CACHE_UNDERSAMPLED). With adaptive refresh a third pass shades it.
    unreliable: bool,
}

// The spatial weight sum below which a pixel counts as undersampled: four
// samples of its surface weigh 1 to 4 by their hats; a silhouette's or a
// thin feature's fewer.
const CACHE_UNDERSAMPLED: f32 = 0.5;

// The four nearest samples of a pixel (the lattice points around it,
// clamped to the image): their payloads, their geometric weight (eq. 2's
// normal and depth terms, and the draw's: a sample of another draw weighs
// CACHE_FOREIGN_WEIGHT, an extension of ours for material edges), their
// distance to the pixel in pixels, and their temporal gradients. Read once
// per pixel; the image-space kernels are applied by `cache_blend`.
struct CacheNeighbours {
    payload: array<vec4<f32>, 4>,
    geometry: vec4<f32>,
    distance: vec4<f32>,
    gradient: vec4<f32>,
    // 1 where a sample shows geometry (any draw), 0 on the background.
    present: vec4<f32>,
    // The index of the sample at the pixel itself, 4 where none is (the
    // pixel is not on this frame's lattice), and of the nearest.
    own: u32,
    nearest: u32,
}

fn cache_neighbours(frag_coord: vec4<f32>, normal: vec3<f32>, flags: u32) -> CacheNeighbours {
    let s = f32(max(cache_params.refresh_quad, 1u));
    let offset = vec2<f32>(cache_sample_offset());
    let last = vec2<i32>(cache_sample_size()) - vec2<i32>(1);
    let pixel = floor(frag_coord.xy);
    let z = 1.0 / frag_coord.w;
    let id = cache_draw_id();
    let base = vec2<i32>(floor((pixel - offset) / s));
    let sigma_n = cache_params.upsample_sigma_normal * cache_params.upsample_sigma_normal;
    let sigma_z = cache_params.upsample_sigma_depth * cache_params.upsample_sigma_depth;
    let range = cache_params.upsample_depth_range;
    let of_range = ((flags & CACHE_MODE_DEPTH_RANGE) != 0u) & (range > 0.0);
    var out: CacheNeighbours;
    out.own = 4u;
    out.nearest = 0u;
    for (var i = 0; i < 4; i = i + 1) {
        let a = clamp(base + vec2<i32>(i & 1, i >> 1u), vec2<i32>(0), last);
        let l = textureLoad(cache_samples, a, 0);
        let g = textureLoad(cache_sample_geometry, a, 0);
        let nj = cache_from_octahedral(g.xy);
        let idj = cache_id_of(g.w);
        let bend = max(0.0, 1.0 - dot(normal, nj));
        let dz = (z - g.z) / select(max(z, 1e-20), range, of_range);
        let n_w = max(0.01, 1.0 - ((bend * bend) / sigma_n));
        let d_w = max(0.01, 1.0 - ((dz * dz) / sigma_z));
        let finite = cache_finite(l);
        out.payload[i] = select(vec4<f32>(0.0), l, finite);
        out.geometry[i] = select(0.0, (n_w * n_w * n_w) * (d_w * d_w * d_w) * select(CACHE_FOREIGN_WEIGHT, 1.0, idj == id), finite);
        out.distance[i] = length(((vec2<f32>(a) * s) + offset) - pixel);
        out.gradient[i] = cache_gradient_of(g.w);
        out.present[i] = select(0.0, 1.0, g.z > 0.0);
        // The pixel's own sample, when it shows the same surface (at a
        // silhouette the samples pass may see what is behind).
        out.own = select(out.own, u32(i), (out.distance[i] < 0.5) & (out.geometry[i] > 0.5));
        out.nearest = select(out.nearest, u32(i), out.distance[i] < out.distance[out.nearest]);
    }
    return out;
}

// The samples blended with weights `w`: the payload and the weight sum.
struct CacheBlend {
    payload: vec4<f32>,
    weight: f32,
}

fn cache_blend(n: CacheNeighbours, w: vec4<f32>) -> CacheBlend {
    let sum = (w.x * n.payload[0]) + (w.y * n.payload[1]) + (w.z * n.payload[2]) + (w.w * n.payload[3]);
    let total = (w.x + w.y) + (w.z + w.w);
    return CacheBlend(sum / max(total, 1e-30), total);
}

// Eq. 3's image-space kernel at each sample's distance, max(ε, 1 − d/r)^γ
// with r the low-resolution pixel's diagonal (s·√2) and ε = 0.01.
fn cache_image_kernel(n: CacheNeighbours, gamma: f32) -> vec4<f32> {
    return pow(cache_hat(n), vec4<f32>(gamma));
}

// The kernel at γ = 1, the linear hat, without a `pow` (four exp2/log2
// pairs a pixel on a CPU rasteriser).
fn cache_hat(n: CacheNeighbours) -> vec4<f32> {
    let r = f32(max(cache_params.refresh_quad, 1u)) * 1.41421356;
    return max(vec4<f32>(0.01), vec4<f32>(1.0) - (n.distance / r));
}

// `cache_upsample`'s mode: the reconstruction in its low byte, and flags.
// The paper's spatial filter of the temporal gradient: the absolute
// gradients, geometry-blind (§3.5.1: a mip of |∇| read at level 2.5, which
// spreads a disocclusion's maximum into its neighbours, Fig. 6).
const CACHE_MODE_PAPER_GRADIENT: u32 = 256u;
// The temporal reconstruction's holes (every pixel the history misses,
// not shaded this frame) left to the third pass, which shades them at full
// resolution: the paper's temporal baseline with second-pass hole filling.
const CACHE_MODE_FILL_HOLES: u32 = 512u;
// σz of the depth weight a share of the camera's depth range (far − near),
// as the paper sets it (§3.1), where the host gives the range; else of the
// depth itself.
const CACHE_MODE_DEPTH_RANGE: u32 = 1024u;
// The history's disocclusion test compares the draw's id with the ones the
// history keeps around where the point was, beside the depth: the paper's
// material ids, for contact points (two surfaces meeting at one depth).
const CACHE_MODE_MATERIAL_IDS: u32 = 2048u;

// The payload at a full-resolution pixel (pass 2), and the history to keep.
// `mode & 255`: 0 nearest sample, 1 bilinear, 2 spatial (eq. 1 with
// normal, depth and draw weights, a linear hat in image space), 3 temporal
// (eq. 4; the spatial result where the history misses), 4 spatio-temporal
// (eqs. 6–8); with the flags above.
// `before` and `hit` are the lookup of last frame's result where this
// point was (the cache's depth-tested reprojection), `previous_clip` its
// previous clip position, for the history texel.
fn cache_upsample(flags: u32, components: u32, frag_coord: vec4<f32>, normal: vec3<f32>, before: vec4<f32>, hit: bool, previous_clip: vec4<f32>) -> CacheUpsampled {
    let mode = flags & 255u;
    let n = cache_neighbours(frag_coord, normal, flags);
    let none = cache_history_texel(0.0, vec3<f32>(1.0));
    if (mode == 0u) {
        return CacheUpsampled(n.payload[n.nearest], none, false);
    }
    // The linear hat of bilinear and of the spatial upsampling: 1 − d/r.
    let hat = cache_hat(n);
    if (mode == 1u) {
        // Bilinear over the lattice: the product of the hats along x and
        // y is the tent's footprint; the radial hat stands in for it.
        return CacheUpsampled(cache_blend(n, hat).payload, none, false);
    }
    let spatial = cache_blend(n, hat * n.geometry);
    let own_spatial = n.own < 4u;
    if (mode == 2u) {
        return CacheUpsampled(spatial.payload, none, !own_spatial & (spatial.weight < CACHE_UNDERSAMPLED));
    }
    let own = n.own < 4u;
    let own_payload = n.payload[min(n.own, 3u)];
    // Where this point was last frame. With material ids its history is
    // found only where the texels its lookup reads showed this draw.
    let point = cache_point(previous_clip);
    var found = hit;
    if ((flags & CACHE_MODE_MATERIAL_IDS) != 0u) {
        found = hit & cache_history_same_draw(point.texel);
    }
    if (mode == 3u) {
        let reused = select(spatial.payload, before, found);
        let hole = !own & !found;
        let fill = (flags & CACHE_MODE_FILL_HOLES) != 0u;
        return CacheUpsampled(select(reused, own_payload, own), none, hole & (fill | (spatial.weight < CACHE_UNDERSAMPLED)));
    }
    // Last frame's history there: its weight and gradients.
    let texel = round(point.texel);
    let history = textureLoad(cache_previous_history, vec2<i32>(clamp(texel, vec2<f32>(0.0), cache_params.viewport - vec2<f32>(1.0))), 0);
    let previous_exact = history.x >= CACHE_EXACT;
    let previous_weight = history.x - select(0.0, CACHE_EXACT, previous_exact);
    // Eq. 8: the gradient, filtered over the samples' footprint in space
    // (the four nearest samples, 2s pixels across, weighted as the spatial
    // upsampling) and over four frames in time (0.4, 0.3, 0.2, 0.1); 1
    // where the history misses.
    // Ours: the signed gradients weighted as the spatial upsampling weighs
    // the samples, so that what another surface did does not count. The
    // paper's (CACHE_MODE_PAPER_GRADIENT): their absolute values, blind to
    // the geometry (the background's samples left out), so that opposite
    // changes near each other (a thin shadow's two edges) do not cancel
    // and a disocclusion spreads to its neighbours.
    let spatial_weights = hat * n.geometry;
    let signed_gradient = dot(spatial_weights, n.gradient) / max(spatial.weight, 1e-30);
    let blind_weights = hat * n.present;
    let blind_weight = dot(blind_weights, vec4<f32>(1.0));
    let absolute_gradient = dot(blind_weights, abs(n.gradient)) / max(blind_weight, 1e-30);
    let paper_gradient = (flags & CACHE_MODE_PAPER_GRADIENT) != 0u;
    let now_gradient = select(signed_gradient, absolute_gradient, paper_gradient);
    // Where no sample shows this surface (a silhouette pixel whose lattice
    // points this frame all fell on another draw or the background), the
    // samples say nothing of its change: it carries its last gradient, and
    // eq. 7 leans on its history.
    let reliable = select(spatial.weight, blind_weight, paper_gradient) > CACHE_RELIABLE;
    let now = select(1.0, select(history.y, now_gradient, reliable), found);
    let older = select(vec3<f32>(1.0), cache_history_gradients(history), found);
    let filtered = abs((0.4 * now) + dot(vec3<f32>(0.3, 0.2, 0.1), older));
    let confidence = 1.0 - clamp(filtered, 0.0, 1.0);
    // Ours: where this frame's samples alone say the shading changed by
    // half or more (a light switched on), the history is dropped at once,
    // as where it is disoccluded; eq. 8's temporal filter would keep a
    // share of it for frames. Smaller changes follow eq. 8.
    let changed = reliable & (abs(now) >= CACHE_CHANGED);
    let wf = select(cache_params.upsample_sensitivity * confidence * confidence, 0.0, changed);
    // Eq. 6 with the image kernel's exponent adapted (γ·wf, at most 4),
    // then eq. 7.
    let current = cache_blend(n, cache_image_kernel(n, 4.0 * wf) * n.geometry);
    let weight = max(current.weight, 1e-30);
    let kept = wf * select(0.0, previous_weight, found);
    var payload = ((current.payload * weight) + (before * kept)) / (weight + kept);
    var accumulated = min(weight + kept, CACHE_HISTORY_WEIGHT_LIMIT);
    // Ours: a static pixel converges to its own shading. The paper's blend
    // averages the interpolated values of the other s² − 1 phases into it
    // forever. Here a pixel shaded this frame shows its own sample (the
    // exact value now), and a pixel whose history is such a sample,
    // reprojected onto a texel centre (nothing moved) with the temporal
    // gradient below CACHE_STILL, keeps it until it is shaded again, s²
    // frames on: the cache variants' bounded staleness, with Δn = s².
    let still = filtered < CACHE_STILL;
    let centred = all(abs(point.texel - texel) < vec2<f32>(0.01));
    let keep = found & previous_exact & centred & still;
    payload = select(select(payload, before, keep), own_payload, own);
    accumulated = accumulated + select(0.0, CACHE_EXACT, own | keep);
    let unreliable = !own & (!found | changed) & (spatial.weight < CACHE_UNDERSAMPLED);
    return CacheUpsampled(payload, cache_history_texel(accumulated, vec3<f32>(now, older.x, older.y)), unreliable);
}
