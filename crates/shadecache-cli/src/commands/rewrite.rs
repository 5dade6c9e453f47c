//! `shadecache rewrite`: write reprojection-cache variants of a shader.

use std::path::PathBuf;

use clap::ValueEnum;
use shadecache::analysis::{self, Options as AnalysisOptions};
use shadecache::back::{self, Language};
use shadecache::diagnostic::{self, Color, Diagnostic, Error, Severity};
use shadecache::rewrite::{
    self, CacheFormat, CacheRead, DepthConvention, Options, Reconstruction, Upsampler, Variant,
};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The WGSL shader to rewrite.
    pub shader: PathBuf,

    /// The node to cache (an id from `shadecache analyze`).
    #[arg(
        long,
        value_name = "ID",
        required_unless_present = "all_nodes",
        conflicts_with = "all_nodes"
    )]
    pub node: Option<String>,

    /// Rewrite every candidate node, each into DIR/<node-id>/<variant>/.
    #[arg(long)]
    pub all_nodes: bool,

    /// Which variants to write, separated by commas.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "all")]
    pub variant: Vec<VariantArg>,

    /// Δn: every pixel is recomputed at least once every N frames.
    #[arg(long, value_name = "N", default_value_t = 32, value_parser = clap::value_parser!(u32).range(1..=shadecache::rewrite::MAX_REFRESH_PERIOD as i64))]
    pub refresh_period: u32,

    /// k: refresh decisions are made per K×K block of pixels.
    #[arg(long, value_name = "K", default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..))]
    pub refresh_quad: u32,

    /// Texture format of the payload cache.
    #[arg(long, value_enum, default_value_t = CacheFormatArg::Rgba16float)]
    pub cache_format: CacheFormatArg,

    /// ε of the cache's depth test, relative: about the share of a point's
    /// distance by which two surfaces must differ to be told apart.
    #[arg(long, value_name = "E", default_value_t = rewrite::DEFAULT_DEPTH_EPSILON, value_parser = epsilon)]
    pub depth_epsilon: f32,

    /// Which way the host's depth buffer runs: standard (near 0, far 1) or
    /// reversed (near 1, far 0).
    #[arg(long, value_enum, default_value_t = DepthArg::Standard)]
    pub depth: DepthArg,

    /// How payload and depth are read back where a point was last frame:
    /// bilinear or nearest from the payload and last frame's depth buffer,
    /// or their packed forms, which keep the depth in the payload's fourth
    /// channel (payloads of up to three components). For lowres, how the
    /// payload is rebuilt from its samples: nearest, bilinear, spatial,
    /// temporal or spatio-temporal. Default: bilinear, and spatio-temporal
    /// for lowres.
    #[arg(long, value_enum)]
    pub reconstruction: Option<ReconstructionArg>,

    #[command(flatten)]
    pub upsampling: UpsamplingArgs,

    /// Adaptive refresh for the cache variants: a value that changed by 10%
    /// or more since it was cached is refreshed again after Δn/4 frames
    /// (lowres's is --reshade-unreliable).
    #[arg(long)]
    pub adaptive_refresh: bool,

    /// The bind groups the host's device has: the cache takes the first
    /// group the shader leaves free, and shares the last with a shader
    /// that uses them all. Bevy binds four of its own, so its materials
    /// want 5 or more (every Vulkan, Metal and D3D12 device has 8).
    #[arg(long, default_value_t = shadecache::rewrite::DEFAULT_MAX_BIND_GROUPS, value_parser = clap::value_parser!(u32).range(1..))]
    pub max_bind_groups: u32,

    /// Per-vertex inputs (by name, separated by commas) that the
    /// application changes every frame, deforming the mesh on the CPU:
    /// the position gets last frame's value of each from a twin of its
    /// vertex buffer. Inputs skinned on the GPU need none.
    #[arg(long, value_name = "NAME", value_delimiter = ',')]
    pub deforming_input: Vec<String>,

    /// Output language (WGSL is what shadecache validates and runs).
    #[arg(long, value_enum, default_value_t = EmitArg::Wgsl)]
    pub emit: EmitArg,

    #[command(flatten)]
    pub stages: super::StageArgs,

    /// Where to write the shaders and plan.json.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,

    /// Write into an --out folder that holds files a previous run did not
    /// list as its own (they stay; files of the same names are replaced).
    /// Without it, such a folder is refused before anything runs.
    #[arg(long)]
    pub overwrite: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum VariantArg {
    OnePass,
    TwoPass,
    ThreePass,
    /// One geometry pass into a G-buffer; lookup, misses and shading in
    /// screen space.
    Deferred,
    /// The payload shaded at 1/s × 1/s of the pixels on a jittered
    /// lattice, rebuilt at full resolution from the samples and the
    /// reprojected history (Herzog et al. 2010).
    Lowres,
    /// Lowres as the paper runs it: one geometry pass into a G-buffer,
    /// the samples shaded from it at 1/s × 1/s and the upsampling in
    /// screen space.
    DeferredLowres,
    All,
}

