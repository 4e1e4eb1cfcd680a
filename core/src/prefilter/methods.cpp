#include <burnish/core/prefilter/methods.h>

#include <burnish/core/prefilter/gloss.h>
#include <burnish/core/shading/ndf.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace burnish {

namespace {

using R = ChannelRange;

const TextureSpec kTextureTable[kTextureRoleCount] = {
    {TextureRole::Normal,
     {{"normal.x", R::Signed}, {"normal.y", R::Signed, true}, {"normal.z", R::Signed}},
     false,
     "uNormalMap"},
    {TextureRole::Gloss, {{"gloss", R::Unit}}, false, "uGlossMap"},
    {TextureRole::Toksvig, {{"toksvig", R::Unit}}, false, "uToksvigMap"},
    {TextureRole::LeanB, {{"B.x", R::Slope}, {"B.y", R::Slope, true}}, true, "uLeanB"},
    {TextureRole::LeanM,
     {{"M.xx", R::Moment}, {"M.yy", R::Moment}, {"M.xy", R::SignedMoment, true}},
     true,
     "uLeanM"},
    {TextureRole::Clean, {{"B.x", R::Slope}, {"B.y", R::Slope, true}, {"M.avg", R::Moment}}, true, "uClean"},
    // The compact LEAN gloss is for export: the shader reads B and M.
    {TextureRole::LeanGloss,
     {{"gloss.x", R::Unit}, {"gloss.y", R::Unit}, {"rho", R::Signed, true}},
     false,
     ""},
    // Bound by the renderer's detail code (its own sampler and uniforms), not as a method texture.
    {TextureRole::Detail,
     {{"detail.x", R::Signed}, {"detail.y", R::Signed, true}, {"zero", R::Unit}, {"variance", R::Variance}},
     false,
     ""},
    // The mixture's premultiplied raw moments (lobe_mixture.h): linear in the moments, so bilinear and
    // trilinear filtering merge lobes of the same index exactly.
    {TextureRole::MixtureWeights,
     {{"w0", R::Unit}, {"w1", R::Unit}, {"w2", R::Unit}, {"w3", R::Unit}},
     true,
     "uMixtureWeights"},
    {TextureRole::MixtureLobe0,
     {{"wb.x", R::Slope}, {"wb.y", R::Slope, true}, {"wM.xx", R::Moment}, {"wM.yy", R::Moment}},
     true,
     "uMixtureLobe0"},
    {TextureRole::MixtureLobe1,
     {{"wb.x", R::Slope}, {"wb.y", R::Slope, true}, {"wM.xx", R::Moment}, {"wM.yy", R::Moment}},
     true,
     "uMixtureLobe1"},
    {TextureRole::MixtureLobe2,
     {{"wb.x", R::Slope}, {"wb.y", R::Slope, true}, {"wM.xx", R::Moment}, {"wM.yy", R::Moment}},
     true,
     "uMixtureLobe2"},
    {TextureRole::MixtureLobe3,
     {{"wb.x", R::Slope}, {"wb.y", R::Slope, true}, {"wM.xx", R::Moment}, {"wM.yy", R::Moment}},
     true,
     "uMixtureLobe3"},
    {TextureRole::MixtureCross,
     {{"wM.xy0", R::SignedMoment, true},
      {"wM.xy1", R::SignedMoment, true},
      {"wM.xy2", R::SignedMoment, true},
      {"wM.xy3", R::SignedMoment, true}},
     true,
     "uMixtureCross"},
};

// In TextureRole order, as kTextureTable's rows.
constexpr std::string_view kRoleNames[kTextureRoleCount] = {
    "normal",        "gloss",         "toksvig",       "lean-b",          "lean-m",
    "clean",         "lean-gloss",    "detail",        "mixture-weights", "mixture-lobe0",
    "mixture-lobe1", "mixture-lobe2", "mixture-lobe3", "mixture-cross"};

constexpr std::string_view kRenormalized = "renormalized mean normal";
constexpr std::string_view kAuthoredGloss = "authored gloss, {encoding}";
constexpr std::string_view kAdjustedGloss = "adjusted gloss, {encoding}";

const MethodSpec kMethodTable[] = {
    {Method::Naive,
     "naive",
     "renormalized mean normal, base power unchanged (the too-shiny baseline)",
     kMomentsMean,
     {{TextureRole::Normal, kRenormalized}, {TextureRole::Gloss, kAuthoredGloss}},
     false,
     false,
     "Blinn-Phong D_s about the renormalized mean normal",
     "METHOD_NAIVE",
     {2, 1.5, "normal BC5 + gloss BC4"}},
    {Method::Toksvig,
     "toksvig",
     "run-time Toksvig: p = s|Na|/(|Na| + s(1-|Na|)) from the unnormalized mean normal",
     kMomentsMean,
     {{TextureRole::Normal, "unnormalized mean normal Na (its length carries the variance)"},
      {TextureRole::Gloss, kAuthoredGloss}},
     true,
     false,
     "p = f_t s with f_t = |Na|/(|Na| + s(1-|Na|)) from the filtered, unnormalized normal",
     "METHOD_TOKSVIG",
     // Hill 2011: the length of Na must survive, so no two-channel or block-compressed normals.
     {2, 4.5, "normal RGBA8 uncompressed (its length is the variance) + gloss BC4"}},
    {Method::ToksvigMap,
     "toksvig-map",
     "baked 8-bit Toksvig factor for a fixed power, converted to s at run time",
     kMomentsMean,
     {{TextureRole::Normal, kRenormalized},
      {TextureRole::Gloss, kAuthoredGloss},
      {TextureRole::Toksvig,
       "Toksvig factor f_t for power {toksvig-power}; convert with ft /= lerp(s/fixed_s, 1, ft)"}},
     false,
     false,
     "ft /= lerp(s/fixed_s, 1, ft); p = ft s",
     "METHOD_TOKSVIG_MAP",
     {2, 2.0, "normal BC5 + Toksvig factor and gloss in one BC5"}},
    {Method::VarianceToGloss,
     "variance-to-gloss",
     "projected variance added to gloss as 1/(n+1): p = 1/(v + 1/(s+1)) - 1",
     kMomentsCov,
     {{TextureRole::Normal, kRenormalized}, {TextureRole::Gloss, kAdjustedGloss}},
     false,
     true,
     "plain Blinn-Phong with the stored (adjusted) gloss",
     "METHOD_VARIANCE_TO_GLOSS",
     {2, 1.5, "normal BC5 + adjusted gloss BC4"}},
    {Method::Lean,
     "lean",
     "slope-space Gaussian, Sigma = M - BB^T + I/s about the normal of slope B (5 values)",
     kMomentsSlope,
     {{TextureRole::Normal, kRenormalized},
      {TextureRole::LeanB, "LEAN slope mean B"},
      {TextureRole::LeanM, "LEAN second moments M with 1/s on the diagonal"},
      {TextureRole::LeanGloss,
       "compact LEAN: log2(1/Sigma_x)/13, log2(1/Sigma_y)/13, correlation (rho+1)/2"}},
     false,
     false,
     "slope-space Gaussian with Sigma = M - BB^T from filtered B and M, and the 1/h_z^4 Jacobian",
     "METHOD_LEAN",
     // Baker & Hill 2012: "X, Y offset can be 8 bit; X², Y², XY need to be 16 bit".
     {2, 8.0, "B in RG8 + M in RGB16 (padded to RGBA16: 10 B as stored by most APIs, 8 B packed)"}},
    {Method::Clean,
     "clean",
     "isotropic slope-space Gaussian, variance ((Mxx+Myy) - |B|^2)/2 + 1/s (3 values)",
     kMomentsSlope,
     {{TextureRole::Normal, kRenormalized},
      {TextureRole::Clean, "CLEAN: B and (M.xx + M.yy)/2 with 1/s added"}},
     false,
     false,
     "isotropic slope-space Gaussian with variance (M.avg - |B|^2/2) from filtered B and M.avg",
     "METHOD_CLEAN",
     // Baker & Hill 2012: "Store 3 values, X, Y, (X²+Y²)/2; only (X²+Y²)/2 needs high precision".
     {2, 4.0, "B in RG8 + (M.xx+M.yy)/2 in R16"}},
    {Method::Vmf,
     "vmf",
     "von Mises-Fisher: kappa = (3r - r^3)/(1 - r^2), 1/p = 1/s + 1/kappa (Filament/Godot/Unity form)",
     kMomentsMean,
     {{TextureRole::Normal, kRenormalized}, {TextureRole::Gloss, kAdjustedGloss}},
     false,
     true,
     "plain Blinn-Phong (or GGX with alpha^2 = 2/(p+2)) with the stored (adjusted) gloss",
     "METHOD_VMF",
     {2, 1.5, "normal BC5 + adjusted gloss (or GGX roughness) BC4"}},
    {Method::Mixture,
     "mixture",
     "K slope-space Gaussians per texel (K = 1..4, --lobes), fitted by merging, stored as premultiplied "
     "moments (w, w.b, w.M)",
     kMomentsSlope,
     {{TextureRole::Normal, kRenormalized},
      {TextureRole::MixtureWeights, "mixture lobe weights w_0..w_3 (shares of the footprint, sum 1)"},
      {TextureRole::MixtureLobe0, "mixture lobe 0: w.b.x, w.b.y, w.M.xx, w.M.yy (1/s on M's diagonal)"},
      {TextureRole::MixtureLobe1, "mixture lobe 1: w.b.x, w.b.y, w.M.xx, w.M.yy (1/s on M's diagonal)"},
      {TextureRole::MixtureLobe2, "mixture lobe 2: w.b.x, w.b.y, w.M.xx, w.M.yy (1/s on M's diagonal)"},
      {TextureRole::MixtureLobe3, "mixture lobe 3: w.b.x, w.b.y, w.M.xx, w.M.yy (1/s on M's diagonal)"},
      {TextureRole::MixtureCross, "mixture cross moments w_i.M.xy of lobes 0..3"}},
     false,
     false,
     "sum over lobes of w_i D_i(h) max(0, n_i.l), each D_i LEAN's Gaussian with Sigma_i = M_i - b_i b_i^T "
     "from "
     "filtered (w, w.b, w.M)",
     "METHOD_MIXTURE",
     // At the default 3 lobes; methodStorage gives it for any count.
     {5, 40.0, "weights + 3 lobes + cross moments, 5 RGBA16"}},
    {Method::Fitted,
     "fitted",
     "one lobe per texel fitted to the footprint's shading (GGX for roughness presets); never worse than "
     "the base power or vmf by evaluate's measure",
     kMomentsMean,
     {{TextureRole::Normal, kRenormalized}, {TextureRole::Gloss, kAdjustedGloss}},
     false,
     true,
     "plain GGX (or Blinn-Phong) with the stored (fitted) gloss",
     "METHOD_FITTED",
     {2, 1.5, "normal BC5 + fitted gloss (or GGX roughness) BC4"}},
};

} // namespace

