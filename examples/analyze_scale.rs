//! How `analyze` scales with the size of the IR, beside naga's own parse,
//! validate and write-back of the same module, in one run.
//!
//! ```sh
//! cargo run --release --example analyze_scale          # 2000 and 8000 terms
//! cargo run --release --example analyze_scale -- 500 1000 2000 4000 8000
//! ```
//!
//! Each shader is a generated sum in one `let` of the fragment stage,
//! `let s = sin(p.x*1.0+p.y) + sin(p.x*2.0+p.y) + ...;`, whose partial sums
//! are all candidates. Each measurement runs in a child process of this
//! binary so that its peak memory (Linux's `VmHWM`) is its own. Figures
//! are in `docs/results.md`.

use std::process::Command;
use std::time::Instant;

fn shader(terms: usize) -> String {
    let sum: Vec<String> = (1..=terms).map(|i| format!("sin(p.x*{i}.0+p.y)")).collect();
    format!(
        "@group(0) @binding(0) var<uniform> clip_from_world: mat4x4<f32>;
struct V {{ @builtin(position) position: vec4<f32>, @location(0) p: vec3<f32> }}
@vertex
fn vs_main(@location(0) p: vec3<f32>) -> V {{
    return V(clip_from_world * vec4<f32>(p, 1.0), p);
}}
@fragment
fn fs_main(in: V) -> @location(0) vec4<f32> {{
    let p = in.p;
    let s = {};
    return vec4<f32>(s);
}}
",
        sum.join(" + ")
    )
}

/// Peak resident memory of this process in KiB (0 where /proc is not).
fn peak_kib() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|status| {
            status
                .lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse().ok())
        })
        .unwrap_or(0)
}

/// Runs one measurement in this process and prints `seconds peak_kib`.
fn measure(what: &str, terms: usize) {
    let text = shader(terms);
    let start = Instant::now();
    match what {
        "naga" => {
            let module = naga::front::wgsl::parse_str(&text).expect("the sum parses");
            let info = naga::valid::Validator::new(
                naga::valid::ValidationFlags::all(),
                naga::valid::Capabilities::all(),
            )
            .validate(&module)
            .expect("the sum validates");
            let written = naga::back::wgsl::write_string(
                &module,
                &info,
                naga::back::wgsl::WriterFlags::empty(),
            )
            .expect("the sum writes back");
            std::hint::black_box(written);
        }
        "analyze" => {
            let shader =
                shadecache::front::parse(shadecache::diagnostic::SourceFile::new("sum.wgsl", text))
                    .expect("the sum parses");
            let analysis =
                shadecache::analysis::analyze(&shader, &shadecache::analysis::Options::default())
                    .expect("the sum analyses");
            // What `analyze --format json` writes, so output is counted.
            let json = serde_json::to_string_pretty(&analysis).expect("JSON");
            std::hint::black_box(json);
        }
        _ => panic!("unknown measurement `{what}`"),
    }
    println!("{} {}", start.elapsed().as_secs_f64(), peak_kib());
}

fn child(what: &str, terms: usize) -> (f64, u64) {
    let exe = std::env::current_exe().expect("this binary's path");
    let output = Command::new(exe)
        .args(["--measure", what, &terms.to_string()])
        .output()
        .expect("the measurement runs");
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let text = String::from_utf8_lossy(&output.stdout);
    let mut fields = text.split_whitespace();
    let seconds = fields
        .next()
        .and_then(|f| f.parse().ok())
        .unwrap_or(f64::NAN);
    let kib = fields.next().and_then(|f| f.parse().ok()).unwrap_or(0);
    (seconds, kib)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("--measure") {
        measure(&args[1], args[2].parse().expect("a number of terms"));
        return;
    }
    let sizes: Vec<usize> = if args.is_empty() {
        vec![2000, 8000]
    } else {
        args.iter()
            .map(|a| a.parse().expect("numbers of terms"))
            .collect()
    };
    println!("| terms | naga parse+validate+write | analyze (parse, validate, analyse, JSON) | time ratio | naga peak | analyze peak | memory ratio |");
    println!("|---:|---:|---:|---:|---:|---:|---:|");
    for terms in sizes {
        let (naga_s, naga_kib) = child("naga", terms);
        let (ours_s, ours_kib) = child("analyze", terms);
        println!(
            "| {terms} | {naga_s:.3} s | {ours_s:.3} s | {:.1}× | {:.1} MiB | {:.1} MiB | {:.1}× |",
            ours_s / naga_s,
            naga_kib as f64 / 1024.0,
            ours_kib as f64 / 1024.0,
            ours_kib as f64 / naga_kib.max(1) as f64
        );
    }
}
