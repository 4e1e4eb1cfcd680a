#include <burnish/render/shimmer.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

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

Result<std::vector<std::uint8_t>> objectCoverage(Renderer& renderer, const Scene& frame, int width,
                                                 int height) {
    Scene normalsView = frame;
    normalsView.debugView = DebugView::Normals;
    if (auto s = renderer.setScene(normalsView); !s) return Error{s.error()};
    auto normals = renderer.renderToImage(width, height, ImageKind::Hdr);
    if (!normals) return Error{normals.error()};
    std::vector<std::uint8_t> covered(size_t(width) * size_t(height));
    for (size_t p = 0; p < covered.size(); ++p)
        covered[p] =
            (*normals)[4 * p] + (*normals)[4 * p + 1] + (*normals)[4 * p + 2] > kCoveredThreshold ? 1 : 0;
    return covered;
}

Result<ShimmerSample> renderShimmerSample(Renderer& renderer, const Scene& frame, int width, int height,
                                          int referenceSamples, ImageKind space, bool estimateNoise,
                                          bool maskToObject) {
    Scene shaded = frame;
    shaded.debugView = DebugView::None;
    if (auto s = renderer.setScene(shaded); !s) return Error{s.error()};
    ShimmerSample sample;
    auto method = renderer.renderToImage(width, height, space);
    if (!method) return Error{method.error()};
    sample.method = std::move(method).value();
    auto reference = renderer.renderReference(width, height, referenceSamples, space);
    if (!reference) return Error{reference.error()};
    sample.other = std::move(reference).value();
    if (estimateNoise) {
        // The first half of the same Halton samples (renderReference always starts at index 1).
        auto half = renderer.renderReference(width, height, referenceSamples / 2, space);
        if (!half) return Error{half.error()};
        sample.otherHalf = std::move(half).value();
    }
    if (maskToObject) {
        auto covered = objectCoverage(renderer, shaded, width, height);
        if (!covered) return Error{covered.error()};
        sample.covered = std::move(covered).value();
    }
    return sample;
}

ShimmerMeter::ShimmerMeter(int width, int height, int referenceSamples, std::size_t window)
    : m_width(std::max(width, 0))
    , m_height(std::max(height, 0))
    , m_referenceSamples(referenceSamples)
    , m_window(window) {}

void ShimmerMeter::reset() {
    m_previousMethod.clear();
    m_previousOther.clear();
    m_previousCovered.clear();
    m_hasPrevious = false;
    m_method.clear();
    m_other.clear();
    m_noise.clear();
    m_measuredPixels = 0;
}