/// The lowres variant's knobs (Herzog et al. 2010); the paper's values by default.
#[derive(Clone, Debug, clap::Args)]
pub struct UpsamplingArgs {
    /// s: lowres shades one pixel of each S×S window per frame (2 or 4)
    /// [default: 4].
    #[arg(long, value_name = "S")]
    pub upsample_factor: Option<u32>,
    /// σn of lowres's normal weight (eq. 2 of Herzog et al. 2010)
    /// [default: 0.2].
    #[arg(long, value_name = "SIGMA")]
    pub sigma_normal: Option<f32>,
    /// σz of lowres's depth weight, relative to the depth [default: 0.03].
    #[arg(long, value_name = "SIGMA")]
    pub sigma_depth: Option<f32>,
    /// a: how much lowres's history weighs where the scene is unchanged
    /// (eq. 8), in (0, 1] [default: 1].
    #[arg(long, value_name = "A")]
    pub sensitivity: Option<f32>,
    /// Adaptive refresh for lowres: shade at full resolution, in a third
    /// pass, the pixels its upsampling cannot vouch for (disoccluded or
    /// changed, undersampled, not sampled this frame).
    #[arg(long)]
    pub reshade_unreliable: bool,
    /// Lowres's samples read textures log2 S mip levels coarser than the
    /// full resolution does (no LOD bias in the samples pass): to measure
    /// what the bias gives.
    #[arg(long)]
    pub no_lod_bias: bool,
    /// How lowres filters the temporal gradient over the samples around a
    /// pixel: `ours` averages the signed gradients weighted by geometry,
    /// `paper` the absolute ones blind to geometry (§3.5.1)
    /// [default: ours].
    #[arg(long, value_enum, value_name = "FILTER")]
    pub gradient_filter: Option<GradientFilterArg>,
    /// Lowres's temporal reconstruction shades every hole (a pixel its
    /// history misses and this frame did not shade) at full resolution in
    /// a third pass: the paper's temporal baseline, with hole filling.
    #[arg(long)]
    pub fill_holes: bool,
    /// What lowres's σz is a share of: `depth`, the pixel's view depth
    /// (ours), or `range`, the camera's far − near (the paper's; where the
    /// far plane is infinite, of the depth) [default: depth].
    #[arg(long, value_enum, value_name = "OF")]
    pub depth_tolerance: Option<DepthToleranceArg>,
    /// Lowres's history misses where the draw at the point last frame was
    /// another (the paper's material ids, for contact points: two
    /// surfaces meeting at one depth); without it, depth alone decides.
    /// Draws are told apart by their order in the pass, which must then
    /// stay the same from frame to frame.
    #[arg(long)]
    pub material_ids: bool,
    /// Lowres as the paper runs it, where ours differs and is a knob:
    /// `--gradient-filter paper --fill-holes --depth-tolerance range
    /// --material-ids`.
    #[arg(long, conflicts_with_all = ["gradient_filter", "depth_tolerance"])]
    pub paper: bool,
}

/// Why lowres's knobs were given for nothing.
pub const LOWRES_KNOBS_UNUSED: &str =
    "lowres's knobs, and --variant asks for neither lowres nor deferred-lowres";

/// A `--depth-tolerance` value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum DepthToleranceArg {
    Depth,
    Range,
}

/// A `--gradient-filter` value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum GradientFilterArg {
    Ours,
    Paper,
}

