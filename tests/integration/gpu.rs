//! wgpu render pipelines for every pass of every variant, on whatever
//! adapter the machine has (Mesa's lavapipe in CI).

use std::collections::HashMap;
use std::path::Path;

use shadecache::back::{self, Language};
use shadecache::rewrite::{self, Options, Variant};
use shadecache::runtime::{self, Gpu};

use crate::util::{corpus, root};

/// A device, or `None` after saying so on stderr. In CI (the `CI`
/// environment variable set) a missing adapter fails the test: CI installs
/// lavapipe, so its absence is a broken setup, not a reason to skip.
pub fn gpu() -> Option<Gpu> {
    match Gpu::new() {
        Ok(Some(gpu)) => Some(gpu),
        Ok(None) if std::env::var_os("CI").is_none() => {
            eprintln!("SKIPPED: no GPU adapter (install mesa-vulkan-drivers for lavapipe)");
            None
        }
        Ok(None) => panic!("no GPU adapter in CI: is mesa-vulkan-drivers installed?"),
        Err(err) => panic!("{err}"),
    }
}

#[test]
fn every_pass_of_every_variant_builds_a_wgpu_pipeline() {
    let Some(gpu) = gpu() else { return };
    eprintln!("adapter: {} ({:?})", gpu.adapter.name, gpu.adapter.backend);
    let mut built = 0;
    for path in corpus() {
        let text = std::fs::read_to_string(root().join(&path)).unwrap();
        let shader = shadecache::front::parse(shadecache::diagnostic::SourceFile::new(
            path.display().to_string(),
            text,
        ))
        .unwrap();
        let analysis =
            shadecache::analysis::analyze(&shader, &shadecache::analysis::Options::default())
                .unwrap();
        for candidate in &analysis.candidates {
            for variant in Variant::ALL {
                let Ok(rewritten) =
                    rewrite::rewrite(&shader, &analysis, candidate, variant, &Options::default())
                else {
                    continue;
                };
                let sources: HashMap<String, String> = rewritten
                    .passes
                    .iter()
                    .map(|pass| {
                        let out = back::write(&pass.module, &pass.info, Language::Wgsl).unwrap();
                        (
                            format!("{}.wgsl", pass.name),
                            String::from_utf8(out[0].bytes.clone()).unwrap(),
                        )
                    })
                    .collect();
                let pipelines =
                    runtime::pipelines(&gpu, &rewritten.plan, |name| sources.get(name).cloned())
                        .unwrap_or_else(|err| {
                            panic!(
                                "{} {} {variant}: {err}",
                                Path::new(&path).display(),
                                candidate.node.id
                            )
                        });
                built += pipelines.len();
            }
        }
    }
    assert!(built > 1000, "{built} pipelines");
    eprintln!("built {built} pipelines");
}
