//! The folders the commands write (`--out`): checked before anything runs,
//! named in every message, and left as they were by a command that fails.

use crate::util::{shadecache, stderr};

/// `--out` under a file cannot be made: `profile` and `interpolate` say
/// so, naming the path, before they read the scene, let alone measure (a
/// scene that does not parse would otherwise be the error), and `merge`
/// and `rewrite` before they write.
#[test]
fn an_unwritable_out_is_refused_before_measuring() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("a-file");
    std::fs::write(&file, b"").unwrap();
    let bad_scene = dir.path().join("bad.toml");
    std::fs::write(&bad_scene, b"[camera\n").unwrap();
    let out = file.join("report");
    let out_arg = out.to_str().unwrap();
    let scene_arg = bad_scene.to_str().unwrap();
    for command in ["profile", "interpolate"] {
        let run = shadecache([
            command,
            "corpus/noise_marble.wgsl",
            "--scene",
            scene_arg,
            "--out",
            out_arg,
        ]);
        let said = stderr(&run);
        assert_eq!(run.status.code(), Some(1), "{command}: {said}");
        assert!(
            said.contains(&format!("cannot create `{out_arg}`")),
            "{command}: {said}"
        );
        assert!(!said.contains("bad.toml"), "{command}: {said}");
    }
    // An --out that is a file.
    let run = shadecache([
        "rewrite",
        "corpus/noise_marble.wgsl",
        "--node",
        "n5c3eb6af",
        "--out",
        file.to_str().unwrap(),
    ]);
    assert_eq!(run.status.code(), Some(1));
    assert!(stderr(&run).contains("is a file"), "{}", stderr(&run));
}

/// A rewrite that fails writing leaves nothing of its own: not the
/// variants written before the failure, not a `.partial` file, not a
/// variant folder without its `plan.json`. What was in the folder before
/// (here a `plan.json` that is a folder, the review's case) stays.
#[test]
fn a_failed_rewrite_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("variants");
    std::fs::create_dir_all(out.join("three-pass/plan.json")).unwrap();
    // Two variants of the marble's `node` into `out`, with `more` flags.
    let rewrite = |node: &str, out: &std::path::Path, more: &[&str]| {
        let mut args = vec![
            "rewrite",
            "corpus/noise_marble.wgsl",
            "--node",
            node,
            "--variant",
            "two-pass,three-pass",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend(more);
        shadecache(args)
    };
    let run = rewrite("n5c3eb6af", &out, &[]);
    // Files no run of ours listed: refused before anything is written.
    assert_eq!(run.status.code(), Some(1));
    assert!(stderr(&run).contains("--overwrite"), "{}", stderr(&run));
    let listing = |dir: &std::path::Path| -> Vec<String> {
        walk(dir)
            .into_iter()
            .map(|p| p.strip_prefix(dir).unwrap().display().to_string())
            .collect()
    };
    assert_eq!(listing(&out), ["three-pass", "three-pass/plan.json"]);

    let run = rewrite("n5c3eb6af", &out, &["--overwrite"]);
    let said = stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{said}");
    assert!(
        said.contains(&format!(
            "cannot write `{}`",
            out.join("three-pass/plan.json").display()
        )),
        "{said}"
    );
    assert_eq!(listing(&out), ["three-pass", "three-pass/plan.json"]);

    // Into a folder of its own making: gone when the rewrite fails.
    let fresh = dir.path().join("fresh/variants");
    let run = rewrite("nzzzz", &fresh, &[]);
    assert_eq!(run.status.code(), Some(1));
    assert!(
        stderr(&run).contains("unknown node id `nzzzz`"),
        "{}",
        stderr(&run)
    );
    assert!(!dir.path().join("fresh").exists());
}

/// Every path under `dir`, sorted.
fn walk(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        out.push(path.clone());
        if path.is_dir() {
            out.extend(walk(&path));
        }
    }
    out.sort();
    out
}
