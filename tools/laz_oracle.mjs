#!/usr/bin/env node
// The LAZ test oracle: decodes .laz files with the npm package laz-perf
// (Hobu's LASzip implementation compiled to WebAssembly, pinned in
// tools/package.json; install with `npm ci --prefix tools`), which shares no
// code with pointbake's decoder.
//
//   laz_oracle.mjs compare A.laz A.las [B.laz B.las ...]
//       every point record laz-perf decodes from X.laz must equal the
//       records of the uncompressed X.las, byte for byte (same count, same
//       record length). Prints one line per file; exits 1 on a difference.
//   laz_oracle.mjs decode IN.laz OUT.bin
//       writes the decoded records, concatenated, to OUT.bin.
//   laz_oracle.mjs time IN.laz [REPEATS]
//       decodes the file REPEATS times (default 3) and prints the best run's
//       wall and CPU seconds and points per second as a Markdown table row
//       (bench/laz_decode.sh).
// Exits 2 on bad usage or an unreadable file, 77 (ctest's "skipped") when
// laz-perf is not installed and CI is not set; in CI that is an error.
import { readFile, writeFile } from 'node:fs/promises';
import { createRequire } from 'node:module';

const require = createRequire(import.meta.url);
let createLazPerf;
try {
  ({ createLazPerf } = require('laz-perf'));
} catch (e) {
  const hint = 'laz-perf is not installed: run `npm ci --prefix tools --no-audit --no-fund`';
  if (process.env.CI === 'true' || process.env.CI === '1') {
    console.error(`error: ${hint} (CI is set, so this fails)`);
    process.exit(1);
  }
  console.error(`skipped: ${hint}`);
  process.exit(77);
}

function usage() {
  console.error('usage: laz_oracle.mjs compare A.laz A.las ... | decode IN.laz OUT.bin | time IN.laz [REPEATS]');
  process.exit(2);
}

async function load(file) {
  try {
    return new Uint8Array(await readFile(file));
  } catch (e) {
    console.error(`${file}: ${e.message}`);
    process.exit(2);
  }
}

const LazPerf = await createLazPerf();

// Decodes `bytes` (a whole LAZ file); calls visit(record, index) per point.
function decode(bytes, visit) {
  const filePtr = LazPerf._malloc(bytes.length);
  LazPerf.HEAPU8.set(bytes, filePtr);
  const laszip = new LazPerf.LASZip();
  let pointPtr = 0;
  try {
    laszip.open(filePtr, bytes.length);
    const count = laszip.getCount();
    const length = laszip.getPointLength();
    pointPtr = LazPerf._malloc(length);
    for (let i = 0; i < count; ++i) {
      laszip.getPoint(pointPtr);
      if (visit) visit(LazPerf.HEAPU8.subarray(pointPtr, pointPtr + length), i);
    }
    return { count, length, format: laszip.getPointFormat() };
  } finally {
    laszip.delete();
    if (pointPtr) LazPerf._free(pointPtr);
    LazPerf._free(filePtr);
  }
}

const [command, ...args] = process.argv.slice(2);
if (command === 'compare') {
  if (args.length === 0 || args.length % 2 !== 0) usage();
  let failed = false;
  for (let f = 0; f < args.length; f += 2) {
    const [lazFile, lasFile] = [args[f], args[f + 1]];
    const las = await load(lasFile);
    const view = new DataView(las.buffer, las.byteOffset, las.byteLength);
    const offset = view.getUint32(96, true);
    const recordLength = view.getUint16(105, true);
    const lasCount = (las.length - offset) / recordLength;
    let firstDifference = null;
    let info;
    try {
      info = decode(await load(lazFile), (record, i) => {
        if (firstDifference !== null || i >= lasCount) return;
        const start = offset + i * recordLength;
        for (let b = 0; b < recordLength; ++b) {
          if (record[b] !== las[start + b]) {
            firstDifference = `point ${i} byte ${b}: laz-perf ${record[b]}, LAS ${las[start + b]}`;
            return;
          }
        }
      });
    } catch (e) {
      console.log(`${lazFile}: laz-perf failed: ${e.message || e}`);
      failed = true;
      continue;
    }
    if (info.length !== recordLength || info.count !== lasCount || firstDifference !== null) {
      console.log(`${lazFile}: DIFFERS from ${lasFile}: ${info.count} points of ${info.length} bytes ` +
                  `vs ${lasCount} of ${recordLength}` + (firstDifference ? `; first difference at ${firstDifference}` : ''));
      failed = true;
    } else {
      console.log(`${lazFile}: ${info.count} points (format ${info.format}, ${info.length} bytes) identical to ${lasFile}`);
    }
  }
  process.exit(failed ? 1 : 0);
} else if (command === 'decode') {
  if (args.length !== 2) usage();
  const chunks = [];
  const info = decode(await load(args[0]), (record) => chunks.push(Buffer.from(record)));
  await writeFile(args[1], Buffer.concat(chunks));
  console.log(`${args[0]}: ${info.count} points of ${info.length} bytes`);
} else if (command === 'time') {
  if (args.length < 1) usage();
  const bytes = await load(args[0]);
  const repeats = Number(args[1] || 3);
  let best = Infinity;
  let bestCpu = 0;
  let count = 0;
  for (let r = 0; r < repeats; ++r) {
    const start = process.hrtime.bigint();
    const cpu = process.cpuUsage();
    count = decode(bytes, null).count;
    const wall = Number(process.hrtime.bigint() - start) / 1e9;
    if (wall < best) {
      best = wall;
      const used = process.cpuUsage(cpu);
      bestCpu = (used.user + used.system) / 1e6;
    }
  }
  // The same columns as bench/laz_bench's table.
  console.log(`| ${args[0].split('/').pop()} | npm laz-perf (WebAssembly, node) | 1 | ${best.toFixed(3)} | ` +
              `${bestCpu.toFixed(3)} | ${bestCpu.toFixed(3)} | ${(count / best / 1e6).toFixed(2)} | ${(count / bestCpu / 1e6).toFixed(2)} |`);
} else {
  usage();
}
