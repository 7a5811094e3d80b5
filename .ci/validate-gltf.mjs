// Validates every .glb/.gltf under a folder with the Khronos glTF validator (npm gltf-validator)
// and counts its messages of every severity (errors, warnings, infos, hints). Exit 1 on any.
import fs from "node:fs";
import path from "node:path";

let validator;
try {
  validator = await import("gltf-validator");
} catch (e) {
  console.error(`validate-gltf: gltf-validator is not installed (${e.message}); run .ci/setup-validators`);
  process.exit(1);
}

function walk(dir) {
  const out = [];
  for (const e of fs.readdirSync(dir, { withFileTypes: true })) {
    const p = path.join(dir, e.name);
    if (e.isDirectory()) out.push(...walk(p));
    else if (/\.(glb|gltf)$/i.test(e.name)) out.push(p);
  }
  return out.sort();
}

const root = process.argv[2];
const files = walk(root);
let issues = 0;
for (const f of files) {
  const bytes = new Uint8Array(fs.readFileSync(f));
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(f),
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        fs.readFile(path.join(path.dirname(f), decodeURIComponent(uri)), (err, data) =>
          err ? reject(err.toString()) : resolve(new Uint8Array(data)),
        );
      }),
  });
  const n = report.issues;
  const count = n.numErrors + n.numWarnings + n.numInfos + n.numHints;
  for (const m of n.messages) console.log(`  ${f}: ${m.code} ${m.message} (${m.pointer ?? ""})`);
  issues += count;
}
console.log(`gltf: ${files.length} files checked with gltf-validator ${validator.version()}, ${issues} issues`);
process.exit(issues ? 1 : 0);
