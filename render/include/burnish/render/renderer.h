// The scene renderer: draws a Scene's material the way an engine would (one program per feature
// set, the method's baked textures), the supersampled ground truth beside it, and debug views.
// Everything here needs the OpenGL context the Renderer was created in to be current.
#pragma once

#include <burnish/core/util/result.h>
#include <burnish/render/features.h>
#include <burnish/render/program.h>
#include <burnish/render/scene.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace burnish {
class LiveGlossBake;
struct TexelRect;
} // namespace burnish

namespace burnish::render {

/// Where render() draws: a framebuffer object id (0 = the default framebuffer) and its size.
struct RenderTarget {
    unsigned framebuffer = 0;
    int width = 0;
    int height = 0;
    /// Optional scissor rectangle in pixels (x, y from the bottom-left, as glScissor): only these
    /// pixels of the target are written, the image is still framed for the whole target (an A/B
    /// split draws two scenes into one target). A width or height of 0 writes the whole target.
    int scissorX = 0;
    int scissorY = 0;
    int scissorWidth = 0;
    int scissorHeight = 0;

    /// The frame while the camera moves (an orbit, a zoom): the view is drawn at half the target's
    /// width and height and scaled up bilinearly, a quarter of the fragments; the caller draws the full
    /// frame when the camera rests. Debug views and the reference ignore it.
    bool interactive = false;

    /// The frame at rest of a mixture filtered after shading (MaterialSettings::mixtureFiltering
    /// Stochastic, more than one pass), drawn a pass a call: each call adds the next of the scene's
    /// mixtureSamples passes to the average of the calls before and shows that average, as long as
    /// the scene as drawn (every setting, the maps, and the inputs a background bake is still
    /// replacing) and the target's size stay the same; anything else starts again from the first
    /// pass. Once every pass is in, a call shows the average again. progressiveDone() tells the
    /// caller whether to call again. Other materials, debug views and interactive frames ignore it.
    bool progressive = false;

    bool hasScissor() const { return scissorWidth > 0 && scissorHeight > 0; }
};

enum class ImageKind {
    Hdr,     // linear radiance before exposure and tonemapping (RGBA32F)
    Display, // after exposure and tonemapping, sRGB-encoded, in [0, 1] (read from RGBA8)
};

class Renderer {
public:
    /// Creates the renderer in the current context (which must be OpenGL 3.3 core or later).
    static Result<std::unique_ptr<Renderer>> create();
    ~Renderer();
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    /// Takes a scene: bakes with core's bake() only what changed (keyed by the normal map's
    /// identity, the gloss map's, the method, its parameters, the base power and the encoding),
    /// uploads the textures, loads the mesh if it changed, and compiles or fetches the program.
    /// Errors: a bake failure, an unreadable OBJ, a shader that does not compile.
    Status setScene(const Scene& scene);
    const Scene& scene() const;

    /// Draws the current scene into `target` (HDR pass, then the tonemap pass into the target).
    Status render(const RenderTarget& target);
    /// Draws into an off-screen target of the given size and reads it back: RGBA floats, row 0 at
    /// the top. Errors: a size outside 1..GL_MAX_RENDERBUFFER_SIZE, no scene.
    Result<std::vector<float>> renderToImage(int width, int height, ImageKind kind = ImageKind::Hdr);
    /// The ground truth of the texts' "render big, downsample", done as `samplesPerPixel` jittered
    /// passes (sub-pixel projection offsets from the Halton (2, 3) sequence) with the finest mip and
    /// the base power, added up in RGBA32F and divided by the count. Errors as renderToImage, and a
    /// sample count outside 1..4096.
    Result<std::vector<float>> renderReference(int width, int height, int samplesPerPixel,
                                               ImageKind kind = ImageKind::Hdr);
    /// The same reference, exposed and tonemapped into `target` (its scissor respected). Errors as
    /// above.
    Status renderReference(const RenderTarget& target, int samplesPerPixel);

