// Independent checks of an asset written by `burnish gltf`, by third-party readers:
//   - Khronos's glTF-Validator (npm gltf-validator) must report 0 errors (infos and warnings about the
//     draft KHR_texture_ktx extension are expected and printed);
//   - ktx-parse (npm) must read every KTX2 image back with a known vkFormat, the full mip chain to 1x1,
//     each level's size halving (rounded down), and byte counts matching the format;
//   - with --bake DIR (a `burnish bake --preset gltf --format png8` set of the same map at the same
//     options), every KTX2 level equals that bake's PNG mips code for code: the normal texture's RG
//     against the normal PNGs' R and G, the metallicRoughness texture's G against theirs;
//   - every BURNISH_lobe_mixture material's lobe textures are RGBA16F chains whose weights (R) sum to 1
//     per texel at every level, within half-float rounding.
// Prints one JSON object; exits 1 when a check fails.
// With --input ORIGINAL (the asset `burnish gltf` read), errors the original already has (a real asset's
// own defects) are listed but not counted: the check is that Burnish adds none.
//   node check_gltf.mjs ASSET.gltf|ASSET.glb [--bake DIR] [--input ORIGINAL]
import fs from 'node:fs';
import path from 'node:path';
import zlib from 'node:zlib';
import { createRequire } from 'node:module';
import { read as readKtx2 } from 'ktx-parse';

const require = createRequire(import.meta.url);
const validator = require('gltf-validator');

const args = process.argv.slice(2);
const assetPath = args[0];
const bakeDir = args.includes('--bake') ? args[args.indexOf('--bake') + 1] : null;
const originalPath = args.includes('--input') ? args[args.indexOf('--input') + 1] : null;
if (!assetPath) {
  console.error('usage: node check_gltf.mjs ASSET.gltf|ASSET.glb [--bake DIR]');
  process.exit(2);
}
const folder = path.dirname(assetPath);
const bytes = fs.readFileSync(assetPath);
const failures = [];

// The asset's JSON and binary chunk.
let doc;
let bin = null;
if (bytes.readUInt32LE(0) === 0x46546c67) {
  let at = 12;
  while (at < bytes.length) {
    const length = bytes.readUInt32LE(at);
    const type = bytes.readUInt32LE(at + 4);
    const chunk = bytes.subarray(at + 8, at + 8 + length);
    if (type === 0x4e4f534a) doc = JSON.parse(chunk.toString('utf8'));
    else if (type === 0x004e4942) bin = chunk;
    at += 8 + length;
  }
} else {
  doc = JSON.parse(bytes.toString('utf8'));
}

async function validate(file) {
  const dir = path.dirname(file);
  const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
    uri: path.basename(file),
    maxIssues: 1000,
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        fs.readFile(path.resolve(dir, decodeURIComponent(uri)), (err, data) =>
          err ? reject(err.toString()) : resolve(new Uint8Array(data)));
      }),
  });
  return report.issues;
}
const severity = ['error', 'warning', 'info', 'hint'];
const issues = await validate(assetPath);
const codes = {};
for (const m of issues.messages) codes[`${severity[m.severity]}:${m.code}`] = (codes[`${severity[m.severity]}:${m.code}`] || 0) + 1;
const errorKey = (m) => `${m.code} at ${m.pointer}`;
const originalErrors = new Set();
if (originalPath)
  for (const m of (await validate(originalPath)).messages) if (m.severity === 0) originalErrors.add(errorKey(m));
const errors = issues.messages.filter((m) => m.severity === 0);
const newErrors = errors.filter((m) => !originalErrors.has(errorKey(m)));
if (newErrors.length > 0)
  failures.push(`gltf-validator: ${newErrors.length} errors` + (originalPath ? ' the input does not have' : '') + ': ' +
    newErrors.map((m) => `${m.code} at ${m.pointer}: ${m.message}`).join('; '));

