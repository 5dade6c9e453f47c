// Glossy environment reflection with a normal map.
//
// A tangent-space normal map perturbs the interpolated normal; the view
// vector is reflected about the result and the environment cube map is
// sampled 25 times around the reflection vector with 5x5 Gaussian weights,
// which blurs the reflection like a rough metal surface. The blur is a
// helper function with constant-bound loops; its result, called from the
// fragment entry point, is the expensive value of this shader.

struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
    camera_position: vec3<f32>,
    // Angular spacing of the blur taps (radians, roughly).
    blur_radius: f32,
    base_color: vec3<f32>,
    // Strength of the normal map perturbation, 0 = flat.
    normal_strength: f32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var normal_map: texture_2d<f32>;
@group(0) @binding(2) var environment_map: texture_cube<f32>;
@group(0) @binding(3) var linear_sampler: sampler;

struct VertexInput {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
}

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    @location(1) world_normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
}

@vertex
fn vs_main(in: VertexInput) -> VertexOutput {
    let world = frame.world_from_local * vec4<f32>(in.position, 1.0);
    var out: VertexOutput;
    out.clip_position = frame.clip_from_world * world;
    out.world_position = world.xyz;
    out.world_normal = (frame.world_from_local * vec4<f32>(in.normal, 0.0)).xyz;
    out.uv = in.uv;
    return out;
}

// Orthonormal basis (tangent, bitangent, n) around a unit vector n,
// branch-free (Duff et al. 2017). No mesh tangents are needed.
fn orthonormal_basis(n: vec3<f32>) -> mat3x3<f32> {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    let tangent = vec3<f32>(1.0 + (s * n.x * n.x * a), s * b, -s * n.x);
    let bitangent = vec3<f32>(b, s + (n.y * n.y * a), -n.y);
    return mat3x3<f32>(tangent, bitangent, n);
}

// 5x5 Gaussian-weighted average of the environment around direction r.
// Taps are spread over the plane perpendicular to r; sigma is one tap.
// Explicit level 0 keeps the samples valid inside the loops.
fn blurred_environment(r: vec3<f32>, radius: f32) -> vec3<f32> {
    let basis = orthonormal_basis(r);
    var sum = vec3<f32>(0.0);
    var weight_sum = 0.0;
    for (var i = 0; i < 5; i++) {
        for (var j = 0; j < 5; j++) {
            let offset = vec2<f32>(f32(i - 2), f32(j - 2));
            let weight = exp(-0.5 * dot(offset, offset));
            let tap = normalize(r + (radius * ((offset.x * basis[0]) + (offset.y * basis[1]))));
            sum += weight * textureSampleLevel(environment_map, linear_sampler, tap, 0.0).rgb;
            weight_sum += weight;
        }
    }
    return sum / weight_sum;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    // Normal mapping: tangent-space normal from the texture, taken into
    // world space with a basis built around the interpolated normal.
    let geometric_normal = normalize(in.world_normal);
    let normal_texel = textureSample(normal_map, linear_sampler, in.uv).xyz;
    let tangent_normal = (normal_texel * 2.0) - vec3<f32>(1.0);
    let bent = vec3<f32>(tangent_normal.xy * frame.normal_strength, tangent_normal.z);
    let n = normalize(orthonormal_basis(geometric_normal) * bent);

    // Reflection of the view direction about the perturbed normal.
    let v = normalize(frame.camera_position - in.world_position);
    let r = reflect(-v, n);

    // The expensive part: 25 environment samples.
    let reflection = blurred_environment(r, frame.blur_radius);

    // Schlick Fresnel with a metal-like base reflectance. The dot of two
    // unit vectors can round past 1, and pow() of a negative base is NaN:
    // clamp it to [0, 1] (at 512² a few pixels face the camera exactly).
    let n_dot_v = clamp(dot(n, v), 0.0, 1.0);
    let fresnel = frame.base_color + ((vec3<f32>(1.0) - frame.base_color) * pow(1.0 - n_dot_v, 5.0));
    let color = reflection * fresnel;
    return vec4<f32>(color, 1.0);
}
