// A terrain material that picks its surface per pixel, as terrain and
// splatting shaders do: grass where the ground is flat, rock where it is
// steep, each with its own procedural detail. The albedo is a local `var`
// assigned in both arms of an `if` on the slope (a per-pixel condition),
// and the detail noise lives in helper functions.

struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
    camera_position: vec3<f32>,
    time: f32,
    light_position: vec3<f32>,
    grass_slope: f32,
}

@group(0) @binding(0) var<uniform> frame: Frame;

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    @location(1) world_normal: vec3<f32>,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>) -> VertexOutput {
    let world = frame.world_from_local * vec4<f32>(position, 1.0);
    var out: VertexOutput;
    out.clip_position = frame.clip_from_world * world;
    out.world_position = world.xyz;
    out.world_normal = (frame.world_from_local * vec4<f32>(normal, 0.0)).xyz;
    return out;
}

fn hash3(p: vec3<f32>) -> f32 {
    let q = fract(p * 0.3183099 + vec3<f32>(0.1, 0.2, 0.3)) * 17.0;
    return fract(q.x * q.y * q.z * (q.x + q.y + q.z));
}

fn value_noise(p: vec3<f32>) -> f32 {
    let i = floor(p);
    let f = fract(p);
    let u = f * f * (3.0 - 2.0 * f);
    let n000 = hash3(i);
    let n100 = hash3(i + vec3<f32>(1.0, 0.0, 0.0));
    let n010 = hash3(i + vec3<f32>(0.0, 1.0, 0.0));
    let n110 = hash3(i + vec3<f32>(1.0, 1.0, 0.0));
    let n001 = hash3(i + vec3<f32>(0.0, 0.0, 1.0));
    let n101 = hash3(i + vec3<f32>(1.0, 0.0, 1.0));
    let n011 = hash3(i + vec3<f32>(0.0, 1.0, 1.0));
    let n111 = hash3(i + vec3<f32>(1.0, 1.0, 1.0));
    let x00 = mix(n000, n100, u.x);
    let x10 = mix(n010, n110, u.x);
    let x01 = mix(n001, n101, u.x);
    let x11 = mix(n011, n111, u.x);
    return mix(mix(x00, x10, u.y), mix(x01, x11, u.y), u.z);
}

fn fbm(p: vec3<f32>) -> f32 {
    var sum = 0.0;
    var amplitude = 0.5;
    var q = p;
    for (var octave = 0; octave < 4; octave++) {
        sum += amplitude * value_noise(q);
        q = q * 2.03;
        amplitude *= 0.5;
    }
    return sum;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    let n = normalize(in.world_normal);
    var albedo: vec3<f32>;
    if (n.y > frame.grass_slope) {
        let blades = fbm(in.world_position * 24.0);
        albedo = mix(vec3<f32>(0.10, 0.28, 0.05), vec3<f32>(0.30, 0.45, 0.12), blades);
    } else {
        let strata = fbm(vec3<f32>(in.world_position.x * 3.0, in.world_position.y * 40.0, in.world_position.z * 3.0));
        albedo = mix(vec3<f32>(0.32, 0.30, 0.28), vec3<f32>(0.55, 0.50, 0.45), strata);
    }
    let l = normalize(frame.light_position - in.world_position);
    let diffuse = max(dot(n, l), 0.0);
    let color = albedo * (0.15 + 0.85 * diffuse);
    return vec4<f32>(color, 1.0);
}