function imageBytes(image) {
  if (image.uri) return fs.readFileSync(path.resolve(folder, decodeURIComponent(image.uri)));
  const view = doc.bufferViews[image.bufferView];
  const buffer = view.buffer === 0 && bin ? bin : fs.readFileSync(path.resolve(folder, doc.buffers[view.buffer].uri));
  return buffer.subarray(view.byteOffset || 0, (view.byteOffset || 0) + view.byteLength);
}

// VkFormat → bytes per texel or per 4x4 block.
const FORMATS = { 9: ['r8', 1, false], 16: ['rg8', 2, false], 37: ['rgba8', 4, false],
  137: ['bc3', 16, true], 139: ['bc4', 8, true], 141: ['bc5', 16, true], 97: ['rgba16f', 8, false] };

const ktx = [];
for (const [index, image] of (doc.images || []).entries()) {
  if (image.mimeType !== 'image/ktx2') continue;
  const container = readKtx2(new Uint8Array(imageBytes(image)));
  const format = FORMATS[container.vkFormat];
  const entry = { image: index, name: image.name, vkFormat: container.vkFormat, format: format ? format[0] : null,
    width: container.pixelWidth, height: container.pixelHeight, levels: container.levels.length,
    writer: container.keyValue.KTXwriter, orientation: container.keyValue.KTXorientation };
  if (!format) failures.push(`image ${index}: vkFormat ${container.vkFormat} is not one Burnish writes`);
  let w = container.pixelWidth, h = container.pixelHeight, k = 0;
  for (;; ++k) {
    const level = container.levels[k];
    if (!level) { failures.push(`image ${index}: the chain stops at level ${k} (${w}x${h}), before 1x1`); break; }
    const want = format ? (format[2] ? Math.ceil(w / 4) * Math.ceil(h / 4) * format[1] : w * h * format[1]) : -1;
    if (level.levelData.byteLength !== want || level.uncompressedByteLength !== want)
      failures.push(`image ${index}: level ${k} (${w}x${h}) holds ${level.levelData.byteLength} bytes, not ${want}`);
    if (w === 1 && h === 1) break;
    w = Math.max(1, w >> 1);
    h = Math.max(1, h >> 1);
  }
  if (container.levels.length !== k + 1) failures.push(`image ${index}: ${container.levels.length} levels, the chain has ${k + 1}`);
  entry.container = container;
  ktx.push(entry);
}

// The lobe mixture: per material, the lobe textures' R (w) summed over the lobes at every texel of every level.
function halfToFloat(h) {
  const e = (h >> 10) & 0x1f, m = h & 0x3ff, sign = h & 0x8000 ? -1 : 1;
  if (e === 0) return sign * m * 2 ** -24;
  if (e === 31) return m ? NaN : sign * Infinity;
  return sign * (1 + m / 1024) * 2 ** (e - 15);
}
const mixtures = [];
for (const [mi, material] of (doc.materials || []).entries()) {
  const ext = material.extensions && material.extensions.BURNISH_lobe_mixture;
  if (!ext) continue;
  const chains = ext.lobeTextures.map((info) => {
    const image = doc.textures[info.index].extensions.KHR_texture_ktx.source;
    return ktx.find((e) => e.image === image);
  });
  if (chains.length !== ext.lobes || chains.some((c) => !c || c.format !== 'rgba16f')) {
    failures.push(`material ${mi}: BURNISH_lobe_mixture's ${ext.lobes} lobes are not RGBA16F KTX2 chains`);
    continue;
  }
  let worst = 0;
  chains[0].container.levels.forEach((_, k) => {
    const views = chains.map((c) => {
      const d = c.container.levels[k].levelData;
      return new Uint16Array(d.buffer, d.byteOffset, d.byteLength / 2);
    });
    for (let i = 0; i < views[0].length; i += 4) {
      let sum = 0;
      for (const v of views) sum += halfToFloat(v[i]);
      worst = Math.max(worst, Math.abs(sum - 1));
    }
  });
  if (!(worst <= 2e-3)) failures.push(`material ${mi}: the lobe weights sum to 1 within ${worst}, not 2e-3`);
  mixtures.push({ material: mi, lobes: ext.lobes, levels: chains[0].levels, worstWeightSum: worst });
}

