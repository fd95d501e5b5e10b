#!/usr/bin/env node
// Runs the Khronos glTF-Validator (npm package gltf-validator, pinned in
// package.json) over glTF / GLB files, each in its own child process with a
// time limit and a heap cap, so that a hostile file cannot hang or exhaust the run.
//
//   node validate.mjs [--out FILE] [--timeout SECONDS] [--max-issues N]
//                     [--max-old-space-size MB] [--root DIR]
//                     [--require-valid PREFIX]... FILE...
//
// Writes one JSON line per file, in the order given, to --out (default stdout):
//   {"path", "valid" (numErrors == 0), "errors", "warnings", "infos", "hints",
//    "codes" (distinct error codes), "warning_codes", "truncated", "status"}
// where status is "ok" (the validator produced a report), "rejected" (the
// validator refused the input, e.g. neither glTF nor GLB: valid false, the
// message in "detail"), "timeout" or "crashed" (the child was killed or died,
// e.g. out of heap: valid false, errors null). A short table goes to stderr.
//
// Exit status: 0 whatever the files' validity; 1 if the validator itself cannot
// run (the package does not load, a child cannot be started, bad arguments);
// 3 if a file whose path starts with a --require-valid PREFIX is not valid.
//
// External resources (buffers and images with a relative URI) are read relative
// to the glTF's folder, only if they are regular files of at most 256 MiB
// inside --root (default: the current directory); anything else (absolute
// paths, ../ out of the root, file: or other schemes, FIFOs, devices, /proc
// files, missing files) is refused, which the validator reports as IO_ERROR
// exactly as it reports a missing file. data: URIs the validator decodes itself.
import { spawn } from "node:child_process";
import fs from "node:fs";
import { createRequire } from "node:module";
import path from "node:path";
import { fileURLToPath } from "node:url";

const SELF = fileURLToPath(import.meta.url);
const require = createRequire(import.meta.url);
const MAX_RESOURCE_BYTES = 256 * 1024 * 1024;

function usage(msg) {
  process.stderr.write(`validate.mjs: ${msg}\nusage: node validate.mjs [--out FILE] [--timeout S] [--max-issues N] [--max-old-space-size MB] [--root DIR] [--require-valid PREFIX]... FILE...\n`);
  process.exit(1);
}

function parseArgs(argv) {
  const o = { out: null, timeout: 30, maxIssues: 100, heapMb: 1024, root: ".", requireValid: [], child: false, files: [] };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    const val = () => {
      if (i + 1 >= argv.length) usage(`${a} needs a value`);
      return argv[++i];
    };
    const num = () => {
      const v = Number(val());
      if (!Number.isFinite(v) || v < 0) usage(`${a} needs a number >= 0`);
      return v;
    };
    if (a === "--out") o.out = val();
    else if (a === "--timeout") o.timeout = num();
    else if (a === "--max-issues") o.maxIssues = Math.floor(num());
    else if (a === "--max-old-space-size") o.heapMb = Math.floor(num());
    else if (a === "--root") o.root = val();
    else if (a === "--require-valid") o.requireValid.push(val());
    else if (a === "--child") o.child = true;
    else if (a === "--") o.files.push(...argv.slice(i + 1)), (i = argv.length);
    else if (a.startsWith("--")) usage(`unknown option ${a}`);
    else o.files.push(a);
  }
  return o;
}

// ---- child: validate one file, print one JSON object on stdout ----

function isInside(root, p) {
  const rel = path.relative(root, p);
  return rel === "" || (!rel.startsWith("..") && !path.isAbsolute(rel));
}

