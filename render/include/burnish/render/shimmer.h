// Shimmer: the texts' core complaint — highlights popping in and out as the camera moves — as a
// number. A slow orbit is rendered twice, with the scene's method and as the supersampled ground
// truth; the shimmer of each is the mean absolute luminance change per pixel between consecutive
// frames, and their ratio says how much of the method's flicker is aliasing rather than motion.
#pragma once

#include <burnish/core/util/result.h>
#include <burnish/render/renderer.h>
#include <burnish/render/scene.h>

#include <cstdint>
#include <functional>
#include <vector>

namespace burnish::render {

/// Rec. 709 luminance weights applied to RGBA pixels (four floats each), one value per pixel.
/// Linear luminance for HDR frames; for display frames the values are sRGB-encoded, so the result is
/// luma Y'.
std::vector<float> frameLuminance(const std::vector<float>& rgba);

/// Mean |a − b| over the pixels where mask is non-zero (every pixel when mask is empty). 0 when
/// no pixel is selected. Errors: sizes that differ, a mask of another size.
Result<double> meanAbsoluteChange(const std::vector<float>& a, const std::vector<float>& b,
                                  const std::vector<std::uint8_t>& mask = {});

/// Keeps the pixels of `mask` (width × height, non-zero = in) whose 4-neighbours are all in too:
/// a one-pixel erosion that drops silhouette pixels. Pixels on the image border are dropped.
std::vector<std::uint8_t> erodeMask(const std::vector<std::uint8_t>& mask, int width, int height);

/// One frame of the orbit, handed to ShimmerOptions::onFrame as soon as both images exist.
struct ShimmerFrame {
    int index = 0; // 0 .. frames − 1
    float yawDegrees = 0.0f;
    const std::vector<float>* method = nullptr;    // RGBA, in ShimmerOptions::space
    const std::vector<float>* reference = nullptr; // RGBA, in ShimmerOptions::space
};

struct ShimmerOptions {
    /// Frames of the orbit (at least 2: the deltas are between consecutive frames).
    int frames = 12;
    /// Camera yaw step between frames, degrees (a slow orbit: 0.25–2°).
    float degreesPerFrame = 0.5f;
    int width = 128;
    int height = 128;
    /// Samples per pixel of the reference (1..4096).
    int referenceSamples = 16;
    /// Which frames are measured. Hdr (the default): linear radiance before exposure. The shimmer the
    /// texts complain of is specular energy popping in and out, and the display transform clips
    /// exactly those pixels (a highlight of 5 and one of 500 both show white), so display frames hide
    /// most of it: measured on the samples, naive's highlights move several times more energy than
    /// the baked methods' in HDR, while in display frames the clipped narrow highlight of naive looks
    /// calmer than the broader baked ones. Linear luminance is also additive, so the mean is the
    /// change of the light reaching the eye, independent of exposure and tone curve. Display: after
    /// exposure, the filmic curve and the sRGB encoding (luma Y', bounded to [0, 1]): what a viewer
    /// sees, for comparing with a screen.
    ImageKind space = ImageKind::Hdr;
    /// Measure only pixels the object covers in every frame (after a one-pixel erosion that drops
    /// its silhouette, whose geometric aliasing is no part of the shading's shimmer), so the
    /// background does not dilute the mean. Off: every pixel.
    bool maskToObject = true;
    /// Also estimate the reference's sampling-noise floor (ShimmerReport::referenceNoise): each frame's
    /// reference is rendered once more with the first half of its samples, which costs half a
    /// reference more per frame. Needs referenceSamples >= 2 and Hdr frames (the estimate splits
    /// the sample sum, which only linear radiance allows).
    bool estimateReferenceNoise = false;
    /// Called after each frame (progress, writing frames). May be empty.
    std::function<void(const ShimmerFrame&)> onFrame;
};

struct ShimmerReport {
    int frames = 0;
    float degreesPerFrame = 0.0f;
    int width = 0;
    int height = 0;
    int referenceSamples = 0;
    ImageKind space = ImageKind::Hdr;
    /// Pixels the means are taken over (the mask's size, or every pixel).
    std::int64_t measuredPixels = 0;
    /// Mean |ΔY| per measured pixel between frame i and i + 1 (frames − 1 entries each).
    std::vector<double> methodDeltas;
    std::vector<double> referenceDeltas;
    double methodMean = 0.0;
    double referenceMean = 0.0;
    /// With ShimmerOptions::estimateReferenceNoise: the mean |ΔY| that the reference's Monte Carlo
    /// noise alone would give between two frames (0 without it). The reference's N samples are split
    /// into two independent halves A (the first ⌊N/2⌋ = h) and B (the rest); their difference is
    /// pure noise, and mean |A − B| · √(2h(N − h))/N scales it to the frame-to-frame noise of the
    /// N-sample mean (exactly for the standard deviation, assuming the same shape for the mean
    /// |·|). A reference shimmer near this floor is noise, not the truth's shimmer; well above it
    /// (several times), the reference has converged and referenceMean measures the truth. The noise
    /// floor falls as 1/√N, the truth's shimmer does not.
    double referenceNoise = 0.0;
    std::vector<double> referenceNoiseDeltas; // per frame (frames entries), with the option on
    /// methodMean / referenceMean, the reference mean floored at kMinShimmer so a perfectly still
    /// reference gives a large finite ratio rather than Inf.
    double ratio = 0.0;
};

/// Floor of the reference's mean shimmer in the ratio: a tenth of one 8-bit display step (1/255)
/// per pixel, below anything a frame can show.
inline constexpr double kMinShimmer = 0.1 / 255.0;

/// A still frame's error against the ground truth, in screen space: the scene's method and its
/// supersampled reference (Renderer::renderReference) in linear HDR, compared by Rec. 709
/// luminance over the pixels the object covers (its silhouette dropped, as ShimmerOptions).
struct ImageErrorOptions {
    int width = 256;
    int height = 256;
    /// Samples per pixel of the reference (2..4096: its noise is estimated from two halves).
    int referenceSamples = 64;
    bool maskToObject = true;
};

struct ImageErrorReport {
    int width = 0;
    int height = 0;
    int referenceSamples = 0;
    std::int64_t measuredPixels = 0;
    /// Σ|Y − Y_ref| / Σ Y_ref over the measured pixels: evaluate's relative L1, on the screen.
    double relativeL1 = 0.0;
    /// Σ Y / Σ Y_ref: the energy the method keeps.
    double energyRatio = 0.0;
    /// The reference's own Monte Carlo noise as the same ratio (from two halves of its samples, as
    /// ShimmerReport::referenceNoise): a relativeL1 not well above it is noise, not the method's error.
    double referenceNoiseL1 = 0.0;
};

/// Renders `scene` (its debug view ignored) and its reference and compares them. Leaves `renderer`
/// holding `scene` again. Errors: an empty frame, fewer than 2 reference samples, an object that
/// covers no pixel, a reference that is black where the object is, anything the renderer refuses.
Result<ImageErrorReport> measureImageError(Renderer& renderer, const Scene& scene,
                                           const ImageErrorOptions& options);

/// Renders the orbit: the scene's camera yaw advanced by degreesPerFrame each frame, everything
/// else as given (the debug view is ignored: the shimmer compares shading with the ground truth).
/// Leaves `renderer` holding `scene` again. Errors: frames < 2, a non-finite step, a size or sample
/// count the renderer refuses, a scene it cannot set, an empty mask (the object covers no pixel in
/// every frame) when maskToObject is on.
Result<ShimmerReport> measureShimmer(Renderer& renderer, const Scene& scene, const ShimmerOptions& options);

/// The same with the defaults of ShimmerOptions for the rest.
Result<ShimmerReport> measureShimmer(Renderer& renderer, const Scene& scene, int frames,
                                     float degreesPerFrame, int width, int height, int referenceSamples);

} // namespace burnish::render
