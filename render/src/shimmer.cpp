#include <burnish/render/shimmer.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace burnish::render {

namespace {

// A pixel of the normals view is covered when its RGB sum exceeds this. n·0.5 + 0.5 of a unit
// normal sums to at least 1.5 − √3/2 ≈ 0.63, and the cleared background is exactly 0, so any
// threshold between them separates the two; 0.1 leaves room for filtering at no cost.
constexpr float kCoveredThreshold = 0.1f;

// Largest orbit: a sequence is a slow orbit; past a full turn per frame the step means nothing.
constexpr float kMaxDegreesPerFrame = 360.0f;

double mean(const std::vector<double>& values) {
    if (values.empty()) return 0.0;
    double sum = 0.0;
    for (double v : values)
        sum += v;
    return sum / double(values.size());
}

// Clears covered[p] where `frame` (drawn as its normals view, which leaves the background at 0) does
// not cover pixel p. Leaves the renderer holding that debug view of the frame.
Status clearUncovered(Renderer& renderer, Scene frame, int width, int height,
                      std::vector<std::uint8_t>& covered) {
    frame.debugView = DebugView::Normals;
    if (auto s = renderer.setScene(frame); !s) return s;
    auto normals = renderer.renderToImage(width, height, ImageKind::Hdr);
    if (!normals) return Error{normals.error()};
    for (size_t p = 0; p < covered.size(); ++p)
        if ((*normals)[4 * p] + (*normals)[4 * p + 1] + (*normals)[4 * p + 2] <= kCoveredThreshold)
            covered[p] = 0;
    return {};
}

} // namespace

std::vector<float> frameLuminance(const std::vector<float>& rgba) {
    std::vector<float> Y(rgba.size() / 4);
    for (size_t p = 0; p < Y.size(); ++p) {
        // ITU-R BT.709 luminance weights
        Y[p] = 0.2126f * rgba[4 * p] + 0.7152f * rgba[4 * p + 1] + 0.0722f * rgba[4 * p + 2];
    }
    return Y;
}

Result<double> meanAbsoluteChange(const std::vector<float>& a, const std::vector<float>& b,
                                  const std::vector<std::uint8_t>& mask) {
    if (a.size() != b.size())
        return Error{"frames of " + std::to_string(a.size()) + " and " + std::to_string(b.size()) +
                     " pixels"};
    if (!mask.empty() && mask.size() != a.size())
        return Error{"a mask of " + std::to_string(mask.size()) + " pixels for frames of " +
                     std::to_string(a.size())};
    double sum = 0.0;
    size_t count = 0;
    for (size_t p = 0; p < a.size(); ++p) {
        if (!mask.empty() && !mask[p]) continue;
        sum += std::abs(double(a[p]) - double(b[p]));
        ++count;
    }
    return count ? sum / double(count) : 0.0;
}

std::vector<std::uint8_t> erodeMask(const std::vector<std::uint8_t>& mask, int width, int height) {
    std::vector<std::uint8_t> out(mask.size(), 0);
    if (width < 3 || height < 3 || mask.size() != size_t(width) * size_t(height)) return out;
    auto in = [&](int x, int y) { return mask[size_t(y) * size_t(width) + size_t(x)] != 0; };
    for (int y = 1; y + 1 < height; ++y)
        for (int x = 1; x + 1 < width; ++x)
            out[size_t(y) * size_t(width) + size_t(x)] =
                in(x, y) && in(x - 1, y) && in(x + 1, y) && in(x, y - 1) && in(x, y + 1) ? 1 : 0;
    return out;
}

