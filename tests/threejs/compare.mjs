// Burnish's one-lobe roughness chains rendered by a real third-party client, three.js in headless
// Chromium, against that client's own supersampled reference (page.html has the scene).
//
//   node tests/threejs/compare.mjs --burnish build/bin/burnish --maps A.png,B.png [--distances 2,8,32]
//        [--methods vmf,variance-to-gloss,fitted] [--power 256] [--supersample 32] [--previews DIR]
//        [--assert-never-worse fitted] [--assert-mixture M] [--anisotropy N] [--anisotropy-on] [--json FILE] [--gltf]
//        [--shape plane|sphere] [--orbit FRAMES] [--orbit-degrees D] [--orbit-supersample N]
//
// Each map is baked with the gltf preset (8-bit PNG, one file per mip, as an engine receives it) once per
// method; three.js draws the plane with the map's own PNG (its mips) and constant roughness ("three.js
// alone"), then with each method's roughness mip chain as a DataTexture; the reference draws the finest
// normals (no mips) supersampled. Printed per map and distance: relative L1 and energy against the
// reference, the ratio to three.js alone, and the reference's own noise (a second reference shifted by
// half a sample). --assert-never-worse M exits 1 when M is worse than three.js alone by more than that
// noise at any distance (the test suite's check). --anisotropy N samples both maps with N× anisotropic
// filtering (three.js's default is none: the mip level follows the footprint's long axis).
// --anisotropy-on adds the row "anisotropy on, round": three.js alone with KHR_materials_anisotropy's path
// switched on and a round lobe (MeshPhysicalMaterial, anisotropy 1e-4), which three.js forms in the
// geometric tangent frame: what turning the extension on costs before any anisotropy is stored.
// --gltf goes through glTF instead: each map becomes the test plane asset (tests/data/gltf/plane.gltf,
// roughnessFactor the base roughness, metal), "three.js alone" is that asset as GLTFLoader loads it, and
// each method's row ("gltf <method>") is the asset `burnish gltf --method <method>` wrote, loaded by
// GLTFLoader with three.js's KTX2Loader and resources/three/burnish-gltf.js (KHR_texture_ktx): the KTX2
// normal and metallicRoughness chains as Burnish baked them. The reference is the original's normal map
// without mips. A method "fitted+anisotropy=on" (or =auto) adds burnish gltf --anisotropy: the
// anisotropic fit as KHR_materials_anisotropy, which three.js's MeshPhysicalMaterial draws. The method
// "mixture" is `burnish gltf --method mixture`: BURNISH_lobe_mixture, drawn by burnish-gltf.js's patch of
// the material (each lobe through three.js's own BRDF_GGX). --assert-mixture M exits 1 unless row M meets the
// mixture's targets: never worse than three.js alone beyond the reference's noise, at most half its error
// in the mean over maps at every distance of 8x and more, and energy within [0.9, 1.1] everywhere.
// With --gltf: --shape sphere draws a UV sphere (tangents from its UVs) instead of the asset's plane, the
// minification then at its equator facing the camera; --orbit N also measures the shimmer of a slow orbit
// (render/shimmer.h's measure: N frames, the camera and light turned --orbit-degrees, default 0.5, about
// the up axis between them; the mean absolute change of a pixel's grey between consecutive frames) for the
// reference (supersampled --orbit-supersample times, default 8) and every row, printed with each row's
// ratio to the reference's: 1 is the motion alone, more is flicker.
import {spawnSync} from 'node:child_process';
import fs from 'node:fs';
import http from 'node:http';
import os from 'node:os';
import path from 'node:path';
import {fileURLToPath} from 'node:url';
import puppeteer from 'puppeteer-core';

const here = path.dirname(fileURLToPath(import.meta.url));