    /// Compiles the material as the ubershader (every feature in, switched by uniforms) instead of
    /// the scene's specialized program: only to measure against. Takes effect at the next setScene.
    /// With background bakes on, setScene never runs core's bake on the caller's thread once a
    /// material has been baked: a scene whose bake is not in yet is drawn with the last baked
    /// material's maps, method and power (its colours, view and light as requested) while the bake
    /// runs on a worker; `onReady` is called from that worker when it finishes, and the next
    /// setScene takes it in. One bake runs at a time: a material requested meanwhile stops the
    /// running bake at its next level and is baked next (the last finished bake is drawn until
    /// then), so the newest request is always baked last.
    /// Off by default (the command line and the tests draw exactly the scene they set).
    void setBackgroundBakes(bool on, std::function<void()> onReady = {});
    /// Uploads each baked chain from its first level no larger than `size` on a side (0: every
    /// level, the default): a display shows no more, and an 8192² chain is gigabytes to upload.
    /// Applies to the bakes uploaded after the call.
    void setMaxTextureSize(int size);
    /// Painting: the drawn bake's gloss texture made from a live gloss chain (core's LiveGlossBake,
    /// which its caller keeps up to date stroke by stroke) instead of baking `material` again.
    /// `material` is the next scene's material, equal to the drawn one but for its glossMap, whose
    /// values are the live bake's authored gloss (the caller's promise: they are not compared). With
    /// `dirty` (one rectangle per level of the live chain, as LiveGlossBake::lastRecomputedRects)
    /// only those texels are uploaded, else every uploaded level; the drawn bake then stands for
    /// `material`, so the next setScene bakes nothing, and a bake still running is dropped. False,
    /// changing nothing, where the live chain is not what a bake would upload (another map, method,
    /// power, encoding, kernel or border; no gloss texture drawn). Errors: an upload that fails.
    Result<bool> replaceGloss(const MaterialSettings& material, const LiveGlossBake& live,
                              const std::vector<TexelRect>* dirty);
    /// The gloss values the drawn bake stands for (null: none, or no bake).
    std::shared_ptr<const std::vector<float>> drawnGlossMap() const;
    /// Whether the last setScene draws the last baked material because the requested one is still
    /// baking in the background.
    bool bakePending() const;
    /// False while the last render() drew a progressive frame (RenderTarget::progressive) whose
    /// average holds fewer passes than the scene's mixtureSamples: another call adds the next.
    bool progressiveDone() const;
    /// The passes in the last progressive frame's average (0 before any).
    int progressivePasses() const;
    /// The fraction done of the background bake running for the requested material (0 when none
    /// runs, or the running one was withdrawn and is stopping).
    double bakeProgress() const;
    void setUseUbershader(bool on);

    /// Wall time of the last render()/renderToImage() draw, GPU work included (glFinish), in ms.
    double lastFrameMs() const;
    /// Segments of the sphere the last frame drew (sphereSegmentsForRadius of its size on screen;
    /// rings are half as many), 0 before any sphere was drawn or when the last mesh drawn was not it.
    int lastSphereSegments() const;
    /// The current program's feature set and explain() text.
    const FeatureSet& features() const;
    std::string explainProgram();
    /// The current material program (null before the first successful setScene).
    const Program* program() const;
    /// Number of bakes done so far (a cache hit does not count).
    int bakeCount() const;
    /// Number of environment prefilters done so far: setScene prefilters again only when the source
    /// (kind, path or cube, face size), the lobe model or the power per mip changes.
    int prefilterCount() const;
    /// Wall time setScene spent on the environment (loading, SH, prefiltering, upload; near 0 on a
    /// cache hit), in ms.
    double lastEnvironmentMs() const;
    ProgramCache& programCache();

    struct Impl;

private:
    Renderer();
    std::unique_ptr<Impl> m_impl;
};

/// The i-th point (i >= 1) of the Halton sequence in base 2 and 3, in [0, 1)²: the sub-pixel
/// offsets of the reference.
void haltonPoint(int index, float& x, float& y);

} // namespace burnish::render
