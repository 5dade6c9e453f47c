//! The planet in a window (the `window` feature): each redraw writes the
//! uniforms, then draws with the original pipeline or records the cached
//! variant into the surface's texture; the space bar switches between
//! them. Resizing resizes the cache (its next frame misses everywhere).
//! Every 120 frames it prints the GPU time of each pass.

use std::error::Error;
use std::sync::Arc;

use shadecache_host::{CachedShader, Targets, Timestamps, TwinSources, Twins};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, KeyEvent, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

use super::planet::{self, Planet};
use super::{cached_shader, draw_original, original_pipeline, Gpu};

pub fn run(refresh_period: Option<u32>) -> Result<(), Box<dyn Error>> {
    let event_loop = EventLoop::new()?;
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
        Box::new(event_loop.owned_display_handle()),
    ));
    let mut app = App {
        instance,
        refresh_period,
        state: None,
        error: None,
    };
    event_loop.run_app(&mut app)?;
    match app.error {
        Some(err) => Err(err),
        None => Ok(()),
    }
}

struct App {
    instance: wgpu::Instance,
    refresh_period: Option<u32>,
    state: Option<State>,
    error: Option<Box<dyn Error>>,
}

/// What the window draws with.
struct State {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    gpu: Gpu,
    planet: Planet,
    original: wgpu::RenderPipeline,
    cached: CachedShader,
    twins: Twins,
    depth: wgpu::TextureView,
    timer: Option<Timestamps>,
    use_cache: bool,
    frame: u32,
    /// Per pass: its name, summed milliseconds and frames.
    times: Vec<(String, f64, u32)>,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.state.is_some() {
            return;
        }
        match self.start(event_loop) {
            Ok(state) => self.state = Some(state),
            Err(err) => {
                self.error = Some(err);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(state) = &mut self.state else {
            return;
        };
        let result = match event {
            WindowEvent::CloseRequested => {
                event_loop.exit();
                Ok(())
            }
            WindowEvent::Resized(size) => {
                state.resize(size.width, size.height);
                Ok(())
            }
            WindowEvent::KeyboardInput {
                event:
                    KeyEvent {
                        logical_key: Key::Named(NamedKey::Space),
                        state: ElementState::Pressed,
                        ..
                    },
                ..
            } => {
                state.use_cache = !state.use_cache;
                let drawing = if state.use_cache {
                    "the cached variant"
                } else {
                    "the original"
                };
                println!("drawing {drawing}");
                Ok(())
            }
            WindowEvent::RedrawRequested => {
                let drawn = state.draw();
                state.window.request_redraw();
                drawn
            }
            _ => Ok(()),
        };
        if let Err(err) = result {
            self.error = Some(err);
            event_loop.exit();
        }
    }
}

impl App {
    fn start(&self, event_loop: &ActiveEventLoop) -> Result<State, Box<dyn Error>> {
        let window = Arc::new(event_loop.create_window(
            Window::default_attributes().with_title("shadecache: a marble planet, cached"),
        )?);
        let surface = self.instance.create_surface(window.clone())?;
        let adapter =
            pollster::block_on(self.instance.request_adapter(&wgpu::RequestAdapterOptions {
                compatible_surface: Some(&surface),
                ..Default::default()
            }))?;
        let (device, queue) =
            pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
                required_features: adapter.features() & wgpu::Features::TIMESTAMP_QUERY,
                ..Default::default()
            }))?;
        let size = window.inner_size();
        let (width, height) = (size.width.max(1), size.height.max(1));
        let config = surface
            .get_default_config(&adapter, width, height)
            .ok_or("the surface does not work with this adapter")?;
        surface.configure(&device, &config);
        let gpu = Gpu {
            device,
            queue,
            name: adapter.get_info().name,
        };
        let planet = Planet::new(&gpu.device, &gpu.queue, width as f32 / height as f32);
        let original = original_pipeline(&gpu, &planet, config.format);
        let mut cached = cached_shader(
            &gpu,
            (self.refresh_period, false),
            config.format,
            (width, height),
        )?;
        let twins = cached.twins(&TwinSources {
            buffers: &[([0, 0], &planet.globals), ([1, 0], &planet.locals)],
            ..TwinSources::default()
        })?;
        println!(
            "{}: the space bar switches between the original and the cached variant",
            gpu.name
        );
        Ok(State {
            depth: depth_view(&gpu, width, height),
            timer: Timestamps::new(&gpu.device, &gpu.queue, 3),
            window,
            surface,
            config,
            planet,
            original,
            cached,
            twins,
            gpu,
            use_cache: true,
            frame: 0,
            times: Vec::new(),
        })
    }
}

