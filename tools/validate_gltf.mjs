#!/usr/bin/env node
// Validates .glb/.gltf files with the Khronos glTF validator (npm gltf-validator, installed into
// tools/node_modules by scripts/install_deps.sh). Prints a summary per file and every error and
// warning; exits 1 if any file has a validation error, 2 if a file cannot be read or validated.
// Usage: node tools/validate_gltf.mjs FILE...
import { createRequire } from 'node:module';
import fs from 'node:fs';
import path from 'node:path';

const require = createRequire(import.meta.url);
let validator;
try {
  validator = require('gltf-validator');
} catch (e) {
  console.error('validate_gltf: gltf-validator is not installed (run scripts/install_deps.sh)');
  process.exit(2);
}

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error('usage: node tools/validate_gltf.mjs FILE...');
  process.exit(2);
}

const severityNames = ['error', 'warning', 'info', 'hint'];
let worst = 0;
for (const file of files) {
  let report;
  try {
    const bytes = new Uint8Array(fs.readFileSync(file));
    report = await validator.validateBytes(bytes, {
      uri: path.basename(file),
      maxIssues: 100,
      externalResourceFunction: (uri) =>
        fs.promises.readFile(path.resolve(path.dirname(file), decodeURIComponent(uri))).then((d) => new Uint8Array(d)),
    });
  } catch (e) {
    console.error(`${file}: cannot validate: ${e}`);
    worst = 2;
    continue;
  }
  const issues = report.issues;
  console.log(`${file}: ${issues.numErrors} errors, ${issues.numWarnings} warnings, ` +
              `${issues.numInfos} infos, ${issues.numHints} hints`);
  for (const m of issues.messages) {
    if (m.severity <= 1) console.log(`  ${severityNames[m.severity]} ${m.code} at ${m.pointer ?? '-'}: ${m.message}`);
  }
  if (issues.numErrors > 0) worst = Math.max(worst, 1);
}
process.exit(worst);
