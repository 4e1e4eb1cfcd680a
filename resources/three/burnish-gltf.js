// three.js GLTFLoader plugins for what `burnish gltf` writes. ES module; three.js is imported by the
// caller (this file imports nothing), so it works with any import map or bundler.
//
//   import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
//   import { KTX2Loader } from 'three/addons/loaders/KTX2Loader.js';
//   import { registerBurnish } from './burnish-gltf.js';
//   const ktx2 = new KTX2Loader().detectSupport(renderer);
//   const loader = registerBurnish(new GLTFLoader().setKTX2Loader(ktx2));
//
// KHR_texture_ktx (a draft Khronos extension): a texture's KTX2 image of any payload — here Burnish's
// uncompressed RG8/RGBA8/RGBA16F or BC5/BC3 levels with the whole mip chain it baked — read by three.js's
// own KTX2Loader (which reads such files without its Basis transcoder). Where no KTX2Loader is set, the
// texture's PNG `source` loads instead, as in any viewer that does not know the extension.
//
// BURNISH_lobe_mixture (`burnish gltf --method mixture`): up to four lobes per texel, each an RGBA16F
// texture of (w, w·b.x, w·b.y, w·spread) in the normal texture's UV set, with every mip Burnish fitted.
// The material's MeshStandardMaterial/MeshPhysicalMaterial is patched (onBeforeCompile) to shade each
// lobe with three.js's own BRDF_GGX about the normal of the lobe's mean slope (through the same tangent
// frame and normalScale as the normal map), its roughness widened by the lobe's spread, weighted by its
// share: direct lights and, with an environment map, image-based light. The material's roughness becomes
// the extension's base roughness (the metallicRoughness texture's G holds the fitted one-lobe roughness
// for clients without this module). Needs a KTX2Loader; without one the material stays as written.

export const KHR_TEXTURE_KTX = 'KHR_texture_ktx';
export const BURNISH_LOBE_MIXTURE = 'BURNISH_lobe_mixture';

// The same shape as GLTFLoader's own KHR_texture_basisu plugin (GLTFTextureBasisUExtension).
export class GLTFTextureKtxExtension {
    constructor(parser) {
        this.parser = parser;
        this.name = KHR_TEXTURE_KTX;
    }

    loadTexture(textureIndex) {
        const json = this.parser.json;
        const textureDef = json.textures[textureIndex];
        if (!textureDef.extensions || !textureDef.extensions[this.name]) return null;
        const loader = this.parser.options.ktx2Loader;
        if (!loader) {
            if (json.extensionsRequired && json.extensionsRequired.includes(this.name))
                throw new Error('burnish-gltf: setKTX2Loader must be called before loading KHR_texture_ktx textures');
            return null; // the PNG source
        }
        return this.parser.loadTextureImage(textureIndex, textureDef.extensions[this.name].source, loader);
    }
}

// The GLSL of one lobe, twin of core's mixtureGgxLobe (core/include/burnish/core/prefilter/lobe_mixture.h);
// tests/render/test_twins.cpp compiles the text between the markers and checks it against core.
// Olano & Baker 2010, "LEAN Mapping": slope Gaussians convolve by adding covariances; Walter et al. 2007:
// α² = 2σ²
export const MIXTURE_GGX_LOBE_GLSL = /* glsl */ `
/* BEGIN mixtureGgxLobe */
// A stored lobe t = (w, w*b.x, w*b.y, w*S) of a texel whose weights sum to total: returns its share
// w/total and gives the tangent-space normal of its mean slope b = (w*b)/w and its GGX alpha
// min(1, sqrt(alpha0^2 + c*max(0, S - |b|^2))); an empty lobe has share 0, normal +z and alpha0.
float mixtureGgxLobe(vec4 t, float total, float alpha0, float spreadScale, out vec3 normal, out float alpha) {
    float a0 = alpha0 > 0.0 ? min(alpha0, 1.0) : 0.0;
    alpha = a0;
    normal = vec3(0.0, 0.0, 1.0);
    float w = t.x;
    if (!(w > 0.0) || !(total > 0.0) || isinf(total)) return 0.0;
    float r = 1.0 / w;
    vec2 b = t.yz * r;
    float spread = t.w * r - dot(b, b);
    float c = spreadScale > 0.0 ? spreadScale : 0.0;
    alpha = min(sqrt(a0 * a0 + c * (spread > 0.0 && !isinf(spread) ? spread : 0.0)), 1.0);
    vec3 n = vec3(b, 1.0);
    float len = length(n);
    normal = isinf(len) || isnan(len) ? vec3(0.0, 0.0, 1.0) : n / len;
    return min(w / total, 1.0);
}
/* END mixtureGgxLobe */
`;

