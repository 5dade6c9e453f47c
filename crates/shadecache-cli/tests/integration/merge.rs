//! A sweep in shards (`profile --shard K/N`) and their merge
//! (`shadecache merge`).

use crate::util::{shadecache, stderr, temp_file};

/// The command line: `--shard` takes K/N with 1 ≤ K ≤ N, a shard of a
/// grid too small to have one is an error, and `merge` says which file is
/// not a report, exiting 1.
#[test]
fn shard_and_merge_bad_input_is_an_error() {
    for bad in ["0/2", "3/2", "2", "a/b"] {
        let out = shadecache(["profile", "corpus/noise_marble.wgsl", "--shard", bad]);
        assert_eq!(out.status.code(), Some(1), "{bad}");
        assert!(stderr(&out).contains("K/N"), "{bad}: {}", stderr(&out));
    }
    // More shards than configurations: an error for every shard of such
    // a sweep (3/3's slice is not empty, 1/3's is), before anything runs
    // or is written.
    let dir = tempfile::tempdir().unwrap();
    for shard in ["1/3", "3/3"] {
        let out_dir = dir.path().join("shard");
        let out = shadecache([
            "profile",
            "corpus/noise_marble.wgsl",
            "--nodes",
            "top:1",
            "--variant",
            "two-pass",
            "--refresh-period",
            "8",
            "--refresh-quad",
            "2",
            "--shard",
            shard,
            "--out",
            out_dir.to_str().unwrap(),
        ]);
        assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
        let said = stderr(&out);
        assert!(
            said.contains(&format!("shard {shard}: the grid has 1 configuration"))
                && said.contains("use at most 1"),
            "{said}"
        );
        assert!(!out_dir.exists());
    }
    let (_dir, path) = temp_file("report.json", b"{\"format\": 1}");
    let out = shadecache(["merge", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("is not a profile's report.json"),
        "{}",
        stderr(&out)
    );
}
