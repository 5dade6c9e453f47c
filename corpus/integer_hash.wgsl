// Cellular (Worley) stone pattern with integer hashing.
//
// The surface is divided into cells; each cell has a feature point placed
// by a PCG hash of the integer cell coordinates. The cell coordinates, the
// hash of the pixel's own cell and values derived from it are i32/u32
// values at the top level of the fragment entry point; they are turned into
// floats (a per-cell tint and a parity flag) before shading.

struct Frame {
    clip_from_world: mat4x4<f32>,
    world_from_local: mat4x4<f32>,
    camera_position: vec3<f32>,
    // Cells per uv unit.
    cell_density: f32,
    light_position: vec3<f32>,
    // Width of the mortar between stones, in cell units.
    mortar_width: f32,
    light_color: vec3<f32>,
    // Seed mixed into the hash to get a different layout.
    seed: u32,
}

@group(0) @binding(0) var<uniform> frame: Frame;

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

// 2D PCG hash (Jarzynski and Olano 2020): two u32 in, two mixed u32 out.
fn pcg2d(v_in: vec2<u32>) -> vec2<u32> {
    var v = (v_in * 1664525u) + vec2<u32>(1013904223u);
    v.x += v.y * 1664525u;
    v.y += v.x * 1664525u;
    v = v ^ (v >> vec2<u32>(16u));
    v.x += v.y * 1664525u;
    v.y += v.x * 1664525u;
    v = v ^ (v >> vec2<u32>(16u));
    return v;
}

// Feature point of a cell, as an offset in [0, 1)^2 from the cell corner.
fn feature_point(cell: vec2<i32>) -> vec2<f32> {
    let h = pcg2d(bitcast<vec2<u32>>(cell) ^ vec2<u32>(frame.seed));
    return vec2<f32>(h >> vec2<u32>(8u)) * (1.0 / 16777216.0);
}

// Distances to the nearest (x) and second nearest (y) feature points,
// searching the 3x3 block of cells around the pixel's cell.
fn worley(p: vec2<f32>, cell: vec2<i32>) -> vec2<f32> {
    var f1 = 8.0;
    var f2 = 8.0;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let neighbour = cell + vec2<i32>(dx, dy);
            let point = vec2<f32>(neighbour) + feature_point(neighbour);
            let d = distance(p, point);
            if (d < f1) {
                f2 = f1;
                f1 = d;
            } else if (d < f2) {
                f2 = d;
            }
        }
    }
    return vec2<f32>(f1, f2);
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    let p = in.uv * frame.cell_density;

    // Integer intermediates at the top level.
    let cell = vec2<i32>(floor(p));
    let cell_hash = pcg2d(bitcast<vec2<u32>>(cell) ^ vec2<u32>(frame.seed));
    let cell_id = cell_hash.x ^ (cell_hash.y >> 7u);
    let palette_index = cell_id % 4u;
    let parity = (cell.x + cell.y) & 1;

    // Worley distances; the border between stones is where F2 - F1 is small.
    let distances = worley(p, cell);
    let edge = distances.y - distances.x;
    let mortar = 1.0 - smoothstep(frame.mortar_width, frame.mortar_width + 0.05, edge);

    // Integers turned into floats for shading.
    let brightness = 0.75 + (0.25 * (f32(cell_id & 255u) / 255.0));
    let warm = f32(palette_index) / 3.0;
    let parity_shade = 0.9 + (0.1 * f32(parity));
    let stone = mix(vec3<f32>(0.55, 0.57, 0.60), vec3<f32>(0.70, 0.58, 0.45), warm) * (brightness * parity_shade);
    let albedo = mix(stone, vec3<f32>(0.25, 0.24, 0.22), mortar);

    // Cavity term: stones darken towards their borders.
    let cavity = mix(0.6, 1.0, clamp(edge * 2.0, 0.0, 1.0));

    // Blinn-Phong from a point light.
    let n = normalize(in.world_normal);
    let to_light = frame.light_position - in.world_position;
    let l = normalize(to_light);
    let v = normalize(frame.camera_position - in.world_position);
    let h = normalize(l + v);
    let n_dot_l = max(dot(n, l), 0.0);
    let specular = pow(max(dot(n, h), 0.0), 16.0) * (1.0 - mortar) * 0.2;
    let color = frame.light_color * ((albedo * cavity * (n_dot_l + 0.1)) + vec3<f32>(specular));
    return vec4<f32>(color, 1.0);
}
