// SPDX-License-Identifier: MIT
// Runs the Khronos glTF validator (npm gltf-validator) on one file and prints its issue counts; exits 1 when the
// validator reports errors, 2 when it cannot run. Used by tests/puppeteer/export_test.cpp when node is present.
const fs = require('fs');
let validator;
try {
  validator = require('gltf-validator');
} catch (e) {
  console.log('gltf-validator not installed');
  process.exit(2);
}
const path = process.argv[2];
validator.validateBytes(new Uint8Array(fs.readFileSync(path)))
  .then((report) => {
    const i = report.issues;
    console.log(`errors ${i.numErrors} warnings ${i.numWarnings} infos ${i.numInfos} hints ${i.numHints}`);
    for (const m of i.messages) console.log(`${m.severity} ${m.code} ${m.pointer || ''} ${m.message}`);
    process.exit(i.numErrors > 0 ? 1 : 0);
  })
  .catch((e) => {
    console.log('validator failed: ' + e);
    process.exit(2);
  });
