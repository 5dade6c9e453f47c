//! The example game, headless.
//!
//! ```sh
//! # Each frame through the cache and as Bevy draws it, compared:
//! cargo run -p shadecache-bevy-example -- compare --size 256 --frames 60
//! # The same in linear HDR, PSNR as `shadecache profile` measures it:
//! cargo run -p shadecache-bevy-example -- compare --size 256 --frames 60 --linear
//! # The opaque meshes' GPU time, each material cached or as Bevy draws it:
//! cargo run --release -p shadecache-bevy-example -- measure --size 512 --frames 100
//! # In a window (space toggles the cache):
//! cargo run -p shadecache-bevy-example --features window -- window
//! ```

use shadecache_bevy_harness::{measure, run_headless, Cached, Headless, Masked, Measure};

#[cfg(feature = "window")]
mod window;

struct Args {
    size: u32,
    frames: u32,
    refresh_period: Option<u32>,
    step_degrees: f32,
    linear: bool,
}

fn main() {
    let mut args = std::env::args().skip(1);
    let mode = args
        .next()
        .unwrap_or_else(|| usage("give `compare` or `measure`"));
    let mut settings = Args {
        size: 256,
        frames: 60,
        refresh_period: None,
        step_degrees: 0.5,
        linear: false,
    };
    while let Some(arg) = args.next() {
        let mut value = |name: &str| -> f64 {
            args.next()
                .and_then(|v| v.parse().ok())
                .unwrap_or_else(|| usage(&format!("{name} takes a number")))
        };
        match arg.as_str() {
            "--size" => settings.size = value("--size") as u32,
            "--frames" => settings.frames = value("--frames") as u32,
            "--refresh-period" => settings.refresh_period = Some(value("--refresh-period") as u32),
            "--step" => settings.step_degrees = value("--step") as f32,
            "--linear" => settings.linear = true,
            other => usage(&format!("unknown argument `{other}`")),
        }
    }
    match mode.as_str() {
        "compare" => compare(settings),
        "measure" => time(settings),
        #[cfg(feature = "window")]
        "window" => window::run(),
        #[cfg(not(feature = "window"))]
        "window" => usage("the window needs the `window` feature: --features window"),
        other => usage(&format!("unknown mode `{other}`")),
    }
}

/// The game's scene (the lava, the props in `StandardMaterial`, a glass
/// pane), each frame through the cache and as Bevy draws it, with the lava
/// cached, the props cached, and both: the error each material's cache
/// makes, and both together.
fn compare(args: Args) {
    for cached in [Cached::Lava, Cached::StandardMaterial, Cached::Both] {
        println!("{}:", cached.name());
        compare_one(&args, cached);
    }
}

fn compare_one(args: &Args, cached: Cached) {
    let run = run_headless(Headless {
        size: args.size,
        frames: args.frames,
        refresh_period: args.refresh_period,
        step_degrees: args.step_degrees,
        standard_material: cached != Cached::Lava,
        lava_uncached: cached == Cached::StandardMaterial,
        props: true,
        masks: true,
        linear: args.linear,
        // Every frame through the cache, to compare each with Bevy's.
        mode: shadecache_bevy::CacheMode::Always,
        ..Headless::default()
    });
    for err in &run.errors {
        eprintln!("error: {err}");
    }
    for (n, frame) in run.compared.iter().enumerate() {
        println!(
            "  compared frame {n} (camera frame {}): {}², PSNR {:.2} dB, max error {:.4}, {} lava pixels",
            frame.frame, frame.size, frame.psnr, frame.max_error, frame.lava_pixels
        );
    }
    let steady = &run.compared[run.compared.len() / 2..];
    if steady.is_empty() {
        eprintln!("no frame was compared: Bevy's pipelines were not ready in time");
        std::process::exit(1);
    }
    let (mean, worst) = mean_and_worst(steady.iter().map(|f| Some(f.psnr)));
    println!(
        "  steady state (last {} frames): mean PSNR {mean:.2} dB (∞ counted as 99), worst {worst:.2} dB; {} frames drawn through the cache",
        steady.len(),
        run.frames_drawn
    );
    for material in Masked::ALL {
        let (mean, worst) = mean_and_worst(steady.iter().map(|f| f.psnr_over(material)));
        let name = material.name();
        if worst.is_infinite() {
            println!("    over {name}'s pixels only: Bevy's own in every frame");
        } else {
            println!("    over {name}'s pixels only: mean PSNR {mean:.2} dB, worst {worst:.2} dB");
        }
    }
}

/// The mean PSNR (∞ counted as 99) and the worst, of the frames that have
/// one.
fn mean_and_worst(psnr: impl Iterator<Item = Option<f64>>) -> (f64, f64) {
    let psnr: Vec<f64> = psnr.flatten().collect();
    let mean = psnr.iter().map(|p| p.min(99.0)).sum::<f64>() / psnr.len().max(1) as f64;
    let worst = psnr.iter().copied().fold(f64::INFINITY, f64::min);
    (mean, worst)
}

/// The opaque meshes' GPU time with nothing cached, each material cached
/// alone, and both: what each material's cache saves, and both together.
fn time(args: Args) {
    let mut medians = Vec::new();
    for cached in Cached::ALL {
        let run = measure(Measure {
            size: args.size,
            frames: args.frames,
            cached,
            step_degrees: args.step_degrees,
        });
        for err in &run.errors {
            eprintln!("error: {err}");
        }
        let label = cached.name();
        match run.median_and_interval() {
            Some((median, low, high)) => {
                let speedup = medians.first().map_or(String::new(), |nothing| {
                    format!(", {:.2}× against nothing cached", nothing / median)
                });
                let memory = match run.target_bytes {
                    0 => String::new(),
                    bytes => format!("; the caches own {:.2} MB", bytes as f64 / 1e6),
                };
                println!(
                    "{label}: opaque meshes {median:.3} ms GPU per frame [{low:.3}, {high:.3}] (median, 2.5–97.5th percentile, {} frames, {}²){speedup}{memory}",
                    run.material_ms.len(),
                    args.size
                );
                medians.push(median);
            }
            None => {
                eprintln!(
                    "{label}: no GPU time was recorded (does the device have timestamp queries?)"
                );
                std::process::exit(1);
            }
        }
    }
}

fn usage(problem: &str) -> ! {
    eprintln!(
        "{problem}\nusage: shadecache-bevy-example compare|measure|window [--size N] [--frames N] [--refresh-period N] [--step DEGREES] [--linear]"
    );
    std::process::exit(2);
}