const MethodSpec& methodSpec(Method method) {
    for (const auto& m : kMethodTable)
        if (m.method == method) return m;
    return kMethodTable[0];
}

const TextureSpec& textureSpec(TextureRole role) {
    return kTextureTable[int(role)];
}

std::string_view roleName(TextureRole role) {
    return kRoleNames[int(role)];
}

std::optional<TextureRole> roleFromName(std::string_view name) {
    for (int r = 0; r < kTextureRoleCount; ++r)
        if (kRoleNames[r] == name) return TextureRole(r);
    return std::nullopt;
}

ChannelDecodeRule channelDecode(ChannelRange range, const ChannelScales& scales) {
    switch (range) {
    case ChannelRange::Unit:
        return {1.0, 0.0};
    case ChannelRange::Signed:
        return {2.0, -1.0};
    case ChannelRange::Slope:
        return {2 * scales.slope, -scales.slope};
    case ChannelRange::Moment:
        return {scales.moment, 0.0};
    case ChannelRange::SignedMoment:
        return {2 * scales.moment, -scales.moment};
    case ChannelRange::Variance:
        return {scales.variance, 0.0};
    }
    return {};
}

bool storesSlopes(Method method) {
    for (const MethodTexture& t : methodSpec(method).textures)
        for (const ChannelSpec& c : textureSpec(t.role).channels)
            if (c.range == ChannelRange::Slope || c.range == ChannelRange::Moment ||
                c.range == ChannelRange::SignedMoment)
                return true;
    return false;
}

