// Validates a glTF file with Khronos's glTF-Validator and prints its verdict as one line of JSON: the numbers of
// errors and warnings, the first messages, and what the file holds (triangles, textures, extensions).
// Usage: node gltf_check.mjs FILE
import { readFileSync } from 'node:fs';
import { validateBytes } from 'gltf-validator';

const report = await validateBytes(new Uint8Array(readFileSync(process.argv[2])), { maxIssues: 100 });
console.log(JSON.stringify({
  errors: report.issues.numErrors,
  warnings: report.issues.numWarnings,
  messages: report.issues.messages.slice(0, 100),
  info: report.info,
}));
