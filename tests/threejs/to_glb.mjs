// Packs a .gltf and the files and data URIs it names into one .glb (every buffer and image in the binary
// chunk), for testing `burnish gltf` on GLB input without a third-party packer.
//   node to_glb.mjs IN.gltf OUT.glb
import fs from 'node:fs';
import path from 'node:path';

const [input, output] = process.argv.slice(2);
const doc = JSON.parse(fs.readFileSync(input, 'utf8'));
const load = (uri) => uri.startsWith('data:') ? Buffer.from(uri.slice(uri.indexOf(',') + 1), 'base64')
  : fs.readFileSync(path.resolve(path.dirname(input), decodeURIComponent(uri)));
const parts = [];
let length = 0;
const append = (bytes) => {
  const offset = length;
  parts.push(bytes);
  length += bytes.length;
  const pad = (4 - (length % 4)) % 4;
  if (pad) { parts.push(Buffer.alloc(pad)); length += pad; }
  return offset;
};
const bufferOffsets = (doc.buffers || []).map((b) => append(load(b.uri).subarray(0, b.byteLength)));
for (const view of doc.bufferViews || []) { view.byteOffset = (view.byteOffset || 0) + bufferOffsets[view.buffer]; view.buffer = 0; }
for (const image of doc.images || []) {
  if (!image.uri) continue;
  const bytes = load(image.uri);
  doc.bufferViews = doc.bufferViews || [];
  doc.bufferViews.push({ buffer: 0, byteOffset: append(bytes), byteLength: bytes.length });
  image.mimeType = image.mimeType || (bytes[0] === 0x89 ? 'image/png' : 'image/jpeg');
  image.bufferView = doc.bufferViews.length - 1;
  delete image.uri;
}
doc.buffers = [{ byteLength: length }];
let json = Buffer.from(JSON.stringify(doc), 'utf8');
json = Buffer.concat([json, Buffer.alloc((4 - (json.length % 4)) % 4, 0x20)]);
const bin = Buffer.concat(parts);
const header = Buffer.alloc(12);
header.writeUInt32LE(0x46546c67, 0); header.writeUInt32LE(2, 4); header.writeUInt32LE(12 + 8 + json.length + 8 + bin.length, 8);
const chunk = (type, data) => { const h = Buffer.alloc(8); h.writeUInt32LE(data.length, 0); h.writeUInt32LE(type, 4); return Buffer.concat([h, data]); };
fs.writeFileSync(output, Buffer.concat([header, chunk(0x4e4f534a, json), chunk(0x004e4942, bin)]));
