// Procedural wood-and-rust material built from nested helper functions.
//
// Call chain: fbm -> value_noise -> hash (three levels), and fbm is called
// several times from the fragment entry point (domain warping plus detail).
// The vertex position also goes through helpers: to_clip -> to_world.

struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
    camera_position: vec3<f32>,
    // Pattern cells per world unit.
    pattern_scale: f32,
    light_position: vec3<f32>,
    time: f32,
    light_color: vec3<f32>,
    // Strength of the domain warp.
    warp_amount: f32,
}

@group(0) @binding(0) var<uniform> frame: Frame;

struct VertexInput {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
}

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    @location(1) world_normal: vec3<f32>,
}

// Object space to world space.
fn to_world(p: vec3<f32>) -> vec4<f32> {
    return frame.world_from_local * vec4<f32>(p, 1.0);
}

// Object space to clip space, through to_world.
fn to_clip(p: vec3<f32>) -> vec4<f32> {
    return frame.clip_from_world * to_world(p);
}

@vertex
fn vs_main(in: VertexInput) -> VertexOutput {
    var out: VertexOutput;
    out.clip_position = to_clip(in.position);
    out.world_position = to_world(in.position).xyz;
    out.world_normal = (frame.world_from_local * vec4<f32>(in.normal, 0.0)).xyz;
    return out;
}

// Level 3: hash of a 2D point to [0, 1) with float arithmetic only
// (after Dave Hoskins' "hash without sine").
fn hash(p: vec2<f32>) -> f32 {
    var p3 = fract(vec3<f32>(p.x, p.y, p.x) * 0.1031);
    p3 += vec3<f32>(dot(p3, p3.yzx + vec3<f32>(33.33)));
    return fract((p3.x + p3.y) * p3.z);
}

// Level 2: value noise, bilinear interpolation (smoothstep weights) of the
// hashes of the four surrounding lattice points.
fn value_noise(p: vec2<f32>) -> f32 {
    let cell = floor(p);
    let f = p - cell;
    let u = f * f * (vec2<f32>(3.0) - (2.0 * f));
    let a = hash(cell);
    let b = hash(cell + vec2<f32>(1.0, 0.0));
    let c = hash(cell + vec2<f32>(0.0, 1.0));
    let d = hash(cell + vec2<f32>(1.0, 1.0));
    return mix(mix(a, b, u.x), mix(c, d, u.x), u.y);
}

// Level 1: fractal Brownian motion, four octaves of value noise with a
// rotation between octaves to hide lattice alignment. Result in [0, 1).
fn fbm(p: vec2<f32>) -> f32 {
    let rotation = mat2x2<f32>(0.8, 0.6, -0.6, 0.8);
    var q = p;
    var amplitude = 0.5;
    var total = 0.0;
    for (var octave = 0; octave < 4; octave++) {
        total += amplitude * value_noise(q);
        q = (rotation * q) * 2.0;
        amplitude *= 0.5;
    }
    return total / 0.9375;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    let p = in.world_position.xz * frame.pattern_scale;

    // Domain-warped wood rings: fbm is evaluated three times.
    let warp_x = fbm(p);
    let warp_y = fbm(p + vec2<f32>(5.2, 1.3));
    let warped = p + (frame.warp_amount * vec2<f32>(warp_x, warp_y));
    let rings = fract(length(warped) * 3.0);
    let grain = fbm(warped * 6.0);

    // Rust patches from a fourth, low-frequency fbm.
    let rust_mask = smoothstep(0.55, 0.7, fbm(p * 0.5 + vec2<f32>(17.0, -3.0)));

    let wood_light = vec3<f32>(0.72, 0.52, 0.32);
    let wood_dark = vec3<f32>(0.40, 0.25, 0.13);
    let wood = mix(wood_dark, wood_light, (rings * 0.7) + (grain * 0.3));
    let rust = vec3<f32>(0.45, 0.18, 0.07) * (0.6 + (0.4 * grain));
    let albedo = mix(wood, rust, rust_mask);
    let shininess = mix(32.0, 4.0, rust_mask);

    // Blinn-Phong; rust is rough, wood has a varnish highlight.
    let n = normalize(in.world_normal);
    let to_light = frame.light_position - in.world_position;
    let l = normalize(to_light);
    let v = normalize(frame.camera_position - in.world_position);
    let h = normalize(l + v);
    let n_dot_l = max(dot(n, l), 0.0);
    let highlight = pow(max(dot(n, h), 0.0), shininess) * (1.0 - rust_mask) * select(0.0, 1.0, n_dot_l > 0.0);
    let color = frame.light_color * ((albedo * (n_dot_l + 0.1)) + vec3<f32>(0.3 * highlight));
    return vec4<f32>(color, 1.0);
}
