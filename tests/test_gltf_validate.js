// Validates a glTF/GLB file with the Khronos glTF validator (npm gltf-validator,
// installed by scripts/setup.sh into .tools/). Prints the report's issues as JSON
// and exits 1 when there are errors, 2 when the validator cannot run.
//   node test_gltf_validate.js VALIDATOR_DIR FILE
const fs = require('fs');
const path = require('path');
const [validatorDir, file] = process.argv.slice(2);
let validator;
try {
  validator = require(path.join(validatorDir, 'node_modules', 'gltf-validator'));
} catch (e) {
  console.error(`gltf-validator not found in ${validatorDir}: run scripts/setup.sh (${e.message})`);
  process.exit(2);
}
const bytes = new Uint8Array(fs.readFileSync(file));
validator.validateBytes(bytes, { maxIssues: 100, format: path.extname(file) === '.glb' ? 'glb' : 'gltf' })
  .then((report) => {
    console.log(JSON.stringify({ validatorVersion: report.validatorVersion, issues: report.issues }, null, 1));
    process.exit(report.issues.numErrors > 0 ? 1 : 0);
  })
  .catch((e) => {
    console.error(`validation failed: ${e}`);
    process.exit(1);
  });