function resourceLoader(gltfPath, root) {
  const dir = path.dirname(path.resolve(gltfPath));
  const realRoot = fs.realpathSync(root);
  return async (uri) => {
    if (/^[A-Za-z][A-Za-z0-9+.-]*:/.test(uri)) throw new Error(`${uri}: URI scheme not read`);
    let rel;
    try {
      rel = decodeURIComponent(uri);
    } catch {
      throw new Error(`${uri}: malformed percent-encoding`);
    }
    if (path.isAbsolute(rel)) throw new Error(`${uri}: absolute path not read`);
    const p = path.resolve(dir, rel);
    let real;
    try {
      real = fs.realpathSync(p);
    } catch (e) {
      throw new Error(`${uri}: ${e.code === "ENOENT" ? "no such file" : e.message}`);
    }
    if (!isInside(realRoot, real)) throw new Error(`${uri}: outside the repository, not read`);
    const st = fs.statSync(real);
    if (!st.isFile()) throw new Error(`${uri}: not a regular file, not read`);
    if (st.size > MAX_RESOURCE_BYTES) throw new Error(`${uri}: ${st.size} bytes, over the ${MAX_RESOURCE_BYTES}-byte limit`);
    return new Uint8Array(fs.readFileSync(real));
  };
}

async function child(opts) {
  const validator = require("gltf-validator");
  const file = opts.files[0];
  const data = new Uint8Array(fs.readFileSync(file));
  const ext = path.extname(file).toLowerCase();
  const options = {
    uri: file,
    maxIssues: opts.maxIssues,
    writeTimestamp: false,
    externalResourceFunction: resourceLoader(file, opts.root),
  };
  // Detect the format from the extension, like a loader would; other names
  // are left to the validator's auto-detection (first byte).
  if (ext === ".glb") options.format = "glb";
  else if (ext === ".gltf") options.format = "gltf";
  let out;
  try {
    const report = await validator.validateBytes(data, options);
    const msgs = report.issues.messages || [];
    const distinct = (sev) => [...new Set(msgs.filter((m) => m.severity === sev).map((m) => m.code))].sort();
    out = {
      status: "ok",
      errors: report.issues.numErrors,
      warnings: report.issues.numWarnings,
      infos: report.issues.numInfos,
      hints: report.issues.numHints,
      codes: distinct(0),
      warning_codes: distinct(1),
      truncated: Boolean(report.issues.truncated),
      messages: msgs.filter((m) => m.severity <= 1).slice(0, 20).map((m) => ({ code: m.code, severity: m.severity, pointer: m.pointer, offset: m.offset, message: m.message })),
      validator: report.validatorVersion,
    };
  } catch (e) {
    out = { status: "rejected", detail: String(e) };
  }
  process.stdout.write(JSON.stringify(out) + "\n");
}

// ---- parent: one child per file ----

function runChild(opts, file) {
  return new Promise((resolve) => {
    const args = [`--max-old-space-size=${opts.heapMb}`, SELF, "--child", "--max-issues", String(opts.maxIssues), "--root", opts.root, "--", file];
    let proc;
    try {
      proc = spawn(process.execPath, args, { stdio: ["ignore", "pipe", "pipe"] });
    } catch (e) {
      resolve({ spawnError: String(e) });
      return;
    }
    let stdout = "";
    let stderr = "";
    let timedOut = false;
    const started = Date.now();
    const timer = setTimeout(() => {
      timedOut = true;
      proc.kill("SIGKILL");
    }, opts.timeout * 1000);
    proc.stdout.on("data", (d) => {
      if (stdout.length < 1 << 20) stdout += d;
    });
    proc.stderr.on("data", (d) => {
      if (stderr.length < 1 << 16) stderr += d;
    });
    proc.on("error", (e) => {
      clearTimeout(timer);
      resolve({ spawnError: String(e) });
    });
    proc.on("close", (code, signal) => {
      clearTimeout(timer);
      resolve({ code, signal, stdout, stderr, timedOut, seconds: (Date.now() - started) / 1000 });
    });
  });
}

function lastLine(s) {
  const lines = s.trim().split("\n").filter((l) => l.trim() !== "");
  return lines.length ? lines[lines.length - 1] : "";
}

