// Procedural marble lit with Blinn-Phong.
//
// Five octaves of 3D gradient (Perlin-style) noise are summed into a
// turbulence value that bends a sine stripe pattern into marble veins.
// The octave sum is unrolled in the fragment entry point as a chain of
// partial sums (o1, s2, s3, s4, s5), so every partial sum is a separate
// value that could be kept from one frame to the next. The noise is taken
// in object space, so the pattern sticks to the surface as the object moves.

struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
    camera_position: vec3<f32>,
    time: f32,
    light_position: vec3<f32>,
    // Stripes per object-space unit along x.
    marble_frequency: f32,
    light_color: vec3<f32>,
    // How strongly the turbulence bends the stripes.
    turbulence_amount: f32,
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
    @location(2) local_position: vec3<f32>,
}

@vertex
fn vs_main(in: VertexInput) -> VertexOutput {
    let world = frame.world_from_local * vec4<f32>(in.position, 1.0);
    var out: VertexOutput;
    out.clip_position = frame.clip_from_world * world;
    out.world_position = world.xyz;
    // world_from_local is assumed to scale uniformly, so it maps normals too.
    out.world_normal = (frame.world_from_local * vec4<f32>(in.normal, 0.0)).xyz;
    out.local_position = in.position;
    return out;
}

// PCG hash (O'Neill), one u32 in, one well-mixed u32 out.
fn pcg(v: u32) -> u32 {
    let state = (v * 747796405u) + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// Pseudo-random gradient for an integer lattice point, components in [-1, 1].
fn lattice_gradient(cell: vec3<i32>) -> vec3<f32> {
    let c = bitcast<vec3<u32>>(cell);
    let h = pcg(c.x ^ pcg(c.y ^ pcg(c.z)));
    let bits = vec3<u32>(h & 1023u, (h >> 10u) & 1023u, (h >> 20u) & 1023u);
    return (vec3<f32>(bits) / 511.5) - vec3<f32>(1.0);
}

// Quintic fade curve 6t^5 - 15t^4 + 10t^3.
fn fade(t: vec3<f32>) -> vec3<f32> {
    return t * t * t * ((t * ((t * 6.0) - vec3<f32>(15.0))) + vec3<f32>(10.0));
}

// Contribution of one lattice corner: gradient dotted with the offset to it.
fn corner(cell: vec3<i32>, f: vec3<f32>, offset: vec3<i32>) -> f32 {
    return dot(lattice_gradient(cell + offset), f - vec3<f32>(offset));
}

// 3D gradient noise, roughly in [-1, 1]: trilinear interpolation (with the
// fade curve) of the eight corner contributions of the enclosing cell.
fn gradient_noise(p: vec3<f32>) -> f32 {
    let floor_p = floor(p);
    let cell = vec3<i32>(floor_p);
    let f = p - floor_p;
    let u = fade(f);

    let n000 = corner(cell, f, vec3<i32>(0, 0, 0));
    let n100 = corner(cell, f, vec3<i32>(1, 0, 0));
    let n010 = corner(cell, f, vec3<i32>(0, 1, 0));
    let n110 = corner(cell, f, vec3<i32>(1, 1, 0));
    let n001 = corner(cell, f, vec3<i32>(0, 0, 1));
    let n101 = corner(cell, f, vec3<i32>(1, 0, 1));
    let n011 = corner(cell, f, vec3<i32>(0, 1, 1));
    let n111 = corner(cell, f, vec3<i32>(1, 1, 1));

    let x00 = mix(n000, n100, u.x);
    let x10 = mix(n010, n110, u.x);
    let x01 = mix(n001, n101, u.x);
    let x11 = mix(n011, n111, u.x);
    let y0 = mix(x00, x10, u.y);
    let y1 = mix(x01, x11, u.y);
    return mix(y0, y1, u.z);
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    let p = in.local_position * 2.0;

    // Turbulence: sum of |noise| over five octaves, each octave at twice the
    // frequency and half the amplitude of the previous one. Unrolled so that
    // each partial sum is its own value.
    let o1 = abs(gradient_noise(p));
    let s2 = o1 + (0.5 * abs(gradient_noise(p * 2.0)));
    let s3 = s2 + (0.25 * abs(gradient_noise(p * 4.0)));
    let s4 = s3 + (0.125 * abs(gradient_noise(p * 8.0)));
    let s5 = s4 + (0.0625 * abs(gradient_noise(p * 16.0)));
    let turbulence = s5;

    // Marble: a sine stripe pattern along x, displaced by the turbulence.
    let stripes = sin((p.x * frame.marble_frequency) + (turbulence * frame.turbulence_amount));
    let band = sqrt(0.5 + (0.5 * stripes));
    let vein_color = vec3<f32>(0.22, 0.20, 0.28);
    let stone_color = vec3<f32>(0.93, 0.91, 0.87);
    let albedo = mix(vein_color, stone_color, band);

    // Depends only on the uniform: the same for every pixel.
    let ambient_light = frame.light_color * 0.08;

    // Blinn-Phong with a point light and distance attenuation.
    let n = normalize(in.world_normal);
    let to_light = frame.light_position - in.world_position;
    let l = normalize(to_light);
    let v = normalize(frame.camera_position - in.world_position);
    let h = normalize(l + v);
    let n_dot_l = max(dot(n, l), 0.0);
    let n_dot_h = max(dot(n, h), 0.0);
    let specular = pow(n_dot_h, 48.0) * select(0.0, 1.0, n_dot_l > 0.0);
    let attenuation = 1.0 / (1.0 + (0.05 * dot(to_light, to_light)));
    let direct = frame.light_color * attenuation * ((albedo * n_dot_l) + vec3<f32>(0.35 * specular));
    let color = (ambient_light * albedo) + direct;
    return vec4<f32>(color, 1.0);
}
