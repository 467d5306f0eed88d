// Validates a .glb or .gltf with the Khronos glTF validator and prints its report.
// Usage: node tests/gltf_validate.mjs FILE, or --version to print the validator's version.
// Exit status: 0 no errors and no warnings, 1 issues found, 3 validator not installed.
// The package is found through NODE_PATH (the Rust test adds ./.node/node_modules and
// `npm root -g`); install it with `npm install --prefix .node gltf-validator@2.0.0-dev.3.10`
// (every release is a prerelease, so a plain `@2` range matches none).
import { readFileSync } from 'node:fs';
import path from 'node:path';
import { createRequire } from 'node:module';

const require = createRequire(import.meta.url);
let validator;
try {
  validator = require('gltf-validator');
} catch (e) {
  console.log(
    'gltf-validator is not installed (npm install --prefix .node gltf-validator@2.0.0-dev.3.10)',
  );
  process.exit(3);
}

if (process.argv[2] === '--version') {
  console.log(validator.version());
  process.exit(0);
}

const file = process.argv[2];
const dir = path.dirname(file);
const report = await validator.validateBytes(new Uint8Array(readFileSync(file)), {
  uri: path.basename(file),
  maxIssues: 50,
  externalResourceFunction: (uri) =>
    new Promise((resolve, reject) => {
      try {
        resolve(new Uint8Array(readFileSync(path.join(dir, decodeURIComponent(uri)))));
      } catch (e) {
        reject(e.toString());
      }
    }),
});
const { numErrors, numWarnings, numInfos, numHints, messages } = report.issues;
console.log(JSON.stringify({ file, numErrors, numWarnings, numInfos, numHints, messages }, null, 1));
process.exit(numErrors + numWarnings > 0 ? 1 : 0);
