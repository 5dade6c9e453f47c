//! The profile's report as a person reads it: opened in headless Chromium
//! at a laptop's width.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::util::{shadecache, stderr};

/// Chromium, where the machine has it (`.ci/run` installs it).
fn chromium() -> Option<PathBuf> {
    ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .find_map(|name| {
            let output = Command::new("which").arg(name).output().ok()?;
            output
                .status
                .success()
                .then(|| PathBuf::from(String::from_utf8_lossy(&output.stdout).trim()))
        })
}

/// What the page measures of itself once laid out at `width` px: the
/// script is appended to a copy of `page`, and Chromium's DOM dump
/// carries its answer in an attribute of `<body>`.
fn measured(browser: &Path, page: &Path, width: u32) -> serde_json::Value {
    let script = r#"<script>
const svgs = [...document.querySelectorAll('svg')];
const ticks = (title) => {
  const svg = svgs.find(s => (s.querySelector('text') || {}).textContent === title);
  return svg ? [...svg.querySelectorAll('text.y-tick')].map(t => parseFloat(t.textContent)) : [];
};
const legends = svgs.map(s => [...s.querySelectorAll('rect')].filter(r => r.getAttribute('width') === '10').map(r => r.getAttribute('fill')));
const clipped = svgs.flatMap(s => {
  const box = s.getBoundingClientRect();
  return [...s.querySelectorAll('text')].filter(t => {
    const r = t.getBoundingClientRect();
    return r.width > 0 && (r.left < box.left - 1 || r.right > box.right + 1 || r.top < box.top - 1 || r.bottom > box.bottom + 1);
  }).map(t => t.textContent);
});
document.body.setAttribute('data-check', JSON.stringify({
  width: document.documentElement.scrollWidth,
  ssim_ticks: ticks('SSIM against time'),
  psnr_ticks: ticks('PSNR (dB) against time'),
  legends: legends,
  clipped: clipped,
}));
</script>"#;
    let html = std::fs::read_to_string(page).unwrap();
    let checked = page.with_file_name("checked.html");
    std::fs::write(
        &checked,
        html.replace("</body>", &format!("{script}</body>")),
    )
    .unwrap();
    let output = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--hide-scrollbars",
            &format!("--window-size={width},900"),
            "--dump-dom",
        ])
        .arg(format!("file://{}", checked.display()))
        .output()
        .expect("chromium runs");
    let dom = String::from_utf8_lossy(&output.stdout);
    let start = dom.find("data-check=\"").unwrap_or_else(|| {
        panic!(
            "the script ran: {}",
            String::from_utf8_lossy(&output.stderr)
        )
    }) + "data-check=\"".len();
    let end = start + dom[start..].find('"').unwrap();
    let json = dom[start..end]
        .replace("&quot;", "\"")
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&");
    serde_json::from_str(&json).unwrap()
}

/// At 1280 px the page does not scroll sideways (the results table keeps
/// the figures a choice rests on, the rest on demand), the error charts'
/// axes fit their data (SSIMs near 0.99 are not drawn from 0), no chart
/// label is cut off, and no legend repeats a colour.
#[test]
fn report_fits_a_laptop_screen_and_its_charts_fit_their_data() {
    if crate::util::no_gpu() {
        return;
    }
    let Some(browser) = chromium() else {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI installs Chromium for this test (.ci/run)"
        );
        eprintln!("skipped: no Chromium on this machine (apt-get install chromium)");
        return;
    };
    let out = tempfile::tempdir().unwrap();
    let report = out.path().join("report");
    let output = shadecache([
        "profile",
        "corpus/noise_marble.wgsl",
        "--scene",
        "corpus/scenes/marble_sphere.toml",
        "--frames",
        "3",
        "--size",
        "64x64",
        "--refresh-period",
        "8,16",
        "--quiet",
        "--out",
        report.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let check = measured(&browser, &report.join("report.html"), 1280);
    let width = check["width"].as_f64().unwrap();
    assert!(
        width <= 1280.0,
        "the page is {width} px wide at 1280: {check}"
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(report.join("report.json")).unwrap()).unwrap();
    let lowest = |metric: &str| {
        json["results"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| r[metric].as_f64().unwrap())
            .fold(f64::INFINITY, f64::min)
    };
    for (ticks, metric) in [("ssim_ticks", "ssim"), ("psnr_ticks", "psnr")] {
        let ticks: Vec<f64> = check[ticks]
            .as_array()
            .unwrap_or_else(|| panic!("{check}"))
            .iter()
            .map(|t| t.as_f64().unwrap())
            .collect();
        assert!(!ticks.is_empty(), "the {metric} chart is drawn: {check}");
        let (axis, data) = (ticks[0], lowest(metric));
        assert!(
            axis > 0.0 && axis <= data && data - axis < 0.5 * (ticks[ticks.len() - 1] - axis),
            "the {metric} axis starts at {axis} for data from {data}: {ticks:?}"
        );
    }
    for legend in check["legends"].as_array().unwrap() {
        let mut colours: Vec<&str> = legend
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c.as_str().unwrap())
            .collect();
        let all = colours.len();
        colours.sort();
        colours.dedup();
        assert_eq!(colours.len(), all, "a legend repeats a colour: {legend}");
    }
    assert_eq!(check["clipped"], serde_json::json!([]), "cut-off labels");
}
