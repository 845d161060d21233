#!/usr/bin/env node
// Validates .glb/.gltf files with the Khronos glTF validator (npm package
// gltf-validator, pinned in tools/package.json; install with
// `npm ci --prefix tools`). Prints each file's issues and summary; exits 1 if
// any file has an error (warnings and infos are listed but pass), 2 on bad
// usage or an unreadable file, 77 (ctest's "skipped") when the validator is
// not installed and CI is not set; in CI a missing validator is an error.
import { readFile } from 'node:fs/promises';
import { createRequire } from 'node:module';
import path from 'node:path';

const require = createRequire(import.meta.url);
let validator;
try {
  validator = require('gltf-validator');
} catch (e) {
  const hint = 'gltf-validator is not installed: run `npm ci --prefix tools --no-audit --no-fund`';
  if (process.env.CI === 'true' || process.env.CI === '1') {
    console.error(`error: ${hint} (CI is set, so this fails)`);
    process.exit(1);
  }
  console.error(`skipped: ${hint}`);
  process.exit(77);
}

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error('usage: validate_gltf.mjs FILE.glb [FILE.glb ...]');
  process.exit(2);
}

const severities = ['error', 'warning', 'info', 'hint'];
let failed = false;
for (const file of files) {
  let bytes;
  try {
    bytes = new Uint8Array(await readFile(file));
  } catch (e) {
    console.error(`${file}: ${e.message}`);
    process.exit(2);
  }
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 0,  // all of them
    externalResourceFunction: (uri) => Promise.reject(new Error(`external resource ${uri}`)),
  });
  const issues = report.issues;
  console.log(`${file}: ${issues.numErrors} errors, ${issues.numWarnings} warnings, ` +
              `${issues.numInfos} infos, ${issues.numHints} hints ` +
              `(validator ${report.validatorVersion}; generator ${report.info?.generator ?? '?'})`);
  for (const m of issues.messages) {
    console.log(`  ${severities[m.severity] ?? m.severity} ${m.code} ${m.pointer ?? ''}: ${m.message}`);
  }
  if (issues.numErrors > 0) failed = true;
}
process.exit(failed ? 1 : 0);