Result<ShimmerReport> measureShimmer(Renderer& renderer, const Scene& scene, const ShimmerOptions& options) {
    if (options.frames < 2)
        return Error{"a shimmer sequence needs at least 2 frames, got " + std::to_string(options.frames)};
    if (!std::isfinite(options.degreesPerFrame) || std::abs(options.degreesPerFrame) > kMaxDegreesPerFrame)
        return Error{"the orbit step must be a finite angle within ±360 degrees per frame"};
    if (options.estimateReferenceNoise && options.referenceSamples < 2)
        return Error{"estimating the reference's noise splits its samples in two halves: it needs at least "
                     "2 samples per pixel, got " +
                     std::to_string(options.referenceSamples)};
    if (options.estimateReferenceNoise && options.space != ImageKind::Hdr)
        return Error{"the reference's noise is estimated on linear HDR frames (splitting the sample sum "
                     "needs linear radiance)"};
    if (options.width < 1 || options.height < 1)
        return Error{"frame size " + std::to_string(options.width) + "x" + std::to_string(options.height) +
                     " is empty"};

    ShimmerReport report;
    report.frames = options.frames;
    report.degreesPerFrame = options.degreesPerFrame;
    report.width = options.width;
    report.height = options.height;
    report.referenceSamples = options.referenceSamples;
    report.space = options.space;

    const size_t pixels = size_t(options.width) * size_t(options.height);
    std::vector<std::vector<float>> methodY, referenceY, halfY;
    std::vector<std::uint8_t> covered(pixels, 1);
    auto failed = [&](const std::string& message) -> Result<ShimmerReport> {
        // Leave the renderer with the caller's scene, whatever happened.
        (void)renderer.setScene(scene);
        return Error{message};
    };

    for (int i = 0; i < options.frames; ++i) {
        Scene frame = scene;
        frame.debugView = DebugView::None;
        frame.camera.yawDegrees = scene.camera.yawDegrees + float(i) * options.degreesPerFrame;
        if (auto s = renderer.setScene(frame); !s) return failed(s.error());
        auto method = renderer.renderToImage(options.width, options.height, options.space);
        if (!method) return failed(method.error());
        auto reference =
            renderer.renderReference(options.width, options.height, options.referenceSamples, options.space);
        if (!reference) return failed(reference.error());
        methodY.push_back(frameLuminance(*method));
        referenceY.push_back(frameLuminance(*reference));
        if (options.estimateReferenceNoise) {
            // The first half of the same Halton samples (renderReference always starts at index 1).
            auto half = renderer.renderReference(options.width, options.height, options.referenceSamples / 2,
                                                 ImageKind::Hdr);
            if (!half) return failed(half.error());
            halfY.push_back(frameLuminance(*half));
        }
        if (options.maskToObject)
            if (auto s = clearUncovered(renderer, frame, options.width, options.height, covered); !s)
                return failed(s.error());
        if (options.onFrame) options.onFrame(ShimmerFrame{i, frame.camera.yawDegrees, &*method, &*reference});
    }
    if (auto s = renderer.setScene(scene); !s) return Error{s.error()};

    std::vector<std::uint8_t> mask;
    if (options.maskToObject) {
        mask = erodeMask(covered, options.width, options.height);
        report.measuredPixels = 0;
        for (std::uint8_t m : mask)
            report.measuredPixels += m ? 1 : 0;
        if (report.measuredPixels == 0)
            return Error{
                "the object covers no pixel in every frame (after dropping its silhouette); move the "
                "camera closer or render larger frames"};
    } else {
        report.measuredPixels = std::int64_t(pixels);
    }

    for (int i = 1; i < options.frames; ++i) {
        auto dm = meanAbsoluteChange(methodY[size_t(i)], methodY[size_t(i - 1)], mask);
        auto dr = meanAbsoluteChange(referenceY[size_t(i)], referenceY[size_t(i - 1)], mask);
        if (!dm) return Error{dm.error()};
        if (!dr) return Error{dr.error()};
        report.methodDeltas.push_back(*dm);
        report.referenceDeltas.push_back(*dr);
    }
    if (options.estimateReferenceNoise) {
        const double N = double(options.referenceSamples);
        const double h = double(options.referenceSamples / 2);
        // The N-sample mean C = (h·A + (N − h)·B)/N, so the second half is B = (N·C − h·A)/(N − h).
        // With per-sample variance s², var(A − B) = s²·N/(h(N − h)) and the frame-to-frame noise
        // of C has variance 2s²/N: their ratio of standard deviations is √(2h(N − h))/N.
        const double toFrameNoise = std::sqrt(2.0 * h * (N - h)) / N;
        for (int i = 0; i < options.frames; ++i) {
            const std::vector<float>& A = halfY[size_t(i)];
            const std::vector<float>& C = referenceY[size_t(i)];
            std::vector<float> B(C.size());
            for (size_t p = 0; p < C.size(); ++p)
                B[p] = float((N * double(C[p]) - h * double(A[p])) / (N - h));
            auto d = meanAbsoluteChange(A, B, mask);
            if (!d) return Error{d.error()};
            report.referenceNoiseDeltas.push_back(*d * toFrameNoise);
        }
        report.referenceNoise = mean(report.referenceNoiseDeltas);
    }
    report.methodMean = mean(report.methodDeltas);
    report.referenceMean = mean(report.referenceDeltas);
    report.ratio = report.methodMean / std::max(report.referenceMean, kMinShimmer);
    return report;
}