function parseArgs(argv) {
    const o = {distances: [2, 8, 32], methods: ['vmf', 'variance-to-gloss', 'fitted'], power: 256, supersample: 32,
               maps: [], burnish: '', previews: '', assert: '', assertMixture: '', json: '', anisotropy: 1, anisotropyOn: false, gltf: false,
               shape: 'plane', orbit: 0, orbitDegrees: 0.5, orbitSupersample: 8,
               chromium: process.env.BURNISH_CHROMIUM || '/usr/bin/chromium'};
    for (let i = 2; i < argv.length; ++i) {
        const a = argv[i], v = argv[i + 1];
        const take = () => { ++i; if (v === undefined) throw new Error(`${a} needs a value`); return v; };
        if (a === '--burnish') o.burnish = take();
        else if (a === '--maps') o.maps = take().split(',').filter(Boolean);
        else if (a === '--distances') o.distances = take().split(',').map(Number);
        else if (a === '--methods') o.methods = take().split(',').filter(Boolean);
        else if (a === '--power') o.power = Number(take());
        else if (a === '--supersample') o.supersample = Number(take());
        else if (a === '--previews') o.previews = take();
        else if (a === '--assert-never-worse') o.assert = take();
        else if (a === '--assert-mixture') o.assertMixture = take();
        else if (a === '--json') o.json = take();
        else if (a === '--chromium') o.chromium = take();
        else if (a === '--anisotropy') o.anisotropy = Number(take());
        else if (a === '--anisotropy-on') o.anisotropyOn = true;
        else if (a === '--gltf') o.gltf = true;
        else if (a === '--shape') o.shape = take();
        else if (a === '--orbit') o.orbit = Number(take());
        else if (a === '--orbit-degrees') o.orbitDegrees = Number(take());
        else if (a === '--orbit-supersample') o.orbitSupersample = Number(take());
        else if (a === '--probe-lod') o.probeLod = true;
        else throw new Error(`unknown argument ${a}`);
    }
    if (!o.probeLod && (!o.burnish || !o.maps.length)) throw new Error('give --burnish BIN and --maps A.png[,B.png...]');
    if (o.distances.some(d => !(d > 0)) || !(o.power > 0) || !(o.supersample >= 1))
        throw new Error('distances, power and supersample must be positive');
    if (!['plane', 'sphere'].includes(o.shape)) throw new Error('--shape is plane or sphere');
    if ((o.shape !== 'plane' || o.orbit) && !o.gltf && !o.probeLod) throw new Error('--shape and --orbit go with --gltf');
    if (o.orbit && !(o.orbit >= 2 && o.orbitDegrees > 0 && o.orbitSupersample >= 1))
        throw new Error('--orbit takes at least 2 frames, a positive step and supersample');
    return o;
}

// Every level of one file of a bake: the file, then its _mipK siblings, in order.
function chainFiles(dir, stem, file) {
    const out = [path.join(dir, `${stem}_${file}.png`)];
    for (let k = 1; fs.existsSync(path.join(dir, `${stem}_${file}_mip${k}.png`)); ++k)
        out.push(path.join(dir, `${stem}_${file}_mip${k}.png`));
    return out;
}

function bake(o, map, method, out) {
    const r = spawnSync(o.burnish, ['bake', map, '--preset', 'gltf', '--method', method, '--power', String(o.power),
                                    '--format', 'png8', '--out', out, '--force', '--allow-implausible'],
                        {encoding: 'utf8'});
    if (r.status !== 0) throw new Error(`burnish bake ${map} --method ${method}: ${r.stderr.trim()}`);
    return chainFiles(out, path.basename(map).replace(/\.[^.]+$/, ''), 'metallicRoughness');
}

// The test plane asset with `map` as its normal map and base roughness `roughness`, in `dir`.
function planeAsset(map, roughness, dir) {
    fs.mkdirSync(dir, {recursive: true});
    const doc = JSON.parse(fs.readFileSync(path.join(here, '..', 'data', 'gltf', 'plane.gltf'), 'utf8'));
    doc.materials[0].pbrMetallicRoughness = {baseColorFactor: [1, 1, 1, 1], metallicFactor: 1, roughnessFactor: roughness};
    fs.writeFileSync(path.join(dir, 'plane.gltf'), JSON.stringify(doc));
    fs.copyFileSync(map, path.join(dir, 'normal.png'));
    return path.join(dir, 'plane.gltf');
}

