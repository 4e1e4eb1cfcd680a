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
// uncompressed RG8/RGBA8 or BC5/BC3 levels with the whole mip chain it baked — read by three.js's own
// KTX2Loader (which reads such files without its Basis transcoder). Where no KTX2Loader is set, the
// texture's PNG `source` loads instead, as in any viewer that does not know the extension.

export const KHR_TEXTURE_KTX = 'KHR_texture_ktx';

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

// Registers every Burnish plugin on a GLTFLoader and returns it.
export function registerBurnish(gltfLoader) {
    gltfLoader.register((parser) => new GLTFTextureKtxExtension(parser));
    return gltfLoader;
}