bool hasTexture(Method method, TextureRole role) {
    for (const MethodTexture& t : methodSpec(method).textures)
        if (t.role == role) return true;
    return false;
}

bool bakesTexture(Method method, TextureRole role, const MethodParams& params) {
    if (!hasTexture(method, role)) return false;
    return !isMixtureLobeRole(role) ||
           mixtureLobeIndex(role) < std::clamp(params.mixtureLobes, 1, kMaxMixtureLobes);
}

MethodStorage methodStorage(Method method, const MethodParams& params) {
    if (method != Method::Mixture) return methodSpec(method).storage;
    // K lobe textures, the weights and the cross moments, each RGBA16 (half float or unorm).
    static const std::string_view layouts[kMaxMixtureLobes] = {
        "weights + 1 lobe + cross moments, 3 RGBA16", "weights + 2 lobes + cross moments, 4 RGBA16",
        "weights + 3 lobes + cross moments, 5 RGBA16", "weights + 4 lobes + cross moments, 6 RGBA16"};
    const int k = std::clamp(params.mixtureLobes, 1, kMaxMixtureLobes);
    return {k + 2, 8.0 * (k + 2), layouts[k - 1]};
}

const std::vector<Method>& allMethods() {
    static const std::vector<Method> methods = [] {
        std::vector<Method> v;
        for (const auto& m : kMethodTable)
            v.push_back(m.method);
        return v;
    }();
    return methods;
}

