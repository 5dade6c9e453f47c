//! `shadecache interpolate`: render I-frames and build the frames between
//! them with each whole-frame reuse method, measure their time and error
//! against rendering every frame, write a report.

use std::path::PathBuf;

use shadecache::diagnostic::{Color, Diagnostic, Error};
use shadecache::interpolate::{self, report, Method, Options};

use super::profile::{parse_size, Bar};

/// A `--method` value: `all`, or one method by its name
/// ([`Method::name`], the one list of them).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MethodArg {
    All,
    One(Method),
}

impl clap::ValueEnum for MethodArg {
    fn value_variants<'a>() -> &'a [Self] {
        static VARIANTS: std::sync::OnceLock<Vec<MethodArg>> = std::sync::OnceLock::new();
        VARIANTS.get_or_init(|| {
            std::iter::once(MethodArg::All)
                .chain(Method::ALL.map(MethodArg::One))
                .collect()
        })
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(match self {
            MethodArg::All => "all",
            MethodArg::One(method) => method.name(),
        }))
    }
}

impl MethodArg {
    fn methods(args: &[MethodArg]) -> Vec<Method> {
        let mut methods: Vec<Method> = args
            .iter()
            .flat_map(|arg| match arg {
                MethodArg::All => Method::ALL.to_vec(),
                MethodArg::One(method) => vec![*method],
            })
            .collect();
        methods.sort();
        methods.dedup();
        methods
    }
}

/// A `--blur-order` value ([`interpolate::BlurOrder`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BlurOrderArg {
    /// The rendered frame's low-pass warped with each in-between frame.
    WarpBlurred,
    /// Seed 004's: each morphed frame blurred.
    Paper,
}

