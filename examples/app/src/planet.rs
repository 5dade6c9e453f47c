//! The application's scene: a marble planet turning under a fixed camera
//! and sun, its buffers, layouts and draw — what any wgpu app has before
//! it caches anything. The planet is skinned: two joints, the southern
//! hemisphere and the northern, which twists against it, each vertex
//! weighted between them across the equator.

use glam::{Mat4, Vec3};

/// Frames of rotation: 0.4° about the vertical per frame.
const DEGREES_PER_FRAME: f32 = 0.4;
/// The northern joint's twist against the southern one, per frame.
const TWIST_DEGREES_PER_FRAME: f32 = 0.6;
/// The width of the weights' ramp across the equator (in radii).
const BLEND: f32 = 0.3;

pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

pub const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 4] =
    wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Uint32x4, 3 => Float32x4];

pub fn vertex_layout() -> wgpu::VertexBufferLayout<'static> {
    wgpu::VertexBufferLayout {
        array_stride: 56,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &VERTEX_ATTRIBUTES,
    }
}

/// Both groups hold one uniform buffer.
pub const UNIFORM_ENTRY: [wgpu::BindGroupLayoutEntry; 1] = [wgpu::BindGroupLayoutEntry {
    binding: 0,
    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
    ty: wgpu::BindingType::Buffer {
        ty: wgpu::BufferBindingType::Uniform,
        has_dynamic_offset: false,
        min_binding_size: None,
    },
    count: None,
}];

pub struct Planet {
    pub globals: wgpu::Buffer,
    pub locals: wgpu::Buffer,
    pub layout: wgpu::BindGroupLayout,
    pub globals_group: wgpu::BindGroup,
    pub locals_group: wgpu::BindGroup,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    aspect: f32,
}

fn f32_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

impl Planet {
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, aspect: f32) -> Planet {
        let (vertices, indices) = sphere(48, 48);
        let buffer = |label, bytes: &[u8], usage| {
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes.len() as u64,
                usage: usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            queue.write_buffer(&buffer, 0, bytes);
            buffer
        };
        // COPY_SRC: the cached variant keeps last frame's copy of each.
        let uniform = wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_SRC;
        let globals = buffer("globals", &[0; 96], uniform);
        let locals = buffer("locals", &[0; 128], uniform);
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("uniforms"),
            entries: &UNIFORM_ENTRY,
        });
        let group = |buffer: &wgpu::Buffer| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: None,
                layout: &layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: buffer.as_entire_binding(),
                }],
            })
        };
        let (globals_group, locals_group) = (group(&globals), group(&locals));
        let index_bytes: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        Planet {
            vertices: buffer("sphere", &vertices, wgpu::BufferUsages::VERTEX),
            indices: buffer("sphere indices", &index_bytes, wgpu::BufferUsages::INDEX),
            index_count: indices.len() as u32,
            globals,
            locals,
            layout,
            globals_group,
            locals_group,
            aspect,
        }
    }

    /// Writes frame `frame`'s camera, sun and joints.
    pub fn update(&self, queue: &wgpu::Queue, frame: u32) {
        let eye = Vec3::new(0.0, 0.3, 2.6);
        let view_projection = Mat4::perspective_rh(45f32.to_radians(), self.aspect, 0.1, 20.0)
            * Mat4::look_at_rh(eye, Vec3::ZERO, Vec3::Y);
        let sun = Vec3::new(3.0, 4.0, 2.5).normalize();
        let mut globals = view_projection.to_cols_array().to_vec();
        globals.extend([sun.x, sun.y, sun.z, 0.0, 1.0, 0.97, 0.92, 1.0]);
        queue.write_buffer(&self.globals, 0, &f32_bytes(&globals));
        let turn = (DEGREES_PER_FRAME * frame as f32).to_radians();
        let model = Mat4::from_rotation_y(turn);
        // Each joint's skinning matrix: the model matrix times its pose.
        // The northern joint turns about the vertical through its pivot at
        // the centre.
        let twist = Mat4::from_rotation_y((TWIST_DEGREES_PER_FRAME * frame as f32).to_radians());
        let joints: Vec<f32> = [model, model * twist]
            .iter()
            .flat_map(|m| m.to_cols_array())
            .collect();
        queue.write_buffer(&self.locals, 0, &f32_bytes(&joints));
    }

    /// The planet's draw, as in the original pass.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        self.bind(pass);
        pass.draw_indexed(0..self.index_count, 0, 0..1);
    }

    /// The same draw in a cached variant's pass, through the host, with the
    /// draw's twins (in a deferred plan's screen-space passes the host
    /// draws the screen's triangle instead).
    pub fn draw_cached(
        &self,
        draw: &mut shadecache_host::Draw<'_, '_>,
        twins: &shadecache_host::Twins,
    ) {
        draw.set_bind_group(0, &self.globals_group, &[]);
        draw.set_bind_group(1, &self.locals_group, &[]);
        draw.set_vertex_buffer(0, self.vertices.slice(..));
        draw.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
        draw.draw_indexed(twins, 0..self.index_count, 0, 0..1);
    }

    fn bind(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_bind_group(0, &self.globals_group, &[]);
        pass.set_bind_group(1, &self.locals_group, &[]);
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
    }
}

/// A vertex's joints and weights: the southern joint below the equator,
/// the northern above, smoothstep weights across a band `BLEND` wide.
fn influence(y: f32) -> ([u32; 4], [f32; 4]) {
    let t = ((y + BLEND * 0.5) / BLEND).clamp(0.0, 1.0);
    let north = t * t * (3.0 - 2.0 * t);
    ([0, 1, 0, 0], [1.0 - north, north, 0.0, 0.0])
}

/// A UV sphere of radius 1: (rings + 1) × (segments + 1) vertices of
/// position, normal, joints and weights (56 bytes), two triangles per
/// quad.
fn sphere(rings: u32, segments: u32) -> (Vec<u8>, Vec<u32>) {
    use std::f32::consts::{PI, TAU};
    let mut vertices = Vec::new();
    for ring in 0..=rings {
        for segment in 0..=segments {
            let (u, v) = (segment as f32 / segments as f32, ring as f32 / rings as f32);
            let (theta, phi) = (PI * v, TAU * u);
            let n = [
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            ];
            let (joints, weights) = influence(n[1]);
            for value in n.into_iter().chain(n) {
                vertices.extend(value.to_le_bytes());
            }
            for joint in joints {
                vertices.extend(joint.to_le_bytes());
            }
            for weight in weights {
                vertices.extend(weight.to_le_bytes());
            }
        }
    }
    let row = segments + 1;
    let mut indices = Vec::new();
    for ring in 0..rings {
        for segment in 0..segments {
            let a = ring * row + segment;
            indices.extend([a, a + 1, a + row, a + 1, a + row + 1, a + row]);
        }
    }
    (vertices, indices)
}
