// A fan of 12 triangles around the origin, each with its own copy of the centre (as exporters
// split vertices for flat normals): half the positions are (0, 0, 0). Written twice: dense
// (ARGV[2]) and with POSITION sparse on zeros, without a bufferView (ARGV[3]), as glTF
// Transform's writer stores a sparse accessor (its `sparse` command only converts accessors
// that are two-thirds zeros or more).
import { Document, NodeIO } from '@gltf-transform/core';
const doc = new Document();
const buffer = doc.createBuffer();
const n = 12, p = [], idx = [];
for (let i = 0; i < n; i++) p.push(0, 0, 0);
for (let i = 0; i < n; i++) {
  const a = (2 * Math.PI * i) / n;
  p.push(Math.cos(a), 0.25 * (i % 3), -Math.sin(a));
}
for (let i = 0; i < n; i++) idx.push(i, n + ((i + 1) % n), n + i);
const position = doc.createAccessor().setType('VEC3').setArray(new Float32Array(p)).setBuffer(buffer);
const indices = doc.createAccessor().setType('SCALAR').setArray(new Uint16Array(idx)).setBuffer(buffer);
const prim = doc.createPrimitive().setAttribute('POSITION', position).setIndices(indices);
const mesh = doc.createMesh('fan').addPrimitive(prim);
const node = doc.createNode('fan').setMesh(mesh).setTranslation([0, 1, 0]);
doc.createScene('scene').addChild(node);
await new NodeIO().write(process.argv[2], doc);
position.setSparse(true);
await new NodeIO().write(process.argv[3], doc);