FilterKernel defaultKernel(Method method) {
    return method == Method::Fitted ? FilterKernel::Box : FilterKernel::Tent;
}

std::string_view methodName(Method method) {
    return methodSpec(method).name;
}

std::string_view methodDescription(Method method) {
    return methodSpec(method).description;
}

Result<Method> methodFromName(std::string_view name) {
    for (const auto& m : kMethodTable)
        if (m.name == name) return m.method;
    std::string known;
    for (const auto& m : kMethodTable)
        known += (known.empty() ? "" : ", ") + std::string(m.name);
    return Error{"unknown method '" + std::string(name) + "' (known: " + known + ")"};
}

double vmfKappa(double r) {
    r = r > 0.0 ? std::min(r, 1.0) : 0.0;
    const double oneMinusR2 = (1.0 - r) * (1.0 + r);
    // r = 1 (all normals equal) is the limit κ → ∞: the lobe keeps the base power.
    if (!(oneMinusR2 > 0.0)) return kMaxPower;
    return std::clamp(r * (3.0 - r * r) / oneMinusR2, 0.0, kMaxPower);
}

double methodPower(Method method, const NormalMoments& moments, double s, const MethodParams& params) {
    if (method == Method::Lean || method == Method::Clean || method == Method::Mixture)
        return methodLobe(method, moments, s, params).power;
    // Variance-to-gloss clamps s itself (to [0, kMaxPower]), as the bake's rows call it.
    if (method == Method::VarianceToGloss) return varianceToGlossPower(moments.projectedVariance(), s);
    s = std::max(clampPower(s), kMinBasePower);
    switch (method) {
    case Method::Naive:
        return s;
    case Method::Toksvig:
        return toksvigPower(double(moments.lengthNa()), s);
    case Method::ToksvigMap: {
        // The map stores f_t for the fixed power in 8 bits.
        const double ft =
            std::round(toksvigFactor(double(moments.lengthNa()), params.toksvigMapPower) * 255.0) / 255.0;
        return convertToksvigFactor(ft, params.toksvigMapPower, s) * s;
    }
    case Method::VarianceToGloss: // above
        break;
    case Method::Vmf: {
        const double kappa = vmfKappa(double(moments.lengthNa()));
        return kappa > 0.0 ? clampPower(1.0 / (1.0 / s + 1.0 / kappa)) : 0.0;
    }
    case Method::Fitted: // needs the footprint's normals (fitted_lobe.h): the base power, its first candidate
        return s;
    case Method::Lean:
    case Method::Clean:
    case Method::Mixture:
        break;
    }
    return s;
}