impl UpsamplingArgs {
    /// The knobs, checked: a clear error for a value lowres does not take.
    pub fn upsampling(&self) -> Result<rewrite::Upsampling, Error> {
        let default = rewrite::DEFAULT_UPSAMPLING;
        let upsampling = rewrite::Upsampling {
            factor: self.upsample_factor.unwrap_or(default.factor),
            sigma_normal: self.sigma_normal.unwrap_or(default.sigma_normal),
            sigma_depth: self.sigma_depth.unwrap_or(default.sigma_depth),
            sensitivity: self.sensitivity.unwrap_or(default.sensitivity),
            reshade: self.reshade_unreliable,
            lod_bias: !self.no_lod_bias,
            gradient_filter: match self.gradient_filter {
                Some(GradientFilterArg::Paper) => rewrite::GradientFilter::Paper,
                Some(GradientFilterArg::Ours) | None => rewrite::GradientFilter::Ours,
            },
            fill_holes: self.fill_holes,
            material_ids: self.material_ids,
            depth_tolerance: match self.depth_tolerance {
                Some(DepthToleranceArg::Range) => rewrite::DepthTolerance::OfRange,
                Some(DepthToleranceArg::Depth) | None => rewrite::DepthTolerance::OfDepth,
            },
            ..default
        };
        let upsampling = if self.paper {
            upsampling.as_the_paper()
        } else {
            upsampling
        };
        upsampling
            .check()
            .map_err(|err| Error::plain(Diagnostic::error(err)))?;
        Ok(upsampling)
    }

    /// The lowres flags given on the command line.
    pub fn given(&self) -> Vec<&'static str> {
        [
            ("--upsample-factor", self.upsample_factor.is_some()),
            ("--sigma-normal", self.sigma_normal.is_some()),
            ("--sigma-depth", self.sigma_depth.is_some()),
            ("--sensitivity", self.sensitivity.is_some()),
            ("--reshade-unreliable", self.reshade_unreliable),
            ("--no-lod-bias", self.no_lod_bias),
            ("--gradient-filter", self.gradient_filter.is_some()),
            ("--fill-holes", self.fill_holes),
            ("--depth-tolerance", self.depth_tolerance.is_some()),
            ("--material-ids", self.material_ids),
            ("--paper", self.paper),
        ]
        .into_iter()
        .filter_map(|(flag, given)| given.then_some(flag))
        .collect()
    }
}

/// The variants `--variant` names.
fn variants_asked(args: &Args) -> Vec<Variant> {
    VariantArg::variants(&args.variant)
}

/// One note for the flags given that do nothing for what was asked
/// (`why`), so that a knob is never silently ignored.
pub fn note_unused(flags: &[&str], why: &str) {
    if !flags.is_empty() {
        eprintln!("note: ignored {}: {why}", flags.join(", "));
    }
}