impl From<BlurOrderArg> for interpolate::BlurOrder {
    fn from(order: BlurOrderArg) -> Self {
        match order {
            BlurOrderArg::WarpBlurred => interpolate::BlurOrder::WarpBlurred,
            BlurOrderArg::Paper => interpolate::BlurOrder::Paper,
        }
    }
}

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The WGSL shader to render.
    pub shader: PathBuf,

    /// The scene to render (TOML; see docs/scene-toml.md). Without one,
    /// the default scene `shadecache scene init` writes.
    #[arg(long, value_name = "SCENE.toml")]
    pub scene: Option<PathBuf>,

    /// Methods to run, separated by commas; the reference is rendered
    /// every frame whichever are named.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "all")]
    pub method: Vec<MethodArg>,

    /// n: displayed frames per I-frame interval (an I-frame and n − 1
    /// B-frames).
    #[arg(long, value_name = "N", default_value_t = 4, value_parser = clap::value_parser!(u32).range(2..=64))]
    pub frames_per_interval: u32,

    /// m: iterations of the image-based search.
    #[arg(long, value_name = "M", default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=32))]
    pub iterations: u32,

    /// ε1: the image-based search's largest residual, in pixels.
    #[arg(long, value_name = "PX", default_value_t = 1.0)]
    pub screen_epsilon: f32,

    /// ε2: the relative depth tolerance of the image-based visibility
    /// tests and of half-velocity's merge.
    #[arg(long, value_name = "E", default_value_t = shadecache::rewrite::DEFAULT_DEPTH_EPSILON, value_parser = super::rewrite::epsilon)]
    pub depth_epsilon: f32,

    /// Start the image-based search only from the pixel itself (no dual
    /// initialisation).
    #[arg(long)]
    pub no_dual_init: bool,

    /// Also start the image-based search from the previous B-frame's
    /// offsets (latest-frame initialisation, Yang et al. 2011 eqs. 18–19; off by
    /// default: measured worse and dearer on the bundled scenes, see
    /// docs/results-interpolation.md).
    #[arg(long)]
    pub latest_init: bool,

    /// Image-based as Yang et al. 2011 states it: dual and latest-frame
    /// initialisation, and of two converged starts the smaller residual
    /// (the defaults keep the nearer surface, and leave latest-frame
    /// initialisation off: see docs/results-interpolation.md).
    #[arg(long, conflicts_with_all = ["no_dual_init", "latest_init"])]
    pub paper: bool,

    /// Latest-frame initialisation's neighbourhood: the pixel and its four
    /// diagonal neighbours this many pixels away, of which the nearest
    /// surface's offsets start the search.
    #[arg(long, value_name = "PX", default_value_t = 1)]
    pub latest_radius: u32,

    /// Half-velocity with the later frame's velocity alone (no merging of
    /// the earlier frame's into the tails).
    #[arg(long)]
    pub no_velocity_merge: bool,

    /// Half-velocity's direction test: the cosine below which a tail's
    /// velocity is dropped.
    #[arg(
        long,
        value_name = "C",
        default_value_t = 0.5,
        allow_negative_numbers = true,
        value_parser = cosine
    )]
    pub min_cosine: f32,

    /// Half-velocity without its moving-object handling (Andreev 2010 slides
    /// 33–47): the objects that move are then not drawn at each B-frame's
    /// time for their exact offsets, nor wiped out of the earlier frame
    /// where they have left.
    #[arg(long)]
    pub no_moving_objects: bool,

    /// Character removal's passes: each fills the masked pixels next to
    /// unmasked ones.
    #[arg(long, value_name = "N", default_value_t = 3)]
    pub inpaint_passes: u32,

    /// Character removal's neighbour distance, in pixels.
    #[arg(long, value_name = "PX", default_value_t = 2)]
    pub inpaint_delta: u32,

    /// Also average each method's frames around every I-frame into a
    /// motion-blurred frame (Yang et al. 2011 §9) and compare it with the
    /// reference's; use with a large n (the paper: 10).
    #[arg(long)]
    pub motion_blur: bool,

    /// The morph's grid spacing in pixels (Didyk et al. 2010: 8): a power of two
    /// that divides the frame's width and height.
    #[arg(long, value_name = "PX", default_value_t = 8)]
    pub grid: u32,

    /// The morph on its regular grid: no snapping of the vertices to the
    /// motion's discontinuities.
    #[arg(long)]
    pub no_snap: bool,

    /// The least motion gradient a morph vertex snaps to, in pixels of
    /// flow per pixel.
    #[arg(long, value_name = "PX", default_value_t = 1.0)]
    pub snap_threshold: f32,

    /// The morph's low-pass: the pyramid level it reads (each level
    /// halves the frame).
    #[arg(long, value_name = "L", default_value_t = 2)]
    pub blur_level: u32,

    /// The display's gamma, under which the morph's compensation
    /// conserves light.
    #[arg(long, value_name = "G", default_value_t = 2.2)]
    pub gamma: f32,

    /// The display's refresh rate in Hz; the rendered rate is this over
    /// n (120 at n = 3: the paper's 40 → 120 Hz).
    #[arg(long, value_name = "HZ", default_value_t = 120.0)]
    pub display_hz: f32,

    /// The display's pixels per degree of visual angle.
    #[arg(long, value_name = "PPD", default_value_t = 37.0)]
    pub pixels_per_degree: f32,

    /// The eye-tracking damping's ramp, deg/s: full tracking below the
    /// first, none above the second (`--tracking 70,90`).
    #[arg(long, value_name = "FROM,TO", value_delimiter = ',', num_args = 1, default_values_t = [70.0, 90.0])]
    pub tracking: Vec<f32>,

    /// A gate by speed: the morph blurs and compensates only where the
    /// motion is at least this fast, deg/s (given without a value: 0.15,
    /// below which drift eye movement interferes with smooth pursuit). Not the
    /// paper's selective blur, which gates by luminance and range.
    #[arg(long, value_name = "DEG_PER_S", num_args = 0..=1, default_missing_value = "0.15")]
    pub blur_min_speed: Option<f32>,

    /// Where the morph's in-between frames get their blur: `warp-blurred`
    /// warps the rendered frame's low-pass with each (one pass a frame);
    /// `paper` morphs each frame sharp and then blurs it, as seed 004
    /// does (the pyramid again per frame).
    #[arg(long, value_enum, default_value = "warp-blurred")]
    pub blur_order: BlurOrderArg,

    /// The grid distortion mapped to full blur: a smooth step between the
    /// two (`--distortion-blur 0.25,1`).
    #[arg(long, value_name = "FROM,TO", value_delimiter = ',', num_args = 1, default_values_t = [0.25, 1.0])]
    pub distortion_blur: Vec<f32>,

    /// Sub-steps per displayed frame of the pursuit integral.
    #[arg(long, value_name = "S", default_value_t = 8)]
    pub pursuit_substeps: u32,

    /// The node `payload` interpolates (an id from `shadecache analyze`);
    /// by default the highest-ranked candidate that reads no per-frame
    /// input (light, camera, time), which the report's notes name.
    #[arg(long, alias = "nodes", value_name = "ID")]
    pub node: Option<String>,

    /// Partitioned rendering (Yang et al. 2011 §7): draw each I-frame in n parts
    /// of about equal measured cost, one per displayed frame, so that
    /// every displayed frame costs about the same (at n − 1 frames of
    /// added latency).
    #[arg(long)]
    pub partition: bool,

    /// Frame size (default: the scene's).
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<[u32; 2]>,

    /// Displayed frames to measure, rounded up to whole intervals
    /// (default: the scene's frames).
    #[arg(long, value_name = "N", value_parser = super::profile::frame_count)]
    pub frames: Option<u32>,

    /// Where to write report.json, report.html and the pictures.
    #[arg(long, value_name = "DIR", default_value = "shadecache-interpolation")]
    pub out: PathBuf,

    /// Write into an --out folder that holds files a previous run did not
    /// list as its own (they stay; files of the same names are replaced).
    /// Without it, such a folder is refused before anything runs.
    #[arg(long)]
    pub overwrite: bool,

    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,

    #[command(flatten)]
    pub stages: super::StageArgs,
}

