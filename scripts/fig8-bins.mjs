#!/usr/bin/env node
// Seed 002's fig. 8 over many nodes as a table: a profile's report.json
// (one run, or shards joined by `shadecache merge`) binned by each node's
// measured P/T, each cell the median speed-up of the variant over the
// nodes in that bin (lowest–highest, how many), then how often each
// variant is a node's fastest. docs/reproduction.md's tables of fig. 8
// over the marble's candidates are this script's output.
//
//   node scripts/fig8-bins.mjs REPORT.json [--bin 0.1]
import { readFileSync } from "node:fs";

const args = process.argv.slice(2);
const path = args.find((a) => !a.startsWith("--"));
if (!path) {
  console.error("usage: node scripts/fig8-bins.mjs REPORT.json [--bin WIDTH]");
  process.exit(2);
}
const binAt = args.indexOf("--bin");
const width = binAt >= 0 ? Number(args[binAt + 1]) : 0.1;
if (!(width > 0 && width <= 1)) {
  console.error(`--bin takes a width in (0, 1], not ${args[binAt + 1]}`);
  process.exit(2);
}

const report = JSON.parse(readFileSync(path, "utf8"));
const variants = ["one-pass", "two-pass", "three-pass", "deferred"].filter((v) =>
  report.results.some((r) => r.variant === v),
);
const pOverT = new Map(report.nodes.map((n) => [n.id, n.p_over_t]));

const median = (xs) => {
  const s = [...xs].sort((a, b) => a - b);
  const m = s.length >> 1;
  return s.length % 2 ? s[m] : (s[m - 1] + s[m]) / 2;
};
const x = (v) => `${v.toFixed(2)}×`;

// Bin index of a P/T: noise may put a P/T just under 0 or over 1; those
// join the end bins.
const bins = Math.round(1 / width);
const binOf = (p) => Math.min(bins - 1, Math.max(0, Math.floor(p / width)));

const cells = new Map(); // `${bin} ${variant}` → speed-ups
const nodesIn = new Map(); // bin → set of node ids
const best = new Map(); // node → [variant, speed-up]
for (const row of report.results) {
  const p = pOverT.get(row.node);
  if (p === undefined) continue;
  const bin = binOf(p);
  const key = `${bin} ${row.variant}`;
  cells.set(key, [...(cells.get(key) ?? []), row.speedup]);
  nodesIn.set(bin, (nodesIn.get(bin) ?? new Set()).add(row.node));
  const was = best.get(row.node);
  if (!was || row.speedup > was[1]) best.set(row.node, [row.variant, row.speedup]);
}

const lines = [
  `${pOverT.size} nodes, reference ${report.reference.time_ms.toFixed(2)} ms, ${report.results.length} results.`,
  "",
  `| measured P/T | nodes | ${variants.join(" | ")} |`,
  `|---|---|${variants.map(() => "---|").join("")}`,
];
for (let bin = 0; bin < bins; bin++) {
  const nodes = nodesIn.get(bin);
  if (!nodes) continue;
  const range = `${(bin * width).toFixed(1)}–${((bin + 1) * width).toFixed(1)}`;
  const cols = variants.map((v) => {
    const xs = cells.get(`${bin} ${v}`) ?? [];
    if (!xs.length) return "—";
    return `${x(median(xs))} (${x(Math.min(...xs)).slice(0, -1)}–${x(Math.max(...xs)).slice(0, -1)}, ${xs.length})`;
  });
  lines.push(`| ${range} | ${nodes.size} | ${cols.join(" | ")} |`);
}
const fastest = variants.map((v) => `${v} ${[...best.values()].filter(([w]) => w === v).length}`);
const faster = [...best.values()].filter(([, s]) => s > 1).length;
lines.push("", `fastest variant per node: ${fastest.join(", ")}; nodes with a variant faster than the original: ${faster}`);
console.log(lines.join("\n"));
