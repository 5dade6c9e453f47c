//! Every corpus shader × candidate × variant, rewritten once for all the
//! tests that walk them all — naga and Tint validation, wgpu pipelines,
//! the derivative-after-kill walk. The first test that asks computes the
//! set; the others wait for it and share it. What each test needs of a
//! variant is kept (its plan, its passes' WGSL, what its IR showed), not
//! the naga modules, so the set stays small.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use crate::back::{self, Language};
use crate::plan::Plan;
use crate::rewrite::{self, Options, Variant};

/// One corpus shader's candidate in one variant.
pub struct CorpusRewrite {
    /// The shader, relative to the repository root.
    pub shader: PathBuf,
    pub node: String,
    pub variant: Variant,
    /// The variant, or the reason it was refused.
    pub outcome: Result<Emitted, String>,
}

/// What the tests need of an emitted variant.
pub struct Emitted {
    pub plan: Plan,
    /// Each pass's WGSL (the classification pass's included) under the
    /// file name the plan gives it.
    pub wgsl: Vec<(String, String)>,
    /// For each pass, what walking its IR for a derivative after a
    /// `discard` found.
    pub kills: Vec<(String, Result<(), String>)>,
    /// How many of its passes end their entry point with the `if` that
    /// holds a deferred `discard`.
    pub deferred_kills: usize,
}

impl CorpusRewrite {
    /// `stem/node/variant`, where the tests write and name it.
    pub fn label(&self) -> String {
        format!(
            "{}/{}/{}",
            self.shader.file_stem().unwrap().to_string_lossy(),
            self.node,
            self.variant
        )
    }
}

/// The whole set, computed once.
pub fn corpus_rewrites() -> &'static [CorpusRewrite] {
    static ALL: OnceLock<Vec<CorpusRewrite>> = OnceLock::new();
    ALL.get_or_init(|| {
        super::util::corpus()
            .iter()
            .flat_map(|path| rewrite_shader(path))
            .collect()
    })
}

fn rewrite_shader(path: &Path) -> Vec<CorpusRewrite> {
    // Under its path relative to the root, so nothing depends on where
    // the checkout is.
    let text = std::fs::read_to_string(super::util::root().join(path)).unwrap();
    let shader = crate::front::parse(crate::diagnostic::SourceFile::new(
        path.display().to_string(),
        text,
    ))
    .unwrap_or_else(|e| panic!("{}", e.render()));
    let analysis = crate::analysis::analyze(&shader, &crate::analysis::Options::default()).unwrap();
    let mut out = Vec::new();
    for candidate in &analysis.candidates {
        for variant in Variant::ALL {
            let outcome =
                match rewrite::rewrite(&shader, &analysis, candidate, variant, &Options::default())
                {
                    Ok(rewritten) => Ok(emitted(&rewritten)),
                    Err(refusal) => Err(refusal.reason),
                };
            out.push(CorpusRewrite {
                shader: path.to_path_buf(),
                node: candidate.node.id.clone(),
                variant,
                outcome,
            });
        }
    }
    out
}

fn emitted(rewritten: &rewrite::Rewritten) -> Emitted {
    let wgsl = back::render_variant(rewritten, Language::Wgsl)
        .unwrap_or_else(|e| panic!("{}", e.render()))
        .into_iter()
        .map(|(name, bytes)| (name, String::from_utf8(bytes).unwrap()))
        .collect();
    let mut kills = Vec::new();
    let mut deferred_kills = 0;
    for pass in rewritten.passes.iter().chain([&rewritten.classify]) {
        let found =
            crate::rewrite::uniformity::check_kills(&pass.module).map_err(|err| err.to_string());
        kills.push((pass.name.clone(), found));
        // The kill moved to the end: the entry point's last statement
        // before its return is the `if`.
        let body = &pass.module.entry_points.last().unwrap().function.body;
        if body.len() >= 2
            && matches!(body[body.len() - 2], naga::Statement::If { .. })
            && matches!(body.last(), Some(naga::Statement::Return { .. }))
        {
            deferred_kills += 1;
        }
    }
    Emitted {
        plan: rewritten.plan.clone(),
        wgsl,
        kills,
        deferred_kills,
    }
}