Result<ImageErrorReport> measureImageError(Renderer& renderer, const Scene& scene,
                                           const ImageErrorOptions& options) {
    if (options.width < 1 || options.height < 1)
        return Error{"frame size " + std::to_string(options.width) + "x" + std::to_string(options.height) +
                     " is empty"};
    if (options.referenceSamples < 2)
        return Error{"the reference's noise is estimated from two halves of its samples: it needs at least 2 "
                     "samples per pixel, got " +
                     std::to_string(options.referenceSamples)};
    Scene frame = scene;
    frame.debugView = DebugView::None;
    auto failed = [&](const std::string& message) -> Result<ImageErrorReport> {
        (void)renderer.setScene(scene);
        return Error{message};
    };
    if (auto s = renderer.setScene(frame); !s) return failed(s.error());
    auto method = renderer.renderToImage(options.width, options.height, ImageKind::Hdr);
    if (!method) return failed(method.error());
    auto reference =
        renderer.renderReference(options.width, options.height, options.referenceSamples, ImageKind::Hdr);
    if (!reference) return failed(reference.error());
    // The first half of the same samples (renderReference always starts at the same index).
    const int half = options.referenceSamples / 2;
    auto first = renderer.renderReference(options.width, options.height, half, ImageKind::Hdr);
    if (!first) return failed(first.error());
    const size_t pixels = size_t(options.width) * size_t(options.height);
    std::vector<std::uint8_t> mask(pixels, 1);
    if (options.maskToObject) {
        if (auto s = clearUncovered(renderer, frame, options.width, options.height, mask); !s)
            return failed(s.error());
        mask = erodeMask(mask, options.width, options.height);
    }
    if (auto s = renderer.setScene(scene); !s) return Error{s.error()};

    const std::vector<float> Y = frameLuminance(*method), C = frameLuminance(*reference),
                             A = frameLuminance(*first);
    // The N-sample mean C = (h·A + (N − h)·B)/N, so the second half is B = (N·C − h·A)/(N − h); C's
    // own noise has the standard deviation of A − B times √(h(N − h))/N (see ShimmerReport).
    const double N = double(options.referenceSamples), h = double(half);
    const double toMeanNoise = std::sqrt(h * (N - h)) / N;
    ImageErrorReport report;
    report.width = options.width;
    report.height = options.height;
    report.referenceSamples = options.referenceSamples;
    double absError = 0.0, methodSum = 0.0, referenceSum = 0.0, noise = 0.0;
    for (size_t p = 0; p < pixels; ++p) {
        if (!mask[p]) continue;
        ++report.measuredPixels;
        absError += std::abs(double(Y[p]) - double(C[p]));
        methodSum += double(Y[p]);
        referenceSum += double(C[p]);
        const double B = (N * double(C[p]) - h * double(A[p])) / (N - h);
        noise += std::abs(double(A[p]) - B) * toMeanNoise;
    }
    if (report.measuredPixels == 0)
        return Error{"the object covers no pixel (after dropping its silhouette); move the camera closer or "
                     "render a larger frame"};
    if (!(referenceSum > 0.0) || !std::isfinite(referenceSum) || !std::isfinite(methodSum))
        return Error{"the reference is black (or not finite) where the object is: nothing to compare"};
    report.relativeL1 = absError / referenceSum;
    report.energyRatio = methodSum / referenceSum;
    report.referenceNoiseL1 = noise / referenceSum;
    return report;
}

Result<ShimmerReport> measureShimmer(Renderer& renderer, const Scene& scene, int frames,
                                     float degreesPerFrame, int width, int height, int referenceSamples) {
    ShimmerOptions options;
    options.frames = frames;
    options.degreesPerFrame = degreesPerFrame;
    options.width = width;
    options.height = height;
    options.referenceSamples = referenceSamples;
    return measureShimmer(renderer, scene, options);
}

} // namespace burnish::render
