// Turns the reports of one `scripts/gpu-run.sh` run into one markdown file
// under docs/runs/: the adapter and driver, then a table per command with
// every figure and its interval (the profile's bootstrap interval of the
// speed-up; `interpolate` runs once and gives none, which the table says;
// `play` gives each way's mean frame time and the governor's switches).
//
//   node scripts/runs-table.mjs WORK_DIR MANIFEST [--quick] [--reproduction]
//
// MANIFEST lines: name <TAB> wall seconds <TAB> command. Prints the path
// written.
import { readFileSync, writeFileSync, existsSync } from "node:fs";
import { join } from "node:path";

const [work, manifest, ...flags] = process.argv.slice(2);
const quick = flags.includes("--quick");
const reproduction = flags.includes("--reproduction");
const runs = readFileSync(manifest, "utf8")
  .trim()
  .split("\n")
  .map((line) => {
    const [name, seconds, command] = line.split("\t");
    return { name, seconds: Number(seconds), command };
  });

const fixed = (x, d) => (x === null || x === undefined ? "—" : Number(x).toFixed(d));
const interval = (ci) => (ci ? `[${fixed(ci[0], 2)}, ${fixed(ci[1], 2)}]` : "");

function profileTable(report) {
  const pt = Object.fromEntries(report.nodes.map((n) => [n.id, n.p_over_t]));
  const rows = [...report.results].sort(
    (a, b) =>
      (pt[a.node] ?? 0) - (pt[b.node] ?? 0) ||
      a.variant.localeCompare(b.variant) ||
      a.refresh_period - b.refresh_period ||
      a.refresh_quad - b.refresh_quad ||
      String(a.reconstruction).localeCompare(String(b.reconstruction)),
  );
  const lines = [
    `Reference ${fixed(report.reference.time_ms, 3)} ms; ${report.size[0]}×${report.size[1]}, ${report.frames} frames after ${report.warmup} of warm-up; timing: ${report.timing}.`,
    "",
    "| node | P/T (measured) | variant | read-back | Δn | k | time ms | speed-up [95% interval] | PSNR dB (worst frame) | SSIM |",
    "|---|---|---|---|---|---|---|---|---|---|",
  ];
  for (const r of rows) {
    lines.push(
      `| \`${r.node}\` | ${fixed(pt[r.node], 3)} | ${r.variant} | ${r.reconstruction} | ${r.refresh_period} | ${r.refresh_quad} | ${fixed(r.time_ms, 3)} | ${fixed(r.speedup, 2)}× ${interval(r.speedup_ci)} | ${fixed(r.psnr, 1)} (${fixed(r.worst_psnr, 1)}) | ${fixed(r.ssim, 4)} |`,
    );
  }
  return lines;
}

function interpolateTable(report) {
  const lines = [
    `Reference ${fixed(report.reference_ms, 3)} ms, I-frame with flows ${fixed(report.i_frame_ms, 3)} ms; ${report.size[0]}×${report.size[1]}, n = ${report.frames_per_interval}, ${report.intervals} interval(s); timing: ${report.timing}. One run: no interval (the displayed frames' slowest over median says how much the frames spread).`,
    "",
    "| method | amortised | I-frame | B-frame | SSIM mean (min) | PSNR dB | pursuit error | latency | displayed frames median / slowest ms |",
    "|---|---|---|---|---|---|---|---|---|",
  ];
  for (const m of report.methods) {
    const d = m.displayed_frame_ms ?? {};
    lines.push(
      `| ${m.method} | ${fixed(m.amortized_time_ratio, 2)}× | ${fixed(m.i_frame_time_ratio, 2)}× | ${fixed(m.b_frame_time_ratio, 3)}× | ${fixed(m.ssim_mean, 4)} (${fixed(m.ssim_min, 4)}) | ${fixed(m.psnr_mean, 1)} | ${fixed(m.pursuit_error, 4)} | ${m.added_latency_frames} | ${fixed(d.median, 2)} / ${fixed(d.max, 2)} |`,
    );
  }
  for (const note of report.notes ?? []) {
    if (note.includes("refused")) lines.push("", `Note: ${note}`);
  }
  return lines;
}

