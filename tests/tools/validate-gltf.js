#!/usr/bin/env node
// validate-gltf FILE.glb: runs the Khronos glTF validator on a file and
// prints its summary; exits 0 when it reports no errors, 1 otherwise.
'use strict';
const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

const file = process.argv[2];
if (!file) {
  console.error('usage: validate-gltf FILE.glb');
  process.exit(2);
}
const bytes = new Uint8Array(fs.readFileSync(file));
validator.validateBytes(bytes, {
  uri: path.basename(file),
  externalResourceFunction: () => Promise.reject(new Error('no external resources allowed')),
}).then((report) => {
  const issues = report.issues;
  console.log(JSON.stringify({
    file,
    errors: issues.numErrors,
    warnings: issues.numWarnings,
    infos: issues.numInfos,
    messages: issues.messages.filter((m) => m.severity <= 1).slice(0, 20),
    info: report.info,
  }, null, 1));
  process.exit(issues.numErrors === 0 ? 0 : 1);
}, (error) => {
  console.error('validate-gltf: ' + file + ': ' + error);
  process.exit(1);
});
