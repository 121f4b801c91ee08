// Run the Khronos glTF validator (npm's gltf-validator, which tools/setup installs under target/gltf-validator)
// over glTF and GLB files; print each file's counts and its errors and warnings; exit 1 when any file has an error.
//
//   node tools/validate_gltf.cjs FILE...
"use strict";
const fs = require("fs");
const path = require("path");

const where = path.join(__dirname, "..", "target", "gltf-validator", "node_modules", "gltf-validator");
let validator;
try {
  validator = require(where);
} catch (e) {
  console.error(`the glTF validator is not installed at ${where}: run tools/setup`);
  process.exit(2);
}

async function main(files) {
  let errors = 0;
  for (const file of files) {
    const bytes = new Uint8Array(fs.readFileSync(file));
    const report = await validator.validateBytes(bytes, {
      uri: file,
      maxIssues: 100,
      externalResourceFunction: (uri) =>
        new Promise((resolve, reject) => {
          try {
            resolve(new Uint8Array(fs.readFileSync(path.resolve(path.dirname(file), decodeURIComponent(uri)))));
          } catch (e) {
            reject(e.toString());
          }
        }),
    });
    const i = report.issues;
    console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos`);
    for (const m of i.messages) {
      if (m.severity <= 1) console.log(`  ${m.severity === 0 ? "error" : "warning"} ${m.code} ${m.pointer || ""}: ${m.message}`);
    }
    errors += i.numErrors;
  }
  process.exit(errors > 0 ? 1 : 0);
}

main(process.argv.slice(2)).catch((e) => {
  console.error(e);
  process.exit(2);
});
