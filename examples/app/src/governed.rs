//! The app as it would ship: each frame the host crate's `Governor` says
//! whether to draw the original pipeline or the cached variant, and
//! `FrameTimer` gives it each frame's GPU time when the timestamps are
//! ready, without a wait. With an error budget (`CacheMode::Auto` with
//! `min_psnr`, the default), the frames the governor watches draw the
//! original as well, into the `ErrorWatch`'s spare target, and the watch
//! compares the two on the GPU; its answer, frames later, goes back to the
//! governor, which lowers Δn (`CachedShader::set_refresh_period`) or turns
//! the cache off. `CacheMode::Always` and `Off` run the same loop, one way
//! every frame. What it decided, and what the frames cost, is printed at
//! the end.

use std::error::Error;

use shadecache_host::{
    CacheMode, CachedShader, Cause, Choice, Coverage, ErrorWatch, FrameTimer, Governor, Targets,
    Twins,
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
    /// The watched frames' PSNRs, in dB.
    watched: Vec<f64>,
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

    /// The watch's answer, if it has come: to the governor, and kept.
    fn watch(
        &mut self,
        watch: Option<&mut ErrorWatch>,
        gpu: &Gpu,
        governor: &mut Governor,
    ) -> Result<(), Box<dyn Error>> {
        if let Some(answer) = watch.map(|w| w.ready(&gpu.device)).transpose()?.flatten() {
            governor.watched(answer.frame, answer.psnr);
            self.watched.push(answer.psnr);
        }
        Ok(())
    }
}

/// Plays `frames` frames in `mode`, at `size`.
pub fn run(
    gpu: &Gpu,
    (planet, original): (&Planet, &wgpu::RenderPipeline),
    (cached, twins): (&mut CachedShader, &Twins),
    (size, frames, mode): ((u32, u32), u32, CacheMode),
) -> Result<(), Box<dyn Error>> {
    // The passes a frame times: the variant's, the original a watched
    // frame draws too, and the watch's comparison.
    let passes = cached.plan().passes.len() as u32 + 2;
    let mut timer = FrameTimer::new(&gpu.device, &gpu.queue, passes, 3).ok_or(
        "the adapter has no timestamp queries, which the governor decides from: --compare draws both ways instead",
    )?;
    let mut governor = Governor::for_mode(mode, cached.plan())?;
    let mut watch = match mode {
        CacheMode::Auto {
            min_psnr: Some(_), ..
        } => Some(ErrorWatch::new(&gpu.device, size, COLOR_FORMAT)?),
        _ => None,
    };
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
                if cached.refresh_period() != next.period {
                    cached.set_refresh_period(next.period)?;
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
                let free = watch.as_ref().is_some_and(ErrorWatch::is_free);
                if next.watch && !free {
                    // Its last answer is still on the way: an ordinary
                    // cached frame, the next watch the next due.
                    governor.unwatched(next.frame);
                }
                if let Some(watch) = watch.as_mut().filter(|_| next.watch && free) {
                    // The original into the watch's spare target (the
                    // cache keeps its own depth, so the frame's depth
                    // target is free), then the comparison.
                    draw_original(
                        &mut encoder,
                        (original, planet),
                        (watch.spare_view(), &depth_view),
                        wgpu::Color::TRANSPARENT,
                        Some(&mut timer),
                    );
                    watch.compare(
                        &gpu.device,
                        (&gpu.queue, &mut encoder),
                        &mut timer,
                        next.frame,
                        &target,
                        Coverage::Cache(cached),
                    )?;
                }
            }
        }
        timer.resolve(&mut encoder);
        gpu.queue.submit([encoder.finish()]);
        drawn.take(timer.ready(&gpu.device)?, &mut governor);
        drawn.watch(watch.as_mut(), gpu, &mut governor)?;
    }
    gpu.device.poll(wgpu::PollType::wait_indefinitely())?;
    drawn.take(timer.ready(&gpu.device)?, &mut governor);
    drawn.watch(watch.as_mut(), gpu, &mut governor)?;
    print(&governor, &drawn, (frames, mode));
    Ok(())
}

fn print(governor: &Governor, drawn: &Drawn, (frames, mode): (u32, CacheMode)) {
    let mean = |times: &[f64]| {
        if times.is_empty() {
            0.0
        } else {
            times.iter().sum::<f64>() / times.len() as f64
        }
    };
    for decision in governor.decisions() {
        let state = if decision.on { "on" } else { "off" };
        match (decision.cause, decision.estimate) {
            (Cause::Error { psnr } | Cause::Margin { psnr }, _) => println!(
                "governor: from frame {}, cache {state}, Δn = {} (a watched frame at {psnr:.1} dB)",
                decision.frame, decision.period
            ),
            (Cause::Speed | Cause::Trial, Some(estimate)) => println!(
                "governor: from frame {}, cache {state} (speed-up {:.2}× [{:.2}, {:.2}])",
                decision.frame, estimate.speedup, estimate.interval[0], estimate.interval[1]
            ),
            (Cause::Speed | Cause::Trial, None) => {
                println!("governor: from frame {}, cache {state}", decision.frame)
            }
        }
    }
    if !drawn.watched.is_empty() {
        println!(
            "error watch: {} frames watched, lowest {:.1} dB; Δn = {} at the end",
            drawn.watched.len(),
            drawn.watched.iter().copied().fold(f64::INFINITY, f64::min),
            governor.period()
        );
    }
    match governor.estimate() {
        _ if !matches!(mode, CacheMode::Auto { .. }) => println!(
            "cache {} every frame ({mode:?}): nothing measured or decided",
            if governor.is_on() { "on" } else { "off" }
        ),
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
