// The Khronos glTF Validator on every GLB in a directory: 0 errors each (see readers.sh).
const fs = require("fs");
const path = require("path");
const validator = require("gltf-validator");

async function main(dir) {
  const files = fs.readdirSync(dir).filter((f) => f.endsWith(".glb")).sort();
  if (files.length === 0) {
    console.error(`${dir}: no GLB files`);
    return 1;
  }
  let failed = 0;
  for (const f of files) {
    const bytes = new Uint8Array(fs.readFileSync(path.join(dir, f)));
    const report = await validator.validateBytes(bytes, { maxIssues: 100 });
    const { numErrors, numWarnings, numInfos, messages } = report.issues;
    const status = numErrors === 0 ? "ok" : "FAILED";
    console.log(
      `gltf-validator ${report.validatorVersion}: ${f}: ${numErrors} errors, ${numWarnings} warnings, ${numInfos} infos: ${status}`
    );
    for (const m of messages.filter((m) => m.severity <= 1)) {
      console.log(`  ${m.severity === 0 ? "error" : "warning"} ${m.code} at ${m.pointer}: ${m.message}`);
    }
    failed += numErrors === 0 ? 0 : 1;
  }
  console.log(`gltf-validator: ${files.length - failed}/${files.length} files have 0 errors`);
  return failed ? 1 : 0;
}

main(process.argv[2]).then((code) => process.exit(code), (e) => {
  console.error(e);
  process.exit(1);
});