// Replaces `from` in `text` by `to`, or throws: a three.js whose shader chunks changed must not be
// patched silently wrong.
function replaceOnce(text, from, to, what) {
    const at = text.indexOf(from);
    if (at < 0) throw new Error(`burnish-gltf: this three.js has no '${from.slice(0, 60)}' in ${what}`);
    return text.slice(0, at) + to + text.slice(at + from.length);
}

// Patches `material` (MeshStandardMaterial or MeshPhysicalMaterial with a tangent-space normal map) to
// shade the mixture of `textures` (the lobe textures, 1..4) with base perceptual roughness `roughness`
// and spread scale `spreadScale`, from `chunks` (THREE.ShaderChunk, given by the caller).
export function applyLobeMixture(material, textures, roughness, spreadScale, chunks) {
    const K = textures.length;
    if (K < 1 || K > 4) throw new Error(`burnish-gltf: ${K} lobes (1 to 4)`);
    if (!material.normalMap) throw new Error('burnish-gltf: the lobe mixture needs the material\'s normal map');
    material.roughness = roughness;
    material.roughnessMap = null;
    const lobes = [...Array(K).keys()];
    material.userData.burnishLobeMixture = {lobes: K, roughness, spreadScale};
    material.onBeforeCompile = (shader) => {
        for (const i of lobes) shader.uniforms[`burnishLobe${i}`] = {value: textures[i]};
        shader.uniforms.burnishSpreadScale = {value: spreadScale};
        shader.defines = shader.defines || {};
        shader.defines.BURNISH_LOBE_MIXTURE = K;
        const declarations = `
${lobes.map(i => `uniform sampler2D burnishLobe${i};`).join('\n')}
uniform float burnishSpreadScale;
vec3 burnishLobeNormal[BURNISH_LOBE_MIXTURE];
float burnishLobeShare[BURNISH_LOBE_MIXTURE];
float burnishLobeRoughness[BURNISH_LOBE_MIXTURE];
${MIXTURE_GGX_LOBE_GLSL}`;
        // Each lobe: BRDF_GGX about its normal with its roughness, times its share and its own cosine.
        const specular = `
vec3 burnishMixtureSpecular(const in vec3 lightDir, const in vec3 viewDir, const in PhysicalMaterial material) {
    vec3 sum = vec3(0.0);
    for (int i = 0; i < BURNISH_LOBE_MIXTURE; ++i) {
        PhysicalMaterial lobe = material;
        lobe.roughness = burnishLobeRoughness[i];
        sum += burnishLobeShare[i] * saturate(dot(burnishLobeNormal[i], lightDir)) *
               BRDF_GGX(lightDir, viewDir, burnishLobeNormal[i], lobe);
    }
    return sum;
}
`;
        const direct = 'reflectedLight.directSpecular += irradiance * specularBRDF * material.multiScatteringCompensation;';
        const physical = replaceOnce(
            replaceOnce(chunks.lights_physical_pars_fragment, 'void RE_Direct_Physical(', specular + 'void RE_Direct_Physical(',
                        'lights_physical_pars_fragment'),
            direct, 'reflectedLight.directSpecular += directLight.color * burnishMixtureSpecular( directLight.direction, geometryViewDir, material ) * material.multiScatteringCompensation;',
            'lights_physical_pars_fragment');
        const ibl = 'vec3 iblRadiance = getIBLRadiance( geometryViewDir, geometryNormal, material.roughness );';
        const maps = replaceOnce(chunks.lights_fragment_maps, ibl, `vec3 iblRadiance = vec3( 0.0 );
		for ( int i = 0; i < BURNISH_LOBE_MIXTURE; ++ i )
			iblRadiance += burnishLobeShare[ i ] * getIBLRadiance( geometryViewDir, burnishLobeNormal[ i ], burnishLobeRoughness[ i ] );`,
                                 'lights_fragment_maps');
        // The lobes of this pixel, once three.js has its roughness (material.roughness, geometric
        // roughness included) and the normal map's tangent frame (tbn).
        const setup = `
{
    vec4 burnishT[BURNISH_LOBE_MIXTURE];
${lobes.map(i => `    burnishT[${i}] = texture2D(burnishLobe${i}, vNormalMapUv);`).join('\n')}
    float total = 0.0;
    for (int i = 0; i < BURNISH_LOBE_MIXTURE; ++i) total += max(burnishT[i].x, 0.0);
    float alpha0 = pow2(max(material.roughness, 0.045));
    for (int i = 0; i < BURNISH_LOBE_MIXTURE; ++i) {
        vec3 n;
        float a;
        burnishLobeShare[i] = mixtureGgxLobe(burnishT[i], total, alpha0, burnishSpreadScale, n, a);
        n.xy *= normalScale; // as three.js scales the normal map's
        burnishLobeNormal[i] = normalize(tbn * n);
        burnishLobeRoughness[i] = sqrt(a);
    }
}
`;
        let fs = shader.fragmentShader;
        fs = replaceOnce(fs, '#include <common>', '#include <common>\n' + declarations, 'the fragment shader');
        fs = replaceOnce(fs, '#include <lights_physical_pars_fragment>', physical, 'the fragment shader');
        fs = replaceOnce(fs, '#include <lights_fragment_maps>', maps, 'the fragment shader');
        fs = replaceOnce(fs, '#include <lights_physical_fragment>', '#include <lights_physical_fragment>\n' + setup,
                         'the fragment shader');
        shader.fragmentShader = fs;
    };
    const key = material.customProgramCacheKey.bind(material);
    material.customProgramCacheKey = () => `${key()}|burnish-lobe-mixture-${K}`;
    material.needsUpdate = true;
    return material;
}