pub fn exec(args: Args, color: Color) -> Result<(), Error> {
    let out = crate::out_folder::OutFolder::check(&args.out, args.overwrite)?;
    out.run(|out| interpolate_into(&args, color, out))
}

/// The run, and its report written into `out`.
fn interpolate_into(
    args: &Args,
    _color: Color,
    out: &crate::out_folder::OutFolder,
) -> Result<(), Error> {
    if !(args.screen_epsilon > 0.0 && args.screen_epsilon.is_finite()) {
        return Err(Error::plain(Diagnostic::error(format!(
            "--screen-epsilon must be a positive number of pixels, not {}",
            args.screen_epsilon
        ))));
    }
    let shader = args.stages.load(&args.shader)?;
    // With no scene, the default one with a game's motion: the profile's
    // barely moves, and every method would tie with sample-and-hold.
    let (shader, scene, scene_path) = args.stages.drawn(shader, args.scene.as_deref(), true)?;
    let options = Options {
        methods: MethodArg::methods(&args.method),
        frames_per_interval: args.frames_per_interval,
        iterations: args.iterations,
        screen_epsilon: args.screen_epsilon,
        depth_epsilon: args.depth_epsilon,
        dual_init: !args.no_dual_init,
        smaller_residual: args.paper,
        latest_frame_init: args.latest_init || args.paper,
        latest_radius: args.latest_radius,
        motion_blur: args.motion_blur,
        velocity_merge: !args.no_velocity_merge,
        min_cosine: args.min_cosine,
        moving_objects: !args.no_moving_objects,
        inpaint_passes: args.inpaint_passes,
        inpaint_delta: args.inpaint_delta,
        grid: args.grid,
        snap: !args.no_snap,
        snap_threshold: args.snap_threshold,
        blur_level: args.blur_level,
        gamma: args.gamma,
        display_hz: args.display_hz,
        pixels_per_degree: args.pixels_per_degree,
        tracking: pair(&args.tracking),
        blur_min_speed: args.blur_min_speed,
        blur_order: args.blur_order.into(),
        distortion_blur: pair(&args.distortion_blur),
        pursuit_substeps: args.pursuit_substeps,
        size: args.size,
        frames: args.frames,
        entry: args.stages.entry.clone(),
        vertex_entry: args.stages.vertex_entry.clone(),
        payload_node: args.node.clone(),
        partition: args.partition,
        ..Options::default()
    };
    if !options.methods.contains(&interpolate::Method::Payload) && args.node.is_some() {
        super::rewrite::note_unused(
            &["--node"],
            "it names the node `payload` interpolates, and --method does not ask for payload",
        );
    }
    let mut bar = Bar {
        bar: None,
        quiet: args.quiet,
    };
    let (report, pictures) =
        interpolate::interpolate(&shader, &scene, &scene_path, &options, &mut bar)?;

    out.clear()?;
    super::write_report(
        &args.out,
        &report,
        || report::write_images(&args.out, &report, &pictures),
        || report::html(&report),
    )?;

    let mut summary = format!(
        "{} on {} ({}×{}, n = {}, {} interval(s) measured, {}, {}): reference {:.3} ms, I-frame with flows {:.3} ms\n",
        report.shader,
        report.scene,
        report.size[0],
        report.size[1],
        report.frames_per_interval,
        report.intervals,
        report.adapter,
        report.driver,
        report.reference_ms,
        report.i_frame_ms
    );
    if !report.scene_description.is_empty() {
        summary.push_str(&format!("  scene: {}\n", report.scene_description));
    }
    for m in &report.methods {
        summary.push_str(&format!(
            "  {:<16} amortised {:.2}× (I-frame {:.2}×, B-frame {:.3}×), B-frames SSIM {:.4} (worst {:.4}), PSNR {:.1} dB{}\n",
            m.method.name(),
            m.amortized_time_ratio,
            m.i_frame_time_ratio,
            m.b_frame_time_ratio,
            m.ssim_mean,
            m.ssim_min,
            m.psnr_mean,
            m.double_miss_rate
                .map_or(String::new(), |r| format!(", double misses {:.2}%", r * 100.0))
        ));
        if let Some(error) = &m.correspondence_error_px {
            summary.push_str(&format!(
                "                   correspondences {:.3} px from the exact ones ({:.3} px where I-frame 0 shows the point)\n",
                error.all, error.hit
            ));
            if let Some(used) = &error.used {
                summary.push_str(&format!(
                    "                   the correspondences used (either direction) {:.3} px from the exact ones (95th percentile {:.3} px; silhouettes {:.3}, interiors {:.3})\n",
                    used.mean, used.p95, used.silhouette_mean, used.interior_mean
                ));
            }
            if let Some(linear) = &error.linear {
                summary.push_str(&format!(
                    "                   linear motion {:.3} px from the exact points (95th percentile {:.3} px; silhouettes {:.3}, interiors {:.3})\n",
                    linear.mean, linear.p95, linear.silhouette_mean, linear.interior_mean
                ));
            }
        }
        let frames = &m.displayed_frame_ms;
        summary.push_str(&format!(
            "                   displayed frames {:.3} ms median, {:.3} ms slowest (spread {:.2}×{})\n",
            frames.median,
            frames.max,
            frames.spread,
            if frames.partitioned { ", I-frames in parts" } else { "" }
        ));
        if let Some(error) = m.pursuit_error {
            summary.push_str(&format!(
                "                   pursuit error {error:.4}{}, {} frame(s) of added latency{}\n",
                m.flicker
                    .map_or(String::new(), |f| format!(", flicker {f:.4}")),
                m.added_latency_frames,
                m.displayed_i_frame_psnr
                    .map_or(String::new(), |psnr| format!(
                        ", its I-frame displayed compensated at {psnr:.1} dB"
                    ))
            ));
        }
        if let Some(psnr) = m.edge_psnr {
            summary.push_str(&format!(
                "                   PSNR {psnr:.1} dB within {} px of a motion edge\n",
                interpolate::edges::EDGE_RADIUS_PX
            ));
        }
        if let Some(ratio) = m.extrapolated_frame_ratio {
            let verdict = if ratio < 1.0 {
                "breaks even (seed 004's test: below 1)"
            } else {
                "does not break even (seed 004's test: below 1)"
            };
            summary.push_str(&format!(
                "                   an extrapolated frame with its share of the preparation is {ratio:.3} of a rendered frame: {verdict}; the project's target is 0.25\n"
            ));
        }
        if let (Some(ssim), Some(psnr)) = (m.motion_blur_ssim, m.motion_blur_psnr) {
            summary.push_str(&format!(
                "                   motion blur around each I-frame: SSIM {ssim:.4}, PSNR {psnr:.1} dB\n"
            ));
        }
    }
    for note in &report.notes {
        summary.push_str(&format!("  note: {note}\n"));
    }
    summary.push_str(&format!("  answer: {}\n", report.answer));
    summary.push_str(&format!(
        "report: {}\n",
        args.out.join("report.html").display()
    ));
    super::write_stdout(&summary)
}

/// Two values clap has already counted (NaN, which the run refuses, for
/// a missing one).
/// Two values given as FROM,TO; anything but two is [NaN, NaN], which
/// the run's checks refuse, naming the flag.
fn pair(values: &[f32]) -> [f32; 2] {
    match values {
        &[from, to] => [from, to],
        _ => [f32::NAN; 2],
    }
}

/// A cosine: a number from −1 to 1.
fn cosine(text: &str) -> Result<f32, String> {
    match text.trim().parse::<f32>() {
        Ok(c) if (-1.0..=1.0).contains(&c) => Ok(c),
        _ => Err("a cosine is a number from -1 to 1".into()),
    }
}