// A method name with "+anisotropy=auto|on" asks burnish gltf for KHR_materials_anisotropy too.
function gltf(o, asset, method, out) {
    const [name, extra] = method.split('+');
    const args = ['gltf', asset, '--method', name, '--out', out, '--force', '--allow-implausible'];
    if (extra) args.push('--anisotropy', extra.replace(/^anisotropy=/, ''));
    const r = spawnSync(o.burnish, args, {encoding: 'utf8'});
    if (r.status !== 0) throw new Error(`burnish gltf ${asset} --method ${method}: ${r.stderr.trim()}`);
    return path.join(out, 'plane.gltf');
}

// A file under `root` named by the rest of a URL, or null when it would lie outside.
function within(root, rest) {
    const file = path.resolve(root, '.' + path.posix.normalize('/' + rest));
    return file.startsWith(path.resolve(root) + path.sep) ? file : null;
}

// Serves three.js (its build and addons), Burnish's three.js module, the page, the files it is told about
// and the folders under /asset<k>/, on 127.0.0.1 only.
function serve(files, folders = new Map()) {
    const types = {'.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript', '.png': 'image/png',
                   '.gltf': 'model/gltf+json', '.ktx2': 'image/ktx2', '.wasm': 'application/wasm'};
    const server = http.createServer((req, res) => {
        const url = decodeURIComponent(req.url.split('?')[0]);
        let file = null;
        const folder = [...folders.keys()].find(prefix => url.startsWith(prefix + '/'));
        if (url === '/page.html') file = path.join(here, 'page.html');
        else if (url.startsWith('/three/')) file = within(path.join(here, 'node_modules', 'three'), url.slice(7));
        else if (url.startsWith('/burnish/three/')) file = within(path.join(here, '..', '..', 'resources', 'three'), url.slice(15));
        else if (folder) file = within(folders.get(folder), url.slice(folder.length + 1));
        else if (files.has(url)) file = files.get(url);
        if (!file || !fs.existsSync(file)) {
            res.writeHead(404).end();
            return;
        }
        res.writeHead(200, {'Content-Type': types[path.extname(file)] || 'application/octet-stream'});
        fs.createReadStream(file).pipe(res);
    });
    return new Promise(resolve => server.listen(0, '127.0.0.1', () => resolve(server)));
}