async function parent(opts) {
  if (opts.files.length === 0) usage("no files given");
  let version;
  try {
    version = require("gltf-validator").version();
  } catch (e) {
    process.stderr.write(`validate.mjs: cannot load gltf-validator (run npm ci in ${path.dirname(SELF)}): ${e}\n`);
    process.exit(1);
  }
  const sink = opts.out ? fs.createWriteStream(opts.out) : process.stdout;
  const rows = [];
  let failedRequired = [];
  const t0 = Date.now();
  for (const file of opts.files) {
    const r = await runChild(opts, file);
    if (r.spawnError) {
      process.stderr.write(`validate.mjs: cannot start a child node for ${file}: ${r.spawnError}\n`);
      process.exit(1);
    }
    let res = null;
    if (!r.timedOut && r.code === 0) {
      try {
        res = JSON.parse(lastLine(r.stdout));
      } catch {
        res = null;
      }
    }
    let line;
    if (res && res.status === "ok") {
      line = { path: file, valid: res.errors === 0, errors: res.errors, warnings: res.warnings, infos: res.infos, hints: res.hints, codes: res.codes, warning_codes: res.warning_codes, truncated: res.truncated, status: "ok", messages: res.messages };
    } else if (res && res.status === "rejected") {
      line = { path: file, valid: false, errors: null, warnings: null, codes: [], status: "rejected", detail: res.detail };
    } else if (r.timedOut) {
      line = { path: file, valid: false, errors: null, warnings: null, codes: [], status: "timeout", detail: `validator timed out after ${opts.timeout} s (killed)` };
    } else {
      const why = r.signal ? `killed by ${r.signal}` : `exit ${r.code}`;
      // V8 ends an out-of-memory report with "#" lines around "# Fatal ... OOM ...".
      const said = r.stderr.split("\n").map((l) => l.replace(/^#\s*/, "").trim()).filter((l) => l !== "");
      const oom = said.find((l) => /out of memory|OOM/.test(l));
      line = { path: file, valid: false, errors: null, warnings: null, codes: [], status: "crashed", detail: `validator crashed (${why}): ${(oom || said[said.length - 1] || "no message").slice(0, 300)}` };
    }
    line.seconds = Math.round(r.seconds * 100) / 100;
    sink.write(JSON.stringify(line) + "\n");
    rows.push(line);
    if (!line.valid && opts.requireValid.some((p) => file.startsWith(p))) failedRequired.push(file);
  }
  if (opts.out) await new Promise((res) => sink.end(res));

  const w = Math.max(4, ...rows.map((r) => r.path.length));
  const out = [`glTF-Validator ${version}: ${rows.length} files, ${((Date.now() - t0) / 1000).toFixed(1)} s`];
  out.push(`${"file".padEnd(w)}  result    errors warnings  error codes`);
  for (const r of rows) {
    const result = r.status === "ok" ? (r.valid ? "valid" : "INVALID") : r.status.toUpperCase();
    const e = r.errors == null ? "-" : String(r.errors);
    const wn = r.warnings == null ? "-" : String(r.warnings);
    const codes = r.status === "ok" ? r.codes.join(",") : r.detail;
    out.push(`${r.path.padEnd(w)}  ${result.padEnd(8)} ${e.padStart(7)} ${wn.padStart(8)}  ${codes}`);
  }
  const nValid = rows.filter((r) => r.valid).length;
  out.push(`${nValid} valid, ${rows.length - nValid} not valid`);
  process.stderr.write(out.join("\n") + "\n");
  if (failedRequired.length) {
    process.stderr.write(`validate.mjs: required to be valid but not: ${failedRequired.join(" ")}\n`);
    process.exit(3);
  }
}

const opts = parseArgs(process.argv.slice(2));
if (opts.child) {
  child(opts).catch((e) => {
    process.stderr.write(`validate.mjs child: ${e && e.stack ? e.stack : e}\n`);
    process.exit(2);
  });
} else {
  parent(opts).catch((e) => {
    process.stderr.write(`validate.mjs: ${e && e.stack ? e.stack : e}\n`);
    process.exit(1);
  });
}
