// A material's fragment shader with no vertex stage of its own, as Bevy's
// custom materials are written: it declares the view and its material and
// reads what the mesh pipeline's vertex stage (corpus/split/mesh.wgsl)
// outputs. Toon shading: banded diffuse, a hard specular spot and a rim,
// over cross-hatching from a few octaves of noise in helper functions.

struct View {
    clip_from_world: mat4x4<f32>,
    world_position: vec3<f32>,
    exposure: f32,
}
@group(0) @binding(0) var<uniform> view: View;

struct ToonMaterial {
    color: vec4<f32>,
    light_position: vec3<f32>,
    bands: f32,
    rim_color: vec3<f32>,
    hatch_scale: f32,
}
@group(1) @binding(0) var<uniform> material: ToonMaterial;

struct VertexOutput {
    @builtin(position) position: vec4<f32>,
    @location(0) world_position: vec4<f32>,
    @location(1) world_normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
}

fn hash(p: vec3<f32>) -> f32 {
    let q = fract(p * 0.3183099 + vec3<f32>(0.1, 0.2, 0.3));
    let r = q * 17.0;
    return fract(r.x * r.y * r.z * (r.x + r.y + r.z));
}

fn value_noise(p: vec3<f32>) -> f32 {
    let i = floor(p);
    let f = fract(p);
    let u = f * f * (3.0 - 2.0 * f);
    let a = mix(hash(i), hash(i + vec3<f32>(1.0, 0.0, 0.0)), u.x);
    let b = mix(hash(i + vec3<f32>(0.0, 1.0, 0.0)), hash(i + vec3<f32>(1.0, 1.0, 0.0)), u.x);
    let c = mix(hash(i + vec3<f32>(0.0, 0.0, 1.0)), hash(i + vec3<f32>(1.0, 0.0, 1.0)), u.x);
    let d = mix(hash(i + vec3<f32>(0.0, 1.0, 1.0)), hash(i + vec3<f32>(1.0, 1.0, 1.0)), u.x);
    return mix(mix(a, b, u.y), mix(c, d, u.y), u.z);
}

fn hatching(p: vec3<f32>) -> f32 {
    var sum = 0.0;
    var scale = 1.0;
    for (var octave = 0; octave < 4; octave++) {
        sum += value_noise(p * scale) / scale;
        scale *= 2.0;
    }
    return sum;
}

@fragment
fn fragment(in: VertexOutput) -> @location(0) vec4<f32> {
    let n = normalize(in.world_normal);
    let to_light = normalize(material.light_position - in.world_position.xyz);
    let to_view = normalize(view.world_position - in.world_position.xyz);

    let lambert = max(dot(n, to_light), 0.0);
    let banded = floor(lambert * material.bands) / material.bands;
    let half_dir = normalize(to_light + to_view);
    let spot = step(0.96, dot(n, half_dir));
    let rim = smoothstep(0.6, 1.0, 1.0 - max(dot(n, to_view), 0.0));

    let hatch = hatching(in.world_position.xyz * material.hatch_scale);
    var color = material.color.rgb * (0.25 + 0.75 * banded);
    if (banded < 0.5) {
        color *= 0.6 + 0.4 * hatch;
    }
    color += vec3<f32>(spot) + material.rim_color * rim;
    return vec4<f32>(color * view.exposure, material.color.a);
}