TexelLobe methodLobe(Method method, const NormalMoments& moments, double s, const MethodParams& params) {
    TexelLobe lobe;
    // A mixture's lobes need the footprint's normals (lobe_mixture.h); from moments alone its one
    // moment-matched lobe is LEAN's, which is also what its K = 1 stores.
    if (method == Method::Mixture) method = Method::Lean;
    if (method != Method::Lean && method != Method::Clean) {
        lobe.normal = moments.meanDirection();
        lobe.power = methodPower(method, moments, s, params);
        return lobe;
    }
    switch (method) {
    case Method::Lean:
    case Method::Clean: {
        lobe.slopeGaussian = true;
        lobe.slopeMean = glm::dvec2(moments.slope);
        lobe.normal = glm::vec3(normalOfSlope(lobe.slopeMean));
        const double invS = slopeInverseBasePower(s);
        if (method == Method::Lean) {
            lobe.slopeCov = leanSlopeCovariance(moments, s);
        } else {
            const double sigma2 = 0.5 * (double(moments.slopeCov[0]) + double(moments.slopeCov[1])) + invS;
            lobe.slopeCov = {sigma2, sigma2, 0.0};
        }
        lobe.power =
            powerFromVariance(0.5 * (lobe.slopeCov[0] + lobe.slopeCov[1]), VarianceConvention::InversePower);
        break;
    }
    default: // the isotropic methods, above
        break;
    }
    return lobe;
}

unsigned momentsNeeded(Method method) {
    return methodSpec(method).moments;
}

double slopeGaussianNdf(const glm::dvec3& h, const glm::dvec2& mean, const std::array<double, 3>& cov) {
    if (!(h.z > 0.0)) return 0.0;
    const double det = cov[0] * cov[1] - cov[2] * cov[2];
    // Σ = C + I/s with C positive semi-definite, so det >= 1/s² > 0; guard rounding anyway.
    if (!(det > 0.0)) return 0.0;
    const double dx = h.x / h.z - mean.x;
    const double dy = h.y / h.z - mean.y;
    const double e = (dx * dx * cov[1] + dy * dy * cov[0] - 2.0 * dx * dy * cov[2]) / det;
    const double hz2 = h.z * h.z;
    // exp(−e/2) underflows to 0 long before 1/h_z⁴ overflows a double.
    return std::exp(-0.5 * e) / (2.0 * kPi<double> * std::sqrt(det) * hz2 * hz2);
}

double methodNdf(const TexelLobe& lobe, const glm::dvec3& h) {
    if (lobe.slopeGaussian) return slopeGaussianNdf(h, lobe.slopeMean, lobe.slopeCov);
    return blinnPhongNdf(glm::dot(glm::dvec3(lobe.normal), h), lobe.power);
}

} // namespace burnish