function playTable(play) {
  const ratio = (ms) => (ms > 0 ? `${fixed(play.original_ms / ms, 2)}×` : "—");
  const lines = [
    `${play.size[0]}×${play.size[1]}, ${play.frames} frames each way, interleaved; ${play.fixed_variant}. Mean GPU time of a displayed frame.`,
    "",
    "| way | mean frame ms | speed-up |",
    "|---|---|---|",
    `| original | ${fixed(play.original_ms, 3)} | 1× |`,
    `| fixed cache | ${fixed(play.fixed_ms, 3)} | ${ratio(play.fixed_ms)} |`,
    `| governor | ${fixed(play.auto_ms, 3)} | ${ratio(play.auto_ms)} (${fixed(play.auto_cached_share * 100, 0)}% of frames cached, cache ${play.auto_on_at_end ? "on" : "off"} at the end) |`,
    "",
  ];
  for (const d of play.decisions) {
    lines.push(
      d.cause === "error" || d.cause === "margin"
        ? `- frame ${d.frame}: Δn = ${d.period}, cache ${d.on ? "on" : "off"} (a watched frame at ${fixed(d.psnr, 1)} dB, ${d.cause === "error" ? "below" : "well within"} the budget)`
        : `- frame ${d.frame}: cache ${d.on ? "on" : "off"}, speed-up ${fixed(d.speedup, 2)}× ${interval(d.interval)}`,
    );
  }
  if (play.decisions.length === 0) lines.push("- no switch: the cache stayed on");
  for (const [i, trial] of (play.trials ?? []).entries()) {
    const turns = trial.map((t) => `${play.auto_variants[t.variant]} ${fixed(t.speedup, 2)}×${t.psnr != null ? ` at ${fixed(t.psnr, 1)} dB` : ""}`);
    lines.push(`- trial ${i + 1} of the variants: ${turns.join(", ")}`);
  }
  // play.json format 2 has the error watch.
  if (play.min_psnr != null) {
    const lowest = Math.min(...play.watches.map((w) => w.psnr));
    lines.push(
      `- error watch, budget ${play.min_psnr} dB: ${play.watches.length} frames watched, lowest ${fixed(lowest, 1)} dB; a watched frame ${fixed(play.watch_frame_ms, 3)} ms, its comparison ${fixed(play.watch_compare_ms, 3)} ms; Δn = ${play.auto_period_at_end} at the end`,
    );
  }
  return lines;
}

const reports = runs.map((run) => {
  const path = join(work, run.name, "report.json");
  const played = join(work, run.name, "play.json");
  if (existsSync(played)) return { ...run, play: JSON.parse(readFileSync(played, "utf8")) };
  if (!existsSync(path)) throw new Error(`${run.name}: no report.json`);
  return { ...run, report: JSON.parse(readFileSync(path, "utf8")) };
});
const device = reports.find((r) => r.report?.device)?.report.device;
const adapter = device
  ? `${device.name} (${device.backend})`
  : (reports.find((r) => r.report)?.report.adapter ?? reports[0].play?.device);
const driver = device ? device.driver : "—";
const date = new Date().toISOString().slice(0, 16).replace(":", "") + "Z";
// The file names the adapter and, where the driver says it, its Mesa
// version: one adapter's figures differ from driver to driver.
const mesa = /Mesa (\d+(?:\.\d+)*)/.exec(driver ?? "")?.[1];
const slug = (mesa && /llvmpipe/i.test(device?.name ?? "") ? `llvmpipe mesa ${mesa}` : `${device?.name ?? "adapter"}${mesa ? ` mesa ${mesa}` : ""}`)
  .toLowerCase()
  .replace(/[^a-z0-9]+/g, "-")
  .replace(/^-|-$/g, "");

const out = [
  `# GPU run: ${adapter}${quick ? " (smoke run)" : ""}`,
  "",
  `Adapter: ${adapter}. Driver: ${driver}. Date: ${date}. Made by \`${reproduction ? "GPU_RUN_REPRODUCTION=1 " : ""}${process.env.GPU_RUN_EVERY_CANDIDATE ? `GPU_RUN_EVERY_CANDIDATE=${process.env.GPU_RUN_EVERY_CANDIDATE} ` : ""}scripts/gpu-run.sh\`${quick ? " with GPU_RUN_QUICK=1 (small frames: a check of the script, not figures)" : ""}; total ${reports.reduce((s, r) => s + r.seconds, 0)} s.`,
  "",
];
for (const r of reports) {
  out.push(`## ${r.name}`, "", "```sh", r.command, "```", "", `${r.seconds} s.`, "");
  const table = r.play
    ? playTable(r.play)
    : r.report.methods
      ? interpolateTable(r.report)
      : profileTable(r.report);
  out.push(...table, "");
}
const file = join(
  "docs",
  "runs",
  `${date}-${slug}${reproduction ? "-reproduction" : ""}${quick ? "-smoke" : ""}.md`,
);
writeFileSync(file, out.join("\n"));
console.log(file);
