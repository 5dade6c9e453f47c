//! Arbitrary text through the whole shader pipeline: parse and validate,
//! analyse, rewrite every candidate (up to a few) into every variant, and
//! write each rewrite back as WGSL. Bad input must come back as an error,
//! never a panic; and every module the rewriter emits must parse and
//! validate again (the rule that no variant is emitted broken).

#![no_main]

use libfuzzer_sys::fuzz_target;
use shadecache::back::{self, Language};
use shadecache::diagnostic::SourceFile;
use shadecache::rewrite::{self, Options, Reconstruction, Variant};
use shadecache::{analysis, front};

/// Candidates rewritten per input, to keep each run short.
const MAX_CANDIDATES: usize = 4;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(shader) = front::parse(SourceFile::new("fuzz.wgsl", text)) else {
        return;
    };
    let Ok(analysis) = analysis::analyze(&shader, &analysis::Options::default()) else {
        return;
    };
    // One reconstruction per input, chosen by its length, so that every
    // lookup (separate and packed) is exercised without running four times.
    let options = Options {
        reconstruction: Reconstruction::ALL[data.len() % Reconstruction::ALL.len()],
        ..Options::default()
    };
    for candidate in analysis.candidates.iter().take(MAX_CANDIDATES) {
        for variant in Variant::ALL {
            let Ok(rewritten) = rewrite::rewrite(&shader, &analysis, candidate, variant, &options)
            else {
                continue;
            };
            let files = back::render_variant(&rewritten, Language::Wgsl)
                .expect("a rewritten module is written back");
            for (name, bytes) in files {
                let wgsl = String::from_utf8(bytes).expect("WGSL is text");
                if let Err(err) = front::parse(SourceFile::new(name.as_str(), wgsl.as_str())) {
                    panic!("{name} of {} {variant} does not validate: {err:?}\n{wgsl}", candidate.node.id);
                }
            }
        }
    }
});
