// Runs the Khronos glTF-Validator (npm gltf-validator) on each file named: prints every issue
// (errors, warnings, infos, hints) and exits 1 if any file has an error or a warning, 2 on usage.
//   node gltf_validate.js VALIDATOR_DIR FILE.glb|FILE.gltf...
// VALIDATOR_DIR is the folder holding node_modules/gltf-validator (scripts/setup-deps.sh).
'use strict';
const fs = require('fs');
const path = require('path');

if (process.argv.length < 4) {
    console.error('usage: node gltf_validate.js VALIDATOR_DIR FILE...');
    process.exit(2);
}
const validator = require(path.resolve(process.argv[2], 'node_modules', 'gltf-validator'));
const severities = ['error', 'warning', 'info', 'hint'];

async function validate(file) {
    const full = path.resolve(file);
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(full)), {
        uri: path.basename(full),
        maxIssues: 0,   // all of them
        // A .gltf's buffers are files beside it.
        externalResourceFunction: (uri) => new Promise((resolve, reject) => {
            fs.readFile(path.resolve(path.dirname(full), decodeURIComponent(uri)), (err, data) => err ? reject(err.toString()) : resolve(new Uint8Array(data)));
        }),
    });
    const i = report.issues;
    console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos, ${i.numHints} hints` +
                ` (validator ${report.validatorVersion})`);
    for (const m of i.messages) console.log(`  ${severities[m.severity] || m.severity} ${m.code} ${m.pointer || ''} ${m.message}`);
    return i.numErrors + i.numWarnings === 0;
}

(async () => {
    let ok = true;
    for (const f of process.argv.slice(3)) {
        try {
            ok = (await validate(f)) && ok;
        } catch (e) {
            console.log(`${f}: the validator could not read it: ${e}`);
            ok = false;
        }
    }
    process.exit(ok ? 0 : 1);
})();