// A minimal PNG reader (8-bit grey/RGB/RGBA, not interlaced): enough for Burnish's own PNG mips.
function readPng(file) {
  const b = fs.readFileSync(file);
  let at = 8, width, height, depth, type;
  const idat = [];
  while (at < b.length) {
    const length = b.readUInt32BE(at);
    const kind = b.toString('latin1', at + 4, at + 8);
    const data = b.subarray(at + 8, at + 8 + length);
    if (kind === 'IHDR') { width = data.readUInt32BE(0); height = data.readUInt32BE(4); depth = data[8]; type = data[9]; }
    if (kind === 'IDAT') idat.push(data);
    at += 12 + length;
  }
  if (depth !== 8) throw new Error(`${file}: ${depth}-bit PNG`);
  const channels = { 0: 1, 2: 3, 4: 2, 6: 4 }[type];
  const raw = zlib.inflateSync(Buffer.concat(idat));
  const stride = width * channels;
  const out = Buffer.alloc(stride * height);
  for (let y = 0; y < height; ++y) {
    const filter = raw[y * (stride + 1)];
    for (let i = 0; i < stride; ++i) {
      const x = raw[y * (stride + 1) + 1 + i];
      const a = i >= channels ? out[y * stride + i - channels] : 0;
      const up = y > 0 ? out[(y - 1) * stride + i] : 0;
      const c = y > 0 && i >= channels ? out[(y - 1) * stride + i - channels] : 0;
      let v;
      if (filter === 0) v = x;
      else if (filter === 1) v = x + a;
      else if (filter === 2) v = x + up;
      else if (filter === 3) v = x + ((a + up) >> 1);
      else { const p = a + up - c, pa = Math.abs(p - a), pb = Math.abs(p - up), pc = Math.abs(p - c); v = x + (pa <= pb && pa <= pc ? a : pb <= pc ? up : c); }
      out[y * stride + i] = v & 0xff;
    }
  }
  return { width, height, channels, data: out };
}

const compared = [];
if (bakeDir) {
  const bake = JSON.parse(fs.readFileSync(path.join(bakeDir, 'bake.json'), 'utf8'));
  const files = Object.fromEntries(bake.files.map((f) => [f.name, f.paths]));
  for (const entry of ktx) {
    if (entry.format === 'rgba16f') continue; // the lobe mixture's, checked above: no bake file holds them
    const role = /normal/.test(entry.name) ? 'normal' : /metallicRoughness/.test(entry.name) ? 'metallicRoughness' : null;
    if (!role || !files[role]) { failures.push(`image ${entry.image}: no '${role}' file in the bake to compare with`); continue; }
    if (entry.format !== 'rg8' && entry.format !== 'rgba8') continue; // block-compressed: nothing to compare code for code
    const pngChannels = role === 'normal' ? [0, 1] : [1];
    const ktxStride = entry.format === 'rg8' ? 2 : 4;
    let differing = 0, total = 0;
    entry.container.levels.forEach((level, k) => {
      const png = readPng(path.join(bakeDir, files[role][k]));
      for (let i = 0; i < png.width * png.height; ++i)
        for (const c of pngChannels) {
          total++;
          if (level.levelData[i * ktxStride + c] !== png.data[i * png.channels + c]) differing++;
        }
    });
    compared.push({ image: entry.image, role, codes: total, differing });
    if (differing) failures.push(`image ${entry.image} (${role}): ${differing} of ${total} codes differ from the bake's PNG mips`);
  }
}

for (const e of ktx) delete e.container;
console.log(JSON.stringify({ asset: assetPath, validator: { errors: issues.numErrors, errorsOfTheInput: errors.length - newErrors.length, warnings: issues.numWarnings,
  infos: issues.numInfos, codes }, ktx2: ktx, compared, mixtures, failures }, null, 2));
process.exit(failures.length ? 1 : 0);
