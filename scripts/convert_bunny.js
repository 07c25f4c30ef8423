#!/usr/bin/env node
// Converts the Stanford bunny from the npm package `bunny` (exports `positions` and `cells`)
// into assets/bunny.obj, geometry unchanged (this decimated version turns out to be closed:
// no open boundary edges).
//
// How to run (from the repository root):
//   cd /tmp && npm pack bunny && mkdir -p bunnypkg && tar xzf bunny-*.tgz -C bunnypkg && cd -
//   node scripts/convert_bunny.js /tmp/bunnypkg/package/index.js assets/bunny.obj
//
// Positions are written unchanged (the package's units, roughly 10 units tall, +Y up);
// scene files scale and place it. Faces are 1-based as OBJ requires.
"use strict";
const fs = require("fs");
const path = require("path");

const [src, dst] = process.argv.slice(2);
if (!src || !dst) {
  console.error("usage: node scripts/convert_bunny.js PATH/TO/bunny/index.js OUT.obj");
  process.exit(2);
}
const bunny = require(path.resolve(src));
const lines = [
  "# Stanford bunny (Stanford 3D Scanning Repository), via the npm package `bunny` 1.0.1",
  "# converted by scripts/convert_bunny.js; geometry unchanged",
  `# ${bunny.positions.length} vertices, ${bunny.cells.length} triangles`,
];
for (const p of bunny.positions) lines.push(`v ${p[0]} ${p[1]} ${p[2]}`);
for (const c of bunny.cells) lines.push(`f ${c[0] + 1} ${c[1] + 1} ${c[2] + 1}`);
fs.writeFileSync(dst, lines.join("\n") + "\n");
console.log(`wrote ${dst}: ${bunny.positions.length} vertices, ${bunny.cells.length} triangles`);
