// Shimmer: the texts' core complaint — highlights popping in and out as the camera moves — as a
// number. A slow orbit is rendered twice, with the scene's method and as the supersampled ground
// truth; the shimmer of each is the mean absolute luminance change per pixel between consecutive
// frames, and their ratio says how much of the method's flicker is aliasing rather than motion.
// One measurement: `burnish render --sequence` (measureShimmer) and the studio's live meter feed
// the same frames (renderShimmerSample) to the same ShimmerMeter.
#pragma once

#include <burnish/core/util/result.h>
#include <burnish/render/renderer.h>
#include <burnish/render/scene.h>

#include <cstddef>
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

/// The pixels `frame`'s object covers (non-zero), from its normals view at width × height. Leaves
/// `renderer` holding that view of the frame.
Result<std::vector<std::uint8_t>> objectCoverage(Renderer& renderer, const Scene& frame, int width,
                                                 int height);

/// One frame of a shimmer measurement: the method's image, the other side's (the reference, or a
/// second method the studio shows beside), with a reference the same reference drawn with the first
/// half of its samples (its noise, see ShimmerReport::referenceNoise; empty without), all RGBA in one
/// ImageKind, and the pixels the object covers (empty: every pixel counts).
struct ShimmerSample {
    std::vector<float> method;
    std::vector<float> other;
    std::vector<float> otherHalf;
    std::vector<std::uint8_t> covered;
};

/// Renders one frame of the measurement for `frame` (its debug view ignored): the method, the
/// reference with `referenceSamples` per pixel and, with `estimateNoise`, its first half, in `space`,
/// and with `maskToObject` the object's coverage. Leaves `renderer` holding another scene (callers set
/// theirs again). Errors: anything the renderer refuses.
Result<ShimmerSample> renderShimmerSample(Renderer& renderer, const Scene& frame, int width, int height,
                                          int referenceSamples, ImageKind space, bool estimateNoise,
                                          bool maskToObject = true);

/// The shimmer measurement itself, fed one frame after another. From the second frame on, each frame
/// adds, per side, the mean |ΔY| (frameLuminance) between it and the previous frame over the pixels the
/// object covers in both, eroded by one pixel (erodeMask: the silhouette's geometric aliasing is no
/// part of the shading's shimmer); every pixel when the frames carry no coverage. With the
/// reference's first half of samples, also that frame's reference noise delta (ShimmerReport's
/// formula). Keeps the last `window` deltas (0: all).
class ShimmerMeter {
public:
    /// `referenceSamples`: the other side's samples per pixel (for the noise scale; 0 when it is no
    /// reference).
    ShimmerMeter(int width, int height, int referenceSamples, std::size_t window = 0);
    /// Errors (nothing added): images or coverage of another size than width × height, a half
    /// reference without a reference of at least 2 samples, no pixel covered in both frames.
    Status add(const ShimmerSample& sample);
    void reset();

    const std::vector<double>& methodDeltas() const { return m_method; }
    const std::vector<double>& otherDeltas() const { return m_other; }
    const std::vector<double>& noiseDeltas() const { return m_noise; }
    double methodMean() const;
    double otherMean() const;
    double noiseMean() const;
    /// The fewest pixels any delta was taken over (0 before the first delta).
    std::int64_t measuredPixels() const { return m_measuredPixels; }

private:
    int m_width = 0;
    int m_height = 0;
    int m_referenceSamples = 0;
    std::size_t m_window = 0;
    std::vector<float> m_previousMethod;
    std::vector<float> m_previousOther;
    std::vector<std::uint8_t> m_previousCovered;
    bool m_hasPrevious = false;
    std::vector<double> m_method;
    std::vector<double> m_other;
    std::vector<double> m_noise;
    std::int64_t m_measuredPixels = 0;
};

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
    /// Measure only pixels the object covers in both frames of each delta (after a one-pixel erosion
    /// that drops its silhouette, whose geometric aliasing is no part of the shading's shimmer), so
    /// the background does not dilute the mean. Off: every pixel.
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
    /// The fewest pixels a delta was taken over (ShimmerMeter::measuredPixels).
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
    std::vector<double> referenceNoiseDeltas; // per delta (frames − 1 entries), with the option on
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
/// else as given (the debug view is ignored: the shimmer compares shading with the ground truth),
/// each frame renderShimmerSample's, measured by a ShimmerMeter. Leaves `renderer` holding `scene`
/// again. Errors: frames < 2, a non-finite step, a size or sample count the renderer refuses, a
/// scene it cannot set, two consecutive frames sharing no covered pixel when maskToObject is on.
Result<ShimmerReport> measureShimmer(Renderer& renderer, const Scene& scene, const ShimmerOptions& options);

/// The same with the defaults of ShimmerOptions for the rest.
Result<ShimmerReport> measureShimmer(Renderer& renderer, const Scene& scene, int frames,
                                     float degreesPerFrame, int width, int height, int referenceSamples);

} // namespace burnish::render
