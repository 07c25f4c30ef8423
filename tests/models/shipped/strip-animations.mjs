// The Fox without its animations (42 KB of keyframes dbuffer never plays), so that the corpus
// stays small; its skin, joints and weights stay.
import { NodeIO } from '@gltf-transform/core';
const [, , input, output] = process.argv;
const io = new NodeIO();
const doc = await io.read(input);
for (const a of doc.getRoot().listAnimations()) a.dispose();
await io.write(output, doc);