impl VariantArg {
    /// The variants a `--variant` list names, each once, in its order.
    pub fn variants(list: &[VariantArg]) -> Vec<Variant> {
        let mut out: Vec<Variant> = Vec::new();
        for arg in list {
            // Each variant's argument is spelled as its name.
            let named: Vec<Variant> = match arg {
                VariantArg::All => Variant::ALL.to_vec(),
                one => Variant::ALL
                    .into_iter()
                    .filter(|variant| {
                        one.to_possible_value()
                            .is_some_and(|v| v.get_name() == variant.as_str())
                    })
                    .collect(),
            };
            for variant in named {
                if !out.contains(&variant) {
                    out.push(variant);
                }
            }
        }
        out
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CacheFormatArg {
    Rgba16float,
    Rgba32float,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum DepthArg {
    Standard,
    Reversed,
}

/// ε of the depth test: 0 ≤ ε < 1 (at 1 a depth at the far plane, the
/// "no previous frame" value, would agree with everything).
pub fn epsilon(text: &str) -> Result<f32, String> {
    let value: f32 = text.parse().map_err(|err| format!("{err}"))?;
    if (0.0..1.0).contains(&value) {
        Ok(value)
    } else {
        Err("ε must be at least 0 and below 1".into())
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ReconstructionArg {
    Bilinear,
    Nearest,
    BilinearPacked,
    NearestPacked,
    Spatial,
    Temporal,
    SpatioTemporal,
}

impl From<ReconstructionArg> for Reconstruction {
    fn from(arg: ReconstructionArg) -> Reconstruction {
        match arg {
            ReconstructionArg::Bilinear => Reconstruction::Bilinear,
            ReconstructionArg::Nearest => Reconstruction::Nearest,
            ReconstructionArg::BilinearPacked => Reconstruction::BilinearPacked,
            ReconstructionArg::NearestPacked => Reconstruction::NearestPacked,
            ReconstructionArg::Spatial => Reconstruction::Spatial,
            ReconstructionArg::Temporal => Reconstruction::Temporal,
            ReconstructionArg::SpatioTemporal => Reconstruction::SpatioTemporal,
        }
    }
}

/// The profiler's cache reads (`profile --reconstruction`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CacheReadArg {
    Bilinear,
    Nearest,
    BilinearPacked,
    NearestPacked,
}

impl From<CacheReadArg> for CacheRead {
    fn from(arg: CacheReadArg) -> CacheRead {
        match arg {
            CacheReadArg::Bilinear => CacheRead::Bilinear,
            CacheReadArg::Nearest => CacheRead::Nearest,
            CacheReadArg::BilinearPacked => CacheRead::BilinearPacked,
            CacheReadArg::NearestPacked => CacheRead::NearestPacked,
        }
    }
}

impl CacheReadArg {
    /// Parses one of `profile --reconstruction`'s values; one of lowres's
    /// upsamplers is an error pointing at `--lowres-reconstruction`.
    pub fn parse(text: &str) -> Result<CacheReadArg, String> {
        use clap::ValueEnum;
        CacheReadArg::from_str(text, false).map_err(|_| {
            match UpsamplerArg::from_str(text, false) {
                Ok(_) => format!(
                    "`{text}` is how lowres rebuilds its samples: --lowres-reconstruction {text}; --reconstruction is the cache variants' read-back (bilinear, nearest, bilinear-packed, nearest-packed)"
                ),
                Err(_) => format!(
                    "`{text}` is not a read-back: bilinear, nearest, bilinear-packed or nearest-packed"
                ),
            }
        })
    }
}

/// Lowres's upsamplers (`profile --lowres-reconstruction`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum UpsamplerArg {
    Nearest,
    Bilinear,
    Spatial,
    Temporal,
    SpatioTemporal,
}

impl From<UpsamplerArg> for Upsampler {
    fn from(arg: UpsamplerArg) -> Upsampler {
        match arg {
            UpsamplerArg::Nearest => Upsampler::Nearest,
            UpsamplerArg::Bilinear => Upsampler::Bilinear,
            UpsamplerArg::Spatial => Upsampler::Spatial,
            UpsamplerArg::Temporal => Upsampler::Temporal,
            UpsamplerArg::SpatioTemporal => Upsampler::SpatioTemporal,
        }
    }
}

impl From<CacheFormatArg> for CacheFormat {
    fn from(arg: CacheFormatArg) -> CacheFormat {
        match arg {
            CacheFormatArg::Rgba16float => CacheFormat::Rgba16float,
            CacheFormatArg::Rgba32float => CacheFormat::Rgba32float,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum EmitArg {
    Wgsl,
    Spv,
    Glsl,
    Msl,
    Hlsl,
}

pub fn exec(args: Args, color: Color) -> Result<(), Error> {
    let out = crate::out_folder::OutFolder::check(&args.out, args.overwrite)?;
    out.run(|out| rewrite_into(&args, color, out))
}

/// The rewrite, written into `out` once every entry point checks.
fn rewrite_into(
    args: &Args,
    color: Color,
    out: &crate::out_folder::OutFolder,
) -> Result<(), Error> {
    let shader = args.stages.load_for_plans(&args.shader)?;
    // Every fragment entry point in turn (into `OUT/<entry>`), unless
    // `--entry` names one; with `--node`, the one that has the node.
    let mut analyses = analysis::analyze_entries(
        &shader,
        &AnalysisOptions {
            entry: args.stages.entry.clone(),
            ..AnalysisOptions::default()
        },
    )?;
    if let Some(id) = &args.node {
        if analyses.len() > 1
            && analyses
                .iter()
                .any(|a| a.candidates.iter().any(|c| &c.node.id == id))
        {
            analyses.retain(|a| a.candidates.iter().any(|c| &c.node.id == id));
        }
    }
    let several = analyses.len() > 1;
    for analysis in &analyses {
        if let Some(name) = &args.stages.vertex_entry {
            analysis.check_vertex_entry(&shader, name)?;
        }
        rewrite::check_entry_point(&shader, analysis)?;
    }
    let mut totals = Totals::default();
    out.clear()?;
    for analysis in &analyses {
        if several && analysis.candidates.is_empty() {
            diagnostic::emit_to_stderr(
                None,
                &Diagnostic::new(
                    Severity::Note,
                    format!("entry point `{}` has no cache candidates", analysis.entry),
                ),
                color,
            );
            continue;
        }
        let out = if several {
            args.out.join(&analysis.entry)
        } else {
            args.out.clone()
        };
        rewrite_entry(args, &shader, analysis, &out, color, &mut totals)?;
    }
    let Totals {
        written,
        refused,
        internal,
    } = totals;
    super::write_stdout(&format!(
        "wrote {written} variant{} to {}, refused {refused}\n",
        if written == 1 { "" } else { "s" },
        args.out.display()
    ))?;
    if internal > 0 {
        return Err(Error::internal(Diagnostic::error(format!(
            "{internal} variant{} failed inside the rewrite (see the warnings above): this is a bug in shadecache, please report it with the shader",
            if internal == 1 { "" } else { "s" }
        ))));
    }
    if refused > 0 && args.node.is_some() {
        return Err(Error::plain(Diagnostic::error(format!(
            "{refused} variant{} of node {} refused",
            if refused == 1 { "" } else { "s" },
            args.node.as_deref().unwrap_or_default()
        ))));
    }
    Ok(())
}

/// Variants written, refused, and refused by a failure inside the rewrite.
#[derive(Default)]
struct Totals {
    written: usize,
    refused: usize,
    internal: usize,
}

/// Writes the variants of one fragment entry point's nodes into `out`.
fn rewrite_entry(
    args: &Args,
    shader: &shadecache::front::Shader,
    analysis: &analysis::Analysis,
    out: &std::path::Path,
    color: Color,
    totals: &mut Totals,
) -> Result<(), Error> {
    let options = Options {
        refresh_period: args.refresh_period,
        refresh_quad: args.refresh_quad,
        cache_format: args.cache_format.into(),
        depth_epsilon: args.depth_epsilon,
        depth: match args.depth {
            DepthArg::Standard => DepthConvention::Standard,
            DepthArg::Reversed => DepthConvention::Reversed,
        },
        vertex_entry: args.stages.vertex_entry.clone(),
        deforming_inputs: args.deforming_input.clone(),
        upsampling: args.upsampling.upsampling()?,
        adaptive_refresh: args.adaptive_refresh,
        max_bind_groups: args.max_bind_groups,
        ..Options::default()
    };
    // A reconstruction named is lowres's upsampling for lowres, the
    // cache's read-back for the others.
    let options_for = |variant: Variant| {
        let mut options = options.clone();
        if let Some(reconstruction) = args.reconstruction.map(Reconstruction::from) {
            options.set_reconstruction(variant, reconstruction)?;
        }
        Ok(options)
    };
    if !variants_asked(args).iter().any(|v| v.upsamples()) {
        note_unused(&args.upsampling.given(), LOWRES_KNOBS_UNUSED);
    }
    let language = match args.emit {
        EmitArg::Wgsl => Language::Wgsl,
        EmitArg::Spv => Language::Spv,
        EmitArg::Glsl => Language::Glsl,
        EmitArg::Msl => Language::Msl,
        EmitArg::Hlsl => Language::Hlsl,
    };
    let variants = VariantArg::variants(&args.variant);

    let nodes = analysis.select(
        &shader.file,
        &match &args.node {
            Some(id) => analysis::Nodes::Ids(vec![id.clone()]),
            None => analysis::Nodes::All,
        },
    )?;
    for candidate in &nodes {
        for &variant in &variants {
            let dir = match (args.all_nodes, variants.len()) {
                (true, _) => out.join(&candidate.node.id).join(variant.as_str()),
                (false, 1) => out.to_path_buf(),
                (false, _) => out.join(variant.as_str()),
            };
            let rewritten = options_for(variant).and_then(|options| {
                rewrite::rewrite(shader, analysis, candidate, variant, &options)
            });
            match rewritten {
                Ok(rewritten) => {
                    back::write_variant(&dir, &rewritten, language)?;
                    totals.written += 1;
                }
                Err(refusal) => {
                    totals.refused += 1;
                    totals.internal += usize::from(refusal.is_internal());
                    diagnostic::emit_to_stderr(
                        None,
                        &Diagnostic::new(
                            Severity::Warning,
                            format!(
                                "refused: node {} (`{}`), {variant}: {}",
                                candidate.node.id, candidate.node.text, refusal.reason
                            ),
                        ),
                        color,
                    );
                }
            }
        }
    }
    Ok(())
}