fn depth_view(gpu: &Gpu, width: u32, height: u32) -> wgpu::TextureView {
    crate::texture(&gpu.device, "depth", (width, height), planet::DEPTH_FORMAT)
        .create_view(&wgpu::TextureViewDescriptor::default())
}

impl State {
    fn resize(&mut self, width: u32, height: u32) {
        let (width, height) = (width.max(1), height.max(1));
        self.config.width = width;
        self.config.height = height;
        self.surface.configure(&self.gpu.device, &self.config);
        self.depth = depth_view(&self.gpu, width, height);
        // A size past the device's textures keeps the old cache: the
        // frame's own targets fail the same way, in wgpu, below.
        if let Err(err) = self.cached.resize((width, height)) {
            eprintln!("{err}");
        }
    }

    fn draw(&mut self) -> Result<(), Box<dyn Error>> {
        let texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(texture)
            | wgpu::CurrentSurfaceTexture::Suboptimal(texture) => texture,
            _ => {
                self.surface.configure(&self.gpu.device, &self.config);
                return Ok(());
            }
        };
        let view = texture
            .texture
            .create_view(&wgpu::TextureViewDescriptor::default());
        self.planet.update(&self.gpu.queue, self.frame);
        let mut encoder = self
            .gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        let clear = wgpu::Color {
            r: 0.02,
            g: 0.02,
            b: 0.03,
            a: 1.0,
        };
        if self.use_cache {
            let color = [Some(&view)];
            let targets = Targets {
                color: &color,
                clear: Some(clear),
                depth: None,
            };
            let (planet, twins) = (&self.planet, &self.twins);
            let draw = |draw: &mut shadecache_host::Draw<'_, '_>| {
                planet.draw_cached(draw, twins);
            };
            match self.timer.as_mut() {
                Some(timer) => self.cached.record_timed(
                    &self.gpu.queue,
                    &mut encoder,
                    &targets,
                    timer,
                    draw,
                )?,
                None => self
                    .cached
                    .record(&self.gpu.queue, &mut encoder, &targets, draw)?,
            }
        } else {
            draw_original(
                &mut encoder,
                (&self.original, &self.planet),
                (&view, &self.depth),
                clear,
                self.timer.as_mut(),
            );
        }
        if let Some(timer) = &self.timer {
            timer.resolve(&mut encoder);
        }
        self.gpu.queue.submit([encoder.finish()]);
        self.gpu.queue.present(texture);
        if let Some(timer) = self.timer.as_mut() {
            for time in timer.read(&self.gpu.device)? {
                match self.times.iter_mut().find(|(n, _, _)| *n == time.pass) {
                    Some((_, sum, count)) => {
                        *sum += time.milliseconds;
                        *count += 1;
                    }
                    None => self.times.push((time.pass, time.milliseconds, 1)),
                }
            }
        }
        self.frame += 1;
        if self.frame.is_multiple_of(120) {
            let passes: Vec<String> = self
                .times
                .drain(..)
                .map(|(name, sum, count)| format!("{name} {:.3}", sum / f64::from(count)))
                .collect();
            println!("GPU ms per frame: {}", passes.join(", "));
        }
        Ok(())
    }
}