// BURNISH_lobe_mixture: loads each material's lobe textures with the rest of the asset and, once the
// scene is built, patches every material made from such a material definition (GLTFLoader's clones too).
export class GLTFBurnishLobeMixtureExtension {
    constructor(parser, chunks) {
        this.parser = parser;
        this.chunks = chunks;
        this.name = BURNISH_LOBE_MIXTURE;
        this.loaded = new Map(); // material index -> {extension, textures}
    }

    extendMaterialParams(materialIndex, materialParams) {
        const def = this.parser.json.materials[materialIndex];
        const ext = def.extensions && def.extensions[this.name];
        if (!ext) return Promise.resolve();
        if (!this.chunks) {
            console.warn('burnish-gltf: registerBurnish(loader, THREE.ShaderChunk) shades BURNISH_lobe_mixture; ' +
                         'without the chunks the fitted roughness is drawn');
            return Promise.resolve();
        }
        if (!this.parser.options.ktx2Loader) {
            console.warn('burnish-gltf: BURNISH_lobe_mixture needs a KTX2Loader (its lobes are RGBA16F KTX2); ' +
                         'the fitted roughness is drawn instead');
            return Promise.resolve();
        }
        const infos = ext.lobeTextures || [];
        if (infos.length < 1 || infos.length > 4 || infos.length !== ext.lobes)
            return Promise.reject(new Error(`burnish-gltf: material ${materialIndex}: ${infos.length} lobe textures for ${ext.lobes} lobes`));
        return Promise.all(infos.map(info => this.parser.getDependency('texture', info.index))).then(textures => {
            this.loaded.set(materialIndex, {ext, textures});
        });
    }

    afterRoot(result) {
        if (!this.loaded.size) return null;
        const done = new Set();
        for (const scene of result.scenes || [result.scene])
            scene.traverse(object => {
                if (!object.isMesh) return;
                for (const material of Array.isArray(object.material) ? object.material : [object.material]) {
                    if (done.has(material)) continue;
                    done.add(material);
                    const mapping = this.parser.associations.get(material);
                    const entry = mapping && this.loaded.get(mapping.materials);
                    if (!entry) continue;
                    applyLobeMixture(material, entry.textures, entry.ext.roughnessFactor ?? 1.0,
                                     entry.ext.spreadScale ?? 1.0, this.chunks);
                }
            });
        return null;
    }
}

// Registers every Burnish plugin on a GLTFLoader and returns it. `shaderChunks` is THREE.ShaderChunk (this
// module imports nothing): without it the lobe mixture is not shaded and its materials draw the fitted
// roughness.
export function registerBurnish(gltfLoader, shaderChunks = null) {
    gltfLoader.register((parser) => new GLTFTextureKtxExtension(parser));
    gltfLoader.register((parser) => new GLTFBurnishLobeMixtureExtension(parser, shaderChunks));
    return gltfLoader;
}