async function main() {
    const o = parseArgs(process.argv);
    const work = fs.mkdtempSync(path.join(os.tmpdir(), 'burnish-threejs-'));
    const files = new Map();
    const folders = new Map();
    const cases = [];
    // Base roughness of power s under the gltf preset's conversion: alpha = sqrt(2/(s+2)), r = sqrt(alpha).
    const roughness = Math.sqrt(Math.sqrt(2 / (o.power + 2)));
    try {
        for (const [mi, map] of o.maps.entries()) {
            if (o.gltf) {
                const asset = planeAsset(map, roughness, path.join(work, `m${mi}`, 'original'));
                folders.set(`/asset${mi}/original`, path.dirname(asset));
                const assets = {};
                for (const method of o.methods) {
                    const out = gltf(o, asset, method, path.join(work, `m${mi}`, method.replace(/[^a-z0-9-]/gi, '_')));
                    const folder = method.replace(/[^a-z0-9-]/gi, '_');
                    folders.set(`/asset${mi}/${folder}`, path.dirname(out));
                    assets[`gltf ${method}`] = `/asset${mi}/${folder}/plane.gltf`;
                }
                cases.push({map, original: `/asset${mi}/original/plane.gltf`, assets});
                continue;
            }
            files.set(`/map${mi}/normal.png`, map);
            const chains = {};
            for (const method of o.methods) {
                const levels = bake(o, map, method, path.join(work, `m${mi}-${method}`));
                chains[method] = levels.map((f, k) => {
                    const url = `/map${mi}/${method}/${k}.png`;
                    files.set(url, f);
                    return url;
                });
            }
            cases.push({map, normal: `/map${mi}/normal.png`, chains});
        }
        const server = await serve(files, folders);
        const port = server.address().port;
        const browser = await puppeteer.launch({
            executablePath: o.chromium,
            args: ['--headless=new', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--no-sandbox',
                   '--ignore-gpu-blocklist'],
        });
        const results = [];
        let failed = false;
        try {
            const page = await browser.newPage();
            page.on('pageerror', e => console.error(`page error: ${e.message}`));
            await page.goto(`http://127.0.0.1:${port}/page.html`);
            await page.waitForFunction('window.ready === true', {timeout: 60000});
            if (o.probeLod)
                for (const d of o.distances) {
                    const p = await page.evaluate(cfg => window.probeLod(cfg), {shape: o.shape, minification: d});
                    console.log(`${o.shape} ${d}x: mip level mean ${p.mean.toFixed(2)}, 10/50/90th percentiles ` +
                                `${p.p10.toFixed(2)}/${p.p50.toFixed(2)}/${p.p90.toFixed(2)} over ${p.pixels} pixels`);
                }
            for (const c of cases)
                for (const d of o.distances) {
                    const r = o.gltf
                        ? await page.evaluate(cfg => window.runGltfCase(cfg), {
                              original: c.original, assets: c.assets, minification: d, supersample: o.supersample,
                              anisotropy: o.anisotropy, previews: Boolean(o.previews), shape: o.shape,
                              orbitFrames: o.orbit, orbitDegrees: o.orbitDegrees, orbitSupersample: o.orbitSupersample})
                        : await page.evaluate(cfg => window.runCase(cfg), {
                              normal: c.normal, chains: c.chains, minification: d, roughness, supersample: o.supersample,
                              anisotropy: o.anisotropy, anisotropyOn: o.anisotropyOn,
                              previews: Boolean(o.previews)});
                    results.push({map: path.basename(c.map), distance: d, ...r});
                    if (o.previews) {
                        fs.mkdirSync(o.previews, {recursive: true});
                        for (const [name, url] of Object.entries(r.previews))
                            fs.writeFileSync(path.join(o.previews, `${path.basename(c.map, '.png')}-${d}x-${name.replace(/[^a-z0-9.-]+/gi, '_')}.png`),
                                             Buffer.from(url.split(',')[1], 'base64'));
                    }
                    const alone = r.results['three.js alone'];
                    const line = [`${path.basename(c.map)} ${d}x (reference noise ${r.noise.relativeL1.toFixed(4)}, ` +
                                  `${r.seconds.toFixed(1)} s):`];
                    for (const [name, v] of Object.entries(r.results))
                        line.push(`  ${name.padEnd(18)} rel. L1 ${v.relativeL1.toFixed(4)}  energy ${v.energy.toFixed(3)}  ` +
                                  `ratio to three.js alone ${(v.relativeL1 / alone.relativeL1).toFixed(3)}`);
                    if (r.shimmer)
                        line.push(`  shimmer of a ${o.orbit}-frame orbit (ratio to the reference's ${r.shimmer.reference.toExponential(3)}): ` +
                                  Object.entries(r.shimmer).filter(([n]) => n !== 'reference')
                                      .map(([n, v]) => `${n} ${(v / r.shimmer.reference).toFixed(3)}`).join(', '));
                    console.log(line.join('\n'));
                    for (const m of [o.assert, o.assertMixture])
                        if (m && r.results[m] && r.results[m].relativeL1 > alone.relativeL1 + r.noise.relativeL1) {
                            console.log(`  FAIL: ${m} is worse than three.js alone beyond the reference's noise`);
                            failed = true;
                        }
                    if (o.assertMixture && r.formats && !(r.formats[o.assertMixture] || {}).mixture) {
                        // The module did not patch the material: the row would be the fitted lobe's.
                        console.log(`  FAIL: ${o.assertMixture} was not drawn as a lobe mixture by burnish-gltf.js`);
                        failed = true;
                    }
                    const mix = o.assertMixture && r.results[o.assertMixture];
                    if (mix && !(mix.energy >= 0.9 && mix.energy <= 1.1)) {
                        console.log(`  FAIL: ${o.assertMixture}'s energy ${mix.energy.toFixed(3)} is outside [0.9, 1.1]`);
                        failed = true;
                    }
                }
            if (results.length) console.log(`renderer: ${results[0].renderer}`);
        } finally {
            await browser.close();
            server.close();
        }
        if (!results.length) return;
        // Means per distance, each method's ratio to three.js alone.
        const names = Object.keys(results[0].results);
        console.log('\n| distance | ' + names.map(n => `${n} rel. L1 (energy)`).join(' | ') + ' | ' +
                    names.slice(1).map(n => `${n} / alone`).join(' | ') + ' |');
        console.log('| --- |' + ' ---: |'.repeat(2 * names.length - 1));
        for (const d of o.distances) {
            const at = results.filter(r => r.distance === d);
            const mean = (n, k) => at.reduce((a, r) => a + r.results[n][k], 0) / at.length;
            const ratio = n => at.reduce((a, r) => a + r.results[n].relativeL1 / r.results['three.js alone'].relativeL1, 0) / at.length;
            console.log(`| ${d}x | ` + names.map(n => `${mean(n, 'relativeL1').toFixed(4)} (${mean(n, 'energy').toFixed(3)})`).join(' | ') +
                        ' | ' + names.slice(1).map(n => ratio(n).toFixed(3)).join(' | ') + ' |');
        }
        if (o.orbit) {
            console.log('\n| distance | ' + names.map(n => `${n} shimmer / reference`).join(' | ') + ' |');
            console.log('| --- |' + ' ---: |'.repeat(names.length));
            for (const d of o.distances) {
                const at = results.filter(r => r.distance === d);
                const ratio = n => at.reduce((a, r) => a + r.shimmer[n] / r.shimmer.reference, 0) / at.length;
                console.log(`| ${d}x | ` + names.map(n => ratio(n).toFixed(3)).join(' | ') + ' |');
            }
        }
        if (o.assertMixture)
            for (const d of o.distances.filter(d => d >= 8)) {
                const at = results.filter(r => r.distance === d && r.results[o.assertMixture]);
                const mean = n => at.reduce((a, r) => a + r.results[n].relativeL1, 0) / at.length;
                const ratio = mean(o.assertMixture) / mean('three.js alone');
                if (!at.length) {
                    console.log(`FAIL: no row ${o.assertMixture}`);
                    failed = true;
                } else if (!(ratio <= 0.5)) {
                    console.log(`FAIL: ${o.assertMixture} at ${d}x: mean ${mean(o.assertMixture).toFixed(4)} is ` +
                                `${ratio.toFixed(3)} of three.js alone's ${mean('three.js alone').toFixed(4)} (target 0.5)`);
                    failed = true;
                }
            }
        if (o.json) fs.writeFileSync(o.json, JSON.stringify(results.map(({previews, ...r}) => r), null, 1));
        if (o.assert || o.assertMixture)
            console.log(failed ? `${o.assert || o.assertMixture}: a target is missed (above)` :
                                 `${[o.assert, o.assertMixture].filter(Boolean).join(', ')}: every target met`);
        process.exitCode = failed ? 1 : 0;
    } finally {
        fs.rmSync(work, {recursive: true, force: true});
    }
}

main().catch(e => {
    console.error(`compare.mjs: ${e.message}`);
    process.exitCode = 2;
});
