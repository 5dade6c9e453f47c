#define_import_path engine::lighting

#import engine::view::view

struct PointLight {
    position: vec3<f32>,
    radius: f32,
    color: vec3<f32>,
    intensity: f32,
}

@group(1) @binding(0) var<uniform> light: PointLight;

fn distance_attenuation(distance: f32, radius: f32) -> f32 {
    let ratio = distance / radius;
    let window = saturate(1.0 - ratio * ratio * ratio * ratio);
    return window * window / (distance * distance + 1.0);
}

// Blinn-Phong from the one point light, as seen from the view.
fn point_light(world_position: vec3<f32>, normal: vec3<f32>, albedo: vec3<f32>, gloss: f32) -> vec3<f32> {
    let to_light = light.position - world_position;
    let distance = length(to_light);
    let l = to_light / distance;
    let v = normalize(view.world_position - world_position);
    let h = normalize(l + v);
    let diffuse = max(dot(normal, l), 0.0) * albedo;
    let specular = pow(max(dot(normal, h), 0.0), 4.0 + 60.0 * gloss);
    let attenuation = distance_attenuation(distance, light.radius);
#ifdef SOFT_SPECULAR
    let shine = specular * 0.5;
#else
    let shine = specular;
#endif
    return (diffuse + vec3<f32>(shine)) * light.color * light.intensity * attenuation;
}
