// Validates WGSL files with Tint, Chrome's WGSL compiler, through Dawn's
// node binding (npm package `webgpu`) on Dawn's null backend, so no GPU
// or driver is needed.
//
// Usage:
//   node tests/tint/validate.mjs FILE.wgsl [FILE.wgsl ...]
//   find corpus -name '*.wgsl' | node tests/tint/validate.mjs -
//
// A `-` argument reads further paths from stdin, one per line, so a test can
// validate many files with a single start of node.
//
// Output: one JSON object per file per line on stdout:
//   {"file": "...", "ok": true|false,
//    "messages": [{"type": "error"|"warning"|"info",
//                  "line": N, "column": N, "message": "..."}]}
// `ok` is false when any message has type "error".
//
// Exit status: 0 all files valid, 1 at least one file invalid,
// 2 harness failure (no adapter, unreadable file, ...; reason on stderr).

import { readFileSync } from 'node:fs';
import { create, globals } from 'webgpu';

// Reports a harness failure and leaves with status 2.
function fail(message) {
  process.stderr.write(`validate.mjs: ${message}\n`);
  process.exit(2);
}

// Collects the file list from the arguments, expanding `-` to stdin lines.
function collectFiles(args) {
  const files = [];
  for (const arg of args) {
    if (arg === '-') {
      const text = readFileSync(0, 'utf8');
      for (const line of text.split(/\r?\n/)) {
        const path = line.trim();
        if (path !== '') files.push(path);
      }
    } else {
      files.push(arg);
    }
  }
  return files;
}

async function main() {
  const files = collectFiles(process.argv.slice(2));
  if (files.length === 0) {
    fail('usage: node validate.mjs FILE.wgsl [FILE.wgsl ...] (or - to read paths from stdin)');
  }

  // Read every file first so that an unreadable path is a harness failure
  // before any result is printed.
  const sources = files.map((file) => {
    try {
      return readFileSync(file, 'utf8');
    } catch (err) {
      fail(`cannot read ${file}: ${err.message}`);
    }
  });

  // WebGPU constants (GPUBufferUsage, ...) become globals, as in a browser.
  Object.assign(globalThis, globals);
  const gpu = create(['backend=null']);
  // Dawn aborts after some thousand shader modules on one device (they are
  // freed only when the garbage collector gets to them), so a fresh device
  // validates each batch.
  const BATCH = 250;
  let device = null;

  let allOk = true;
  for (let i = 0; i < files.length; i++) {
    if (i % BATCH === 0) {
      if (device) device.destroy();
      // An adapter gives one device; ask for a new one each batch.
      const adapter = await gpu.requestAdapter();
      if (!adapter) fail('no WebGPU adapter (null backend)');
      device = await adapter.requestDevice();
      if (!device) fail('no WebGPU device');
    }
    // The error scope captures the validation error of an invalid module,
    // which Dawn would otherwise print as an uncaptured error.
    device.pushErrorScope('validation');
    const module = device.createShaderModule({ code: sources[i] });
    const info = await module.getCompilationInfo();
    await device.popErrorScope();

    const messages = info.messages.map((m) => ({
      type: m.type,
      line: m.lineNum,
      column: m.linePos,
      message: m.message,
    }));
    const ok = !messages.some((m) => m.type === 'error');
    if (!ok) allOk = false;
    process.stdout.write(JSON.stringify({ file: files[i], ok, messages }) + '\n');
  }

  // Dawn can keep the event loop alive; leave explicitly.
  process.exit(allOk ? 0 : 1);
}

main().catch((err) => fail(err && err.stack ? err.stack : String(err)));
