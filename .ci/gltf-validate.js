// Validates .glb files with the Khronos glTF validator (npm gltf-validator).
// Usage: node gltf-validate.js FILE...   Exit status 1 if any file has an error (or a warning).
const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

async function main() {
  let bad = 0;
  for (const f of process.argv.slice(2)) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(f)), {
      uri: path.basename(f), maxIssues: 50,
    });
    const n = report.issues;
    console.log(`${f}: ${n.numErrors} errors, ${n.numWarnings} warnings, ${n.numInfos} infos`);
    for (const m of n.messages) {
      if (m.severity <= 1) console.log(`  ${m.severity === 0 ? 'error' : 'warning'} ${m.code} ${m.pointer || ''}: ${m.message}`);
    }
    if (n.numErrors > 0 || n.numWarnings > 0) bad++;
  }
  process.exit(bad ? 1 : 0);
}
main().catch((e) => { console.error(e); process.exit(2); });