Status ShimmerMeter::add(const ShimmerSample& sample) {
    const size_t pixels = size_t(m_width) * size_t(m_height);
    const auto size = [&](const std::vector<float>& rgba, const char* what) -> Status {
        if (rgba.size() == 4 * pixels) return {};
        return Error{std::string(what) + " of " + std::to_string(rgba.size() / 4) +
                     " pixels, the meter measures " + std::to_string(m_width) + "x" +
                     std::to_string(m_height)};
    };
    for (const auto& [rgba, what] :
         {std::pair{&sample.method, "a method frame"}, std::pair{&sample.other, "an other "
                                                                                "frame"}})
        if (auto s = size(*rgba, what); !s) return s;
    const bool noise = !sample.otherHalf.empty();
    if (noise) {
        if (auto s = size(sample.otherHalf, "a half-sample reference"); !s) return s;
        if (m_referenceSamples < 2)
            return Error{
                "the reference's noise is estimated from two halves of its samples: it needs at least 2 "
                "samples per pixel, got " +
                std::to_string(m_referenceSamples)};
    }
    if (!sample.covered.empty() && sample.covered.size() != pixels)
        return Error{"a coverage of " + std::to_string(sample.covered.size()) + " pixels for " +
                     std::to_string(pixels)};

    std::vector<float> methodY = frameLuminance(sample.method);
    std::vector<float> otherY = frameLuminance(sample.other);
    if (m_hasPrevious) {
        // The pixels covered in both frames, silhouette dropped; every pixel without coverage.
        std::vector<std::uint8_t> mask;
        if (!sample.covered.empty() && !m_previousCovered.empty()) {
            mask.resize(pixels);
            for (size_t p = 0; p < pixels; ++p)
                mask[p] = sample.covered[p] && m_previousCovered[p] ? 1 : 0;
            mask = erodeMask(mask, m_width, m_height);
        }
        std::int64_t count = mask.empty() ? std::int64_t(pixels) : 0;
        for (std::uint8_t m : mask)
            count += m ? 1 : 0;
        if (count == 0)
            return Error{"the object covers no pixel in both of two consecutive frames (after dropping its "
                         "silhouette); move the camera closer or render larger frames"};
        const auto dm = meanAbsoluteChange(methodY, m_previousMethod, mask);
        const auto dr = meanAbsoluteChange(otherY, m_previousOther, mask);
        if (!dm) return Error{dm.error()};
        if (!dr) return Error{dr.error()};
        double noiseDelta = 0.0;
        if (noise) {
            // The N-sample mean C = (h·A + (N − h)·B)/N, so the second half is B = (N·C − h·A)/(N − h).
            // With per-sample variance s², var(A − B) = s²·N/(h(N − h)) and the frame-to-frame noise
            // of C has variance 2s²/N: their ratio of standard deviations is √(2h(N − h))/N.
            const double N = double(m_referenceSamples);
            const double h = double(m_referenceSamples / 2);
            const double toFrameNoise = std::sqrt(2.0 * h * (N - h)) / N;
            const std::vector<float> A = frameLuminance(sample.otherHalf);
            std::vector<float> B(otherY.size());
            for (size_t p = 0; p < otherY.size(); ++p)
                B[p] = float((N * double(otherY[p]) - h * double(A[p])) / (N - h));
            const auto d = meanAbsoluteChange(A, B, mask);
            if (!d) return Error{d.error()};
            noiseDelta = *d * toFrameNoise;
        }
        m_method.push_back(*dm);
        m_other.push_back(*dr);
        if (noise) m_noise.push_back(noiseDelta);
        m_measuredPixels = m_method.size() == 1 ? count : std::min(m_measuredPixels, count);
        if (m_window > 0)
            for (auto* deltas : {&m_method, &m_other, &m_noise})
                if (deltas->size() > m_window) deltas->erase(deltas->begin());
    }
    m_previousMethod = std::move(methodY);
    m_previousOther = std::move(otherY);
    m_previousCovered = sample.covered;
    m_hasPrevious = true;
    return {};
}

double ShimmerMeter::methodMean() const {
    return mean(m_method);
}

double ShimmerMeter::otherMean() const {
    return mean(m_other);
}

double ShimmerMeter::noiseMean() const {
    return mean(m_noise);
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

    auto failed = [&](const std::string& message) -> Result<ShimmerReport> {
        // Leave the renderer with the caller's scene, whatever happened.
        (void)renderer.setScene(scene);
        return Error{message};
    };
    ShimmerMeter meter(options.width, options.height, options.referenceSamples);
    for (int i = 0; i < options.frames; ++i) {
        Scene frame = scene;
        frame.camera.yawDegrees = scene.camera.yawDegrees + float(i) * options.degreesPerFrame;
        auto sample =
            renderShimmerSample(renderer, frame, options.width, options.height, options.referenceSamples,
                                options.space, options.estimateReferenceNoise, options.maskToObject);
        if (!sample) return failed(sample.error());
        if (auto s = meter.add(*sample); !s) return failed(s.error());
        if (options.onFrame)
            options.onFrame(ShimmerFrame{i, frame.camera.yawDegrees, &sample->method, &sample->other});
    }
    if (auto s = renderer.setScene(scene); !s) return Error{s.error()};

    report.measuredPixels = meter.measuredPixels();
    report.methodDeltas = meter.methodDeltas();
    report.referenceDeltas = meter.otherDeltas();
    report.referenceNoiseDeltas = meter.noiseDeltas();
    report.referenceNoise = meter.noiseMean();
    report.methodMean = meter.methodMean();
    report.referenceMean = meter.otherMean();
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
        auto covered = objectCoverage(renderer, frame, options.width, options.height);
        if (!covered) return failed(covered.error());
        mask = erodeMask(*covered, options.width, options.height);
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
