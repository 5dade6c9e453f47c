//! The app as it would ship: each frame the host crate's `Governor` says
//! whether to draw the original pipeline or the cached variant, and
//! `FrameTimer` gives it each frame's GPU time when the timestamps are
//! ready, without a wait. What it decided, and what the frames cost, is
//! printed at the end.

use std::error::Error;

use shadecache_host::{
    CachedShader, Choice, FrameTimer, Governor, GovernorSettings, Targets, Twins,
};

use crate::planet::Planet;
use crate::{draw_original, texture, Gpu, COLOR_FORMAT};

/// The frames drawn, by what was drawn.
#[derive(Default)]
struct Drawn {
    /// What each frame whose time is on its way drew.
    choices: std::collections::HashMap<u64, Choice>,
    original: Vec<f64>,
    cached: Vec<f64>,
    untimed: u32,
}

impl Drawn {
    /// The frames whose times arrived: to the governor, and kept by kind.
    fn take(&mut self, times: Vec<(u64, f64)>, governor: &mut Governor) {
        for (frame, ms) in times {
            governor.measured(frame, ms);
            match self.choices.remove(&frame) {
                Some(Choice::Original) => self.original.push(ms),
                Some(Choice::Cached { .. }) => self.cached.push(ms),
                None => {}
            }
        }
    }
}

/// Plays `frames` frames governed, at `size`.
pub fn run(
    gpu: &Gpu,
    (planet, original): (&Planet, &wgpu::RenderPipeline),
    (cached, twins): (&mut CachedShader, &Twins),
    size: (u32, u32),
    frames: u32,
) -> Result<(), Box<dyn Error>> {
    let mut timer = FrameTimer::new(&gpu.device, &gpu.queue, 4, 3).ok_or(
        "the adapter has no timestamp queries, which the governor decides from: --compare draws both ways instead",
    )?;
    let mut governor = Governor::new(GovernorSettings::for_plan(cached.plan()))?;
    let target = texture(&gpu.device, "frame", size, COLOR_FORMAT);
    let depth = texture(&gpu.device, "depth", size, crate::planet::DEPTH_FORMAT);
    let view = target.create_view(&wgpu::TextureViewDescriptor::default());
    let depth_view = depth.create_view(&wgpu::TextureViewDescriptor::default());
    let mut drawn = Drawn::default();
    for frame in 0..frames {
        planet.update(&gpu.queue, frame);
        let next = governor.next_frame();
        if timer.begin_frame(next.frame) {
            drawn.choices.insert(next.frame, next.choice);
        } else {
            drawn.untimed += 1;
        }
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        match next.choice {
            Choice::Original => draw_original(
                &mut encoder,
                (original, planet),
                (&view, &depth_view),
                wgpu::Color::TRANSPARENT,
                Some(&mut timer),
            ),
            Choice::Cached { reset } => {
                if reset {
                    cached.reset();
                }
                let color = [Some(&view)];
                let targets = Targets {
                    color: &color,
                    clear: Some(wgpu::Color::TRANSPARENT),
                    depth: None,
                };
                cached.record_timed(&gpu.queue, &mut encoder, &targets, &mut timer, |draw| {
                    planet.draw_cached(draw, twins)
                })?;
            }
        }
        timer.resolve(&mut encoder);
        gpu.queue.submit([encoder.finish()]);
        drawn.take(timer.ready(&gpu.device)?, &mut governor);
    }
    gpu.device.poll(wgpu::PollType::wait_indefinitely())?;
    drawn.take(timer.ready(&gpu.device)?, &mut governor);
    print(&governor, &drawn, frames);
    Ok(())
}

fn print(governor: &Governor, drawn: &Drawn, frames: u32) {
    let mean = |times: &[f64]| times.iter().sum::<f64>() / times.len().max(1) as f64;
    for decision in governor.decisions() {
        println!(
            "governor: from frame {}, cache {} (speed-up {:.2}× [{:.2}, {:.2}])",
            decision.frame,
            if decision.on { "on" } else { "off" },
            decision.estimate.speedup,
            decision.estimate.interval[0],
            decision.estimate.interval[1]
        );
    }
    match governor.estimate() {
        Some(estimate) => println!(
            "governor: cache {} after {frames} frames; speed-up {:.2}× [{:.2}, {:.2}]",
            if governor.is_on() { "on" } else { "off" },
            estimate.speedup,
            estimate.interval[0],
            estimate.interval[1]
        ),
        None => println!(
            "governor: cache {} after {frames} frames, too few to weigh (it needs a few hundred)",
            if governor.is_on() { "on" } else { "off" }
        ),
    }
    let all: Vec<f64> = drawn
        .original
        .iter()
        .chain(&drawn.cached)
        .copied()
        .collect();
    println!(
        "GPU ms per frame: {:.3} over {} timed frames ({} original at {:.3}, {} cached at {:.3}; {} untimed)",
        mean(&all),
        all.len(),
        drawn.original.len(),
        mean(&drawn.original),
        drawn.cached.len(),
        mean(&drawn.cached),
        drawn.untimed
    );
}
